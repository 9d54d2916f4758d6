#!/usr/bin/env bash
# tests/cli/test_cli_run_garments.sh -- `panelize run` on every garment in
# ../shared/data/garments (skipped when the folder is missing): every panel a
# disk with at most 8 corners, every triangle's strain within +-5% (unless the
# layout merged slivers, and then only S is missed, and reported), no flip or
# boundary self-intersection, seams' sides within 0.5%, no sliver (a piece
# under 40 mm or 1 % of the area), every dart taking in 6 mm, every piece
# named once; and `--panels uv`
# on the DiffAvatar T-shirt goes through the whole run with its 4 true panels,
# each close to its true shape (tests/cli/true_pieces.py prints them). With
# --max-pieces at their true piece count, the three garments whose vt is their
# real pattern get at most that many pieces and (when ../shared/tools and numpy
# can run) seams within 3 % of the true ones, F1 >= 0.7; a line sketched from
# the T-shirt's hem to its neckline adds at most 2 pieces. At the defaults the shirt is consolidated to a
# front, a back and two sleeves, the skirt to a front and a back; the T-shirt keeps its exact mirror pieces.
# Prints one table line per garment (faces, panels, darts, worst strain, worst
# seam mismatch, seconds) for the record. Symmetry (docs/segment.md): the
# T-shirt with its plane forced (x) keeps it only within max(+2, +25 %) panels of its layout without it;
# where a run uses its plane (the wetsuit, the leggings, the dress), every
# mirror piece it made exact is exact within 0.1 mm, and the wetsuit (exactly
# symmetric) gets some.
#
# SPDX-License-Identifier: GPL-3.0-or-later
set -u

source "$(dirname "$0")/lib.sh"

DATA=${PZ_SHARED_DATA:-}
if [ -z "$DATA" ] || [ ! -f "$DATA/INVENTORY.md" ]; then
    echo "SKIPPED: no shared data (PZ_SHARED_DATA=$DATA)"
    exit 77
fi

for garment in "$DATA"/garments/*.obj "$DATA"/garments/*.ply; do
    name=$(basename "$garment")
    out=run-${name%.*}
    start=$(date +%s%N)
    units=()
    # The wetsuit is 4.3 file units tall: 4.3 m or 43 mm, neither a garment's size, so a guess refuses it.
    [ "$name" = parafashion-wetsuit.obj ] && units=(--units m)
    run run "$garment" -o "$out" "${units[@]}" --quiet
    seconds=$(( ($(date +%s%N) - start) / 1000000 ))e-3
    check "run $name: exit $rc ($(head -c 300 "$WORK/err"))" [ "$rc" -eq 0 ]
    [ "$rc" -eq 0 ] || continue
    python3 - "$out/report.json" "$name" "$seconds" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
s = d['summary']
print('%-28s faces %6d panels %3d darts %2d worst strain %.4f worst seam mismatch %.5f %6.2f s goals %s' % (
    sys.argv[2], d['input']['faces'], s['panel_count'], len(d['darts']), s['max_abs_strain'],
    s['max_seam_mismatch_rel'], float(sys.argv[3]), s['goals_met']))
PY
    # Every goal is met, but where the layout merged slivers into their neighbours: there only S may be
    # missed, and said (a sliver is never the answer to S: docs/segment.md, "Piece shapes").
    only_strain="all(re.fullmatch(r'strain [0-9.e-]+ > 0.05', p.get('goals', '')) for p in d['panels'] if not p['goals_met'])"
    report_checks "run $name" "$out" \
        "goals not met: $(grep -o '"goals_reasons": "[^"]*' "$out/report.json" | head -c 300)" \
        "d['summary']['goals_met'] is True or (d['segmentation']['merged_slivers'] > 0 and $only_strain)" \
        "not injective" "d['summary']['injective'] is True" \
        "a panel has more than 8 corners" "all(p['corners'] <= 8 for p in d['panels'])" \
        "a triangle's strain exceeds 0.05" \
        "d['summary']['max_abs_strain'] <= 0.05 + 1e-9 or (d['segmentation']['merged_slivers'] > 0 and $only_strain)" \
        "a seam's sides differ by more than 0.5%" "d['summary']['max_seam_mismatch_rel'] <= 0.005" \
        "a sliver: a piece under 40 mm or 1 % of the area not forced by the garment" \
        "all(p['shape_forced_by_input'] or (p['width_mm'] >= 40 and p['area_share'] >= 0.01) for p in d['panels'])" \
        "a dart taking in under 6 mm" "all(x['intake_mm'] >= 6 for x in d['darts'])" \
        "pieces without names or named alike" "len(set(p['name'] for p in d['panels'])) == len(d['panels'])" \
        "a mirror piece made exact is not (0.1 mm)" \
        "sum(1 for p in d['panels'] if 0 <= p['mirror_residual_mm'] < 0.1) >= d['segmentation']['symmetry']['exact_mirror_pieces']"
done
report_checks "run parafashion-wetsuit.obj mirrored" run-parafashion-wetsuit \
    "the plane not used" "d['segmentation']['symmetry']['used']" \
    "no mirror piece made exact" "d['segmentation']['symmetry']['exact_mirror_pieces'] >= 2"

# Forcing a plane never multiplies the pieces (issue 14: x forced on the T-shirt once gave 6 -> 74 pieces).
run run "$DATA/garments/diffavatar-tshirt.obj" -o tshirt-x --symmetry x --outputs json --quiet
expect_ok "run diffavatar-tshirt --symmetry x"
run run "$DATA/garments/diffavatar-tshirt.obj" -o tshirt-off --symmetry off --outputs json --quiet
expect_ok "run diffavatar-tshirt --symmetry off"
check "run diffavatar-tshirt --symmetry x: the plane multiplied the panels" python3 -c '
import json, sys
forced, off = (json.load(open(f + "/report.json")) for f in sys.argv[1:3])
sym = forced["segmentation"]["symmetry"]
n, n_off = forced["summary"]["panel_count"], off["summary"]["panel_count"]
print("T-shirt: --symmetry x %d panels (%d/%d with/without the plane in its layout), off %d" %
      (n, sym["pieces_with_plane"], sym["pieces_without_plane"], n_off))
# the mirrored layout is kept only within max(+2, +25 %) of the layout without it (docs/segment.md), and
# never twice the panels of a run without symmetry
ok = sym["pieces_with_plane"] <= max(sym["pieces_without_plane"] + 2, 1.25 * sym["pieces_without_plane"])
sys.exit(0 if ok and n < 2 * n_off else 1)' tshirt-x tshirt-off

# ------------------------------------------------------------------ the true piece budget
# Issue 14's goal: with --max-pieces at the true piece count, seams within 3 % of the diagonal of the true
# ones (tools/seamscore.py: F1 >= 0.7) and a p95 strain no worse than the true pattern's own (it is: the
# pieces meet S almost everywhere; docs/segment.md has the table).
SEAMSCORE=$DATA/../tools/seamscore.py
scorer=1
if [ ! -f "$SEAMSCORE" ] || ! /usr/bin/python3 -c 'import numpy, scipy' 2>/dev/null; then
    scorer=0
    skip_part "seam F1 of the budget runs (no $SEAMSCORE, or no numpy and scipy for /usr/bin/python3)"
fi
for entry in diffavatar-tshirt:4 diffavatar-shirt:5 parafashion-skirt:4; do
    name=${entry%%:*} pieces=${entry##*:}
    run run "$DATA/garments/$name.obj" --max-pieces "$pieces" -o "budget-$name" --quiet
    expect_ok "run $name --max-pieces $pieces"
    [ "$rc" -eq 0 ] || continue
    report_checks "run $name --max-pieces $pieces" "budget-$name" \
        "more than $pieces pieces" "d['summary']['panel_count'] <= $pieces" \
        "the budget is not reported as met" "d['segmentation']['max_pieces']['met'] is True" \
        "not injective" "d['summary']['injective'] is True" \
        "a seam's sides differ by more than 0.5%" "d['summary']['max_seam_mismatch_rel'] <= 0.005"
    if [ "$scorer" -eq 1 ]; then
        score=$(/usr/bin/python3 "$SEAMSCORE" "$DATA/garments/$name.obj" "budget-$name")
        echo "$name --max-pieces $pieces: $score"
        check "run $name --max-pieces $pieces: seam F1 under 0.7: $score" \
            python3 -c 'import json, sys; sys.exit(0 if json.loads(sys.argv[1])["f1"] >= 0.7 else 1)' "$score"
    fi
done

# ------------------------------------------------------------------ consolidation at the defaults
# The shirt at the defaults: consolidated (docs/run.md, "Consolidation") to the true structure, a front, a
# back and two sleeves meeting every goal (its first layout: 7 pieces with darts); the skirt to a front and a
# back. The T-shirt's four pieces would lose its exact mirror pieces: it keeps its first layout, every mirror
# piece exact.
for entry in diffavatar-shirt:front,back,sleeve_left,sleeve_right parafashion-skirt:front,back; do
    name=${entry%%:*} names=${entry##*:}
    [ -s "run-$name/report.json" ] || continue
    report_checks "run $name (defaults)" "run-$name" \
        "not consolidated to $names: $(python3 -c 'import json,sys; r=json.load(open(sys.argv[1])); print([p["name"] for p in r["panels"]], r["segmentation"].get("consolidated_from"))' "run-$name/report.json")" \
        "sorted(p['name'] for p in d['panels']) == sorted('$names'.split(',')) and d['segmentation'].get('consolidated_from', 0) > d['summary']['panel_count'] and d['summary']['goals_met'] is True"
done
[ -s run-diffavatar-tshirt/report.json ] && report_checks "run diffavatar-tshirt (defaults)" run-diffavatar-tshirt \
    "consolidated into pieces that are not exact mirror images, or its mirror pieces not exact" \
    "'consolidated_from' not in d['segmentation'] and d['segmentation']['symmetry']['mirror_pieces'] > 0 and d['segmentation']['symmetry']['exact_mirror_pieces'] == d['segmentation']['symmetry']['mirror_pieces']"

# ------------------------------------------------------------------ a sketched seam
# A designer's line from the T-shirt's hem to its neckline, down the front a little off the middle (points
# on the surface every 3 % of the height, stopping 3 cm short of the neckline as a hand would): a seam, at
# most 2 pieces more than without it (the farthest-first insertion alone went from 7 to 12).
python3 - "$DATA/garments/diffavatar-tshirt.obj" <<'PY'
import json, sys
vs = [tuple(map(float, l.split()[1:4])) for l in open(sys.argv[1]) if l.startswith('v ')]
lo = [min(v[k] for v in vs) for k in range(3)]
hi = [max(v[k] for v in vs) for k in range(3)]
height, mid = hi[1] - lo[1], [(lo[k] + hi[k]) / 2 for k in range(3)]
x = mid[0] + 0.065 * (hi[0] - lo[0])
front = [v for v in vs if v[2] > mid[2] and abs(v[0] - x) < 0.03 * (hi[0] - lo[0])]
top = max(v[1] for v in front) - 0.05 * height
points, y = [], lo[1] + 0.02 * height
while y < top:
    points.append(list(min(front, key=lambda v: (v[0] - x) ** 2 + (v[1] - y) ** 2)))
    y += 0.03 * height
json.dump({'curves': [points]}, open('tshirt-sketch.json', 'w'))
PY
run run "$DATA/garments/diffavatar-tshirt.obj" --sketch tshirt-sketch.json -o tshirt-sketched --quiet
expect_ok "run diffavatar-tshirt --sketch"
if [ "$rc" -eq 0 ]; then
    with=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["summary"]["panel_count"])' tshirt-sketched/report.json)
    without=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["summary"]["panel_count"])' run-diffavatar-tshirt/report.json)
    echo "diffavatar-tshirt: $without pieces, $with with the sketched seam"
    check "run diffavatar-tshirt --sketch: $with pieces, more than 2 above the $without without" [ "$with" -le $((without + 2)) ]
fi

run run "$DATA/garments/diffavatar-tshirt.obj" --panels uv -o tshirt-uv --quiet
expect_ok "run --panels uv diffavatar-tshirt"
report_checks "run --panels uv diffavatar-tshirt" tshirt-uv \
    "not the 4 true panels" "d['summary']['panel_count'] == 4" \
    "segmentation ran" "d['segmentation']['panels'] == 'given'" \
    "not injective" "d['summary']['injective'] is True" \
    "a seam's sides differ by more than 0.5%" "d['summary']['max_seam_mismatch_rel'] <= 0.005"
# The true pieces (the input's vt) against ours after the best rigid motion: libigl's ARAP parameterization
# of these panels is off by 1.4 % (issue 3), so do at least as well through the whole run.
python3 "$(dirname "$0")/true_pieces.py" "$DATA/garments/diffavatar-tshirt.obj" tshirt-uv/garment.obj 1.4 >pieces.txt
pieces_rc=$?
cat pieces.txt
check "run --panels uv diffavatar-tshirt: pieces differ from the true pattern by more than 1.4 %" [ "$pieces_rc" -eq 0 ]
# Each piece too (measured 4.10 %, 4.18 % for the sleeves, 0.43 %, 0.36 % for the body: docs/run.md).
check "run --panels uv diffavatar-tshirt: a piece differs from its true shape by more than 5 %: $(tr '\n' ' ' <pieces.txt)" \
    python3 -c 'import re, sys
pieces = [float(m.group(1)) for m in re.finditer(r"^panel_\d+ +\d+ faces +([0-9.]+) %", open("pieces.txt").read(), re.M)]
sys.exit(0 if len(pieces) == 4 and max(pieces) <= 5.0 else 1)'

finish
