#!/usr/bin/env bash
# tests/cli/test_cli_info.sh -- `panelize info` on generated meshes whose
# answers are known: topology (boundary loops, genus, Euler characteristic,
# components) through every writer and reader (.obj .ply .glb), the units
# guess and its override, and poses (GLB morph targets, OBJ pose files).
#
# SPDX-License-Identifier: GPL-3.0-or-later
set -u

source "$(dirname "$0")/lib.sh"

keys='["file","vertices","faces","edges","components","boundary_loops","boundary_loop_lengths_mm","genus",
"euler_characteristic","manifold","problems","poses","units","units_guessed","bbox_mm","area_mm2","uvs",
"labels","timings_ms"]'

# ------------------------------------------------------------------ topology through every format
# shape, generate flags, expected boundary loops
cases=(
    "bodice|2"
    "cylinder|2"
    "hemisphere|1"
    "cone --open|1"
)
for case in "${cases[@]}"; do
    spec=${case%|*}
    loops=${case#*|}
    name=${spec%% *}
    for ext in obj ply glb; do
        file=$name.$ext
        # shellcheck disable=SC2086 # spec holds the shape and its flags
        run generate $spec -o "$file" --faces 2000 --json --quiet
        expect_ok "generate $spec -o $file"
        cp "$WORK/out" generated.json
        run info "$file" --json --quiet
        expect_ok "info $file"
        what="info $file"
        json_checks "$what" \
            "missing keys" "all(k in d for k in $(echo $keys))" \
            "file" "d['file'] == '$file'" \
            "counts differ from what generate wrote" \
            "all(d[k] == json.load(open('generated.json'))[k] for k in ('vertices', 'faces'))" \
            "boundary_loops should be $loops" "d['boundary_loops'] == $loops" \
            "one length per loop, all positive" \
            "len(d['boundary_loop_lengths_mm']) == $loops and all(x > 10 for x in d['boundary_loop_lengths_mm'])" \
            "genus 0, manifold, one component, no problems" \
            "d['genus'] == 0 and d['manifold'] is True and d['components'] == 1 and d['problems'] == []" \
            "Euler characteristic V-E+F should be 2 - loops" \
            "d['euler_characteristic'] == 2 - $loops == d['vertices'] - d['edges'] + d['faces']" \
            "units should be guessed mm" "d['units'] == 'mm' and d['units_guessed'] is True" \
            "bbox of a garment-sized shape in mm, size = max - min" \
            "150 < max(d['bbox_mm']['size']) < 2500 and all(abs(d['bbox_mm']['max'][k] - d['bbox_mm']['min'][k] - d['bbox_mm']['size'][k]) < 1e-3 for k in range(3))" \
            "area should be positive and below the bbox surface" \
            "0 < d['area_mm2'] < 2 * sum(d['bbox_mm']['size'][i] * d['bbox_mm']['size'][(i + 1) % 3] for i in range(3))" \
            "poses should be 0" "d['poses'] == 0" \
            "timings" "all(d['timings_ms'][k] >= 0 for k in ('read', 'validate', 'topology', 'total'))"
        check "$what --quiet: stderr should be empty" [ ! -s "$WORK/err" ]
    done
    # The same shape must read back alike whatever the format.
    run info "$name.obj" --json --quiet && cp "$WORK/out" a.json
    run info "$name.glb" --json --quiet && cp "$WORK/out" b.json
    check "$name: obj and glb disagree on area or loop lengths" python3 -c '
import json
a, b = json.load(open("a.json")), json.load(open("b.json"))
close = lambda x, y: abs(x - y) <= 1e-4 * max(1.0, abs(x))
assert close(a["area_mm2"], b["area_mm2"])
assert all(close(x, y) for x, y in zip(sorted(a["boundary_loop_lengths_mm"]), sorted(b["boundary_loop_lengths_mm"])))
'
done

# ------------------------------------------------------------------ text output
run info bodice.obj
expect_ok "info bodice.obj (text)"
check "text output should say manifold yes" grep -qE '^manifold: +yes' "$WORK/out"
check "text output should list two boundary loops" grep -qE '^boundary loops: +2' "$WORK/out"
check "text output should give the units" grep -qE '^units: +mm \(guessed\)' "$WORK/out"
check "text output should give the area" grep -qE '^area: .* mm\^2 \(.* m\^2\)' "$WORK/out"

# ------------------------------------------------------------------ units
run generate cylinder -o mm.obj --faces 1000 --quiet
awk '$1 == "v" { printf "v %.9g %.9g %.9g\n", $2 / 1000, $3 / 1000, $4 / 1000; next } { print }' mm.obj >metres.obj
run info mm.obj --json --quiet && cp "$WORK/out" mm.json
run info metres.obj --json --quiet
expect_ok "info metres.obj"
check "metres.obj should be guessed as m" json_true "d['units'] == 'm' and d['units_guessed'] is True"
check "metres.obj should have the same bbox in mm as mm.obj" python3 -c '
import json, sys
a, b = json.load(open("mm.json")), json.load(open(sys.argv[1]))
assert all(abs(x - y) < 1e-3 for key in ("min", "max", "size") for x, y in zip(a["bbox_mm"][key], b["bbox_mm"][key]))
assert abs(a["area_mm2"] - b["area_mm2"]) < 1e-6 * a["area_mm2"]
' "$WORK/out"
run info metres.obj --units cm --json --quiet
expect_ok "info metres.obj --units cm"
check "--units cm should override the guess" json_true "d['units'] == 'cm' and d['units_guessed'] is False"
check "--units cm should scale by 10 instead of 1000" \
    json_true "abs(max(d['bbox_mm']['size']) * 100 - max(json.load(open('mm.json'))['bbox_mm']['size'])) < 1e-2"
run info mm.obj --units=mm --json --quiet
check "--units=mm form: not given mm" json_true "d['units'] == 'mm' and d['units_guessed'] is False"
check "a 400 mm cylinder in mm is a plausible garment size" json_true "d['units_plausible'] is True"
# 40 units tall: 40 mm, 400 mm or 40 m. The guess (cm: 400 mm) fits; at 1/10 (4 units) nothing fits.
awk '$1 == "v" { printf "v %.9g %.9g %.9g\n", $2 / 100, $3 / 100, $4 / 100; next } { print }' mm.obj >tiny.obj
run info tiny.obj --json
expect_ok "info tiny.obj"
check "4 units tall fits no unit: units_plausible false" json_true "d['units_plausible'] is False"
check "an implausible guess warns on stderr, naming the file" grep -q "tiny.obj: warning: units guessed" "$WORK/err"
run info tiny.obj --units m --json
check "--units silences the units warning" [ ! -s "$WORK/err" ]

# ------------------------------------------------------------------ poses
run generate bodice --poses 2 -o posed.glb --faces 1000 --quiet
expect_ok "generate bodice --poses 2 -o posed.glb"
check "a .glb should not get pose files" [ ! -e posed.pose1.glb ]
run info posed.glb --json --quiet
check "posed.glb: poses should be 2" json_true "d['poses'] == 2 and d['manifold'] is True"

run generate bodice --poses 2 -o posed.obj --faces 1000 --quiet
expect_ok "generate bodice --poses 2 -o posed.obj"
check "posed.obj: pose files should exist" test -s posed.pose1.obj -a -s posed.pose2.obj
check "posed.obj: no third pose file" [ ! -e posed.pose3.obj ]
check "pose files should differ from the rest pose" differ posed.obj posed.pose1.obj
run info posed.obj --json --quiet
check "posed.obj alone: poses should be 0" json_true "d['poses'] == 0"
run info posed.obj --pose posed.pose1.obj --pose=posed.pose2.obj --json --quiet
expect_ok "info posed.obj with two --pose files"
check "posed.obj with its pose files: poses should be 2" json_true "d['poses'] == 2 and d['manifold'] is True"
run info --pose posed.pose1.obj --json posed.obj --quiet
check "options before the positional argument: poses should be 1" json_true "d['poses'] == 1 and d['file'] == 'posed.obj'"

run generate cylinder --poses 1 -o posed.ply --faces 1000 --quiet
expect_ok "generate cylinder --poses 1 -o posed.ply"
run info posed.ply --pose posed.pose1.ply --json --quiet
check "posed.ply with its pose file: poses should be 1" json_true "d['poses'] == 1"

# ------------------------------------------------------------------ real garments (read in place)
# Boundary loop counts from shared/data/INVENTORY.md: one component, manifold, genus 0.
if [ -n "${PZ_SHARED_DATA:-}" ] && [ -d "$PZ_SHARED_DATA/garments" ]; then
    for real in garments/parafashion-skirt.obj:2 garments/diffavatar-tshirt.obj:4 \
        garments/parafashion-leggings.ply:3 garments/shirtfront-panel.obj:1 surfaces/camelhead.off:1; do
        file=$PZ_SHARED_DATA/${real%:*}
        run info "$file" --json --quiet
        expect_ok "info $file"
        json_checks "info $file" \
            "should be one manifold component of genus 0 with ${real#*:} boundary loops" \
            "d['manifold'] is True and d['components'] == 1 and d['genus'] == 0 and d['boundary_loops'] == ${real#*:}"
    done
else
    skip_part "the real garments (PZ_SHARED_DATA is not set or has no garments/)"
fi

finish
