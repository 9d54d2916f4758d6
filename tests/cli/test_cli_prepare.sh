#!/usr/bin/env bash
# tests/cli/test_cli_prepare.sh -- `panelize prepare` end to end: a generated
# bodice is remeshed to about the faces asked for (or the --edge given),
# stays within the Hausdorff bound, comes out valid (`panelize check`);
# --json reports every step with its counts; the welded seams go to
# OUT-stem.seams.json (only when there are seams; never over a user's
# seams.json or an input), a sketch file that `panelize field --sketch`
# accepts; poses come out with the same connectivity; a NaN vertex's faces are
# dropped; a body scanned with (apart from) the garment is kept beside it
# as a second component, with --keep largest or all;
# --repair only welds and repairs; --keep all keeps a small part that
# --keep largest drops; `panelize run --prepare auto` welds an
# unwelded 4-panel export (report.json's "prepare" object says so) and leaves
# a clean mesh alone; bad options and bad input (an empty file,
# nothing left after repair, an edge longer than the garment) fail with their
# exit code, one line naming the culprit, and nothing written.
#
# SPDX-License-Identifier: GPL-3.0-or-later
set -u

source "$(dirname "$0")/lib.sh"

# split_panels N IN OUT: an unwelded export of IN (as CLO3D writes one): its
# faces cut into N sectors around the garment's height (its longest side) by
# the angle of their centroids, every vertex copied once per sector it is in.
split_panels() {
    python3 - "$@" <<'PY'
import math, sys
sectors, v, f = int(sys.argv[1]), [], []
for line in open(sys.argv[2]):
    t = line.split()
    if t and t[0] == 'v': v.append([float(x) for x in t[1:4]])
    elif t and t[0] == 'f': f.append([int(c.split('/')[0]) - 1 for c in t[1:]])
lo = [min(p[k] for p in v) for k in range(3)]
hi = [max(p[k] for p in v) for k in range(3)]
up = max(range(3), key=lambda k: hi[k] - lo[k])
h0, h1 = [k for k in range(3) if k != up]
centre = [(lo[k] + hi[k]) / 2 for k in range(3)]
out_v, copy, faces = [], {}, []
for face in f:
    x = sum(v[i][h0] for i in face) / 3 - centre[h0]
    y = sum(v[i][h1] for i in face) / 3 - centre[h1]
    sector = int(math.floor((math.atan2(y, x) + math.pi) / (2 * math.pi / sectors))) % sectors
    ids = []
    for i in face:
        if (i, sector) not in copy:
            copy[(i, sector)] = len(out_v)
            out_v.append(v[i])
        ids.append(copy[(i, sector)] + 1)
    faces.append(ids)
with open(sys.argv[3], 'w') as out:
    for p in out_v: out.write('v %r %r %r\n' % tuple(p))
    for ids in faces: out.write('f %d %d %d\n' % tuple(ids))
PY
}

run generate bodice -o bodice.obj --faces 8000 --poses 1 --quiet
expect_ok "generate"

# ------------------------------------------------------------------ a plain run with --json
run prepare bodice.obj -o dest/prepared.obj --faces 5000 --json
check "prepare into a missing directory fails" [ "$rc" -eq 73 ]
mkdir dest
run prepare bodice.obj -o dest/prepared.obj --faces 5000 --json
expect_ok "prepare --faces 5000"
json_checks "prepare --json" \
    "every step is reported" 'sorted(d["steps"]) == sorted(["weld","repair","fragments","decimate","remesh","poses","hausdorff"])' \
    "each step has ran, detail, ms" 'all(set(s) == {"ran","detail","ms"} for s in d["steps"].values())' \
    "remeshing ran" 'd["steps"]["remesh"]["ran"] is True' \
    "about 5000 faces" 'abs(d["counts"]["output_faces"] - 5000) < 500' \
    "within the Hausdorff bound" 'd["within_bound"] is True and 0 <= d["hausdorff_mm"] < d["hausdorff_bound_mm"]' \
    "the bound is 0.5% of the diagonal" 'abs(d["hausdorff_bound_mm"] - 0.005 * d["bbox_diagonal_mm"]) < 1e-3' \
    "well shaped" 'd["min_angle_over_20_fraction"] > 0.99' \
    "input counts" 'd["counts"]["input_faces"] > 7500'
check "the steps are on stderr" grep -q 'remesh' "$WORK/err"
check "prepared.obj written" [ -s dest/prepared.obj ]
check "no seams, no seams file" [ ! -e dest/prepared.seams.json ]
check "no seams.json either" [ ! -e dest/seams.json ]
json_checks "prepare --json, no seams" "seams_file is null" 'd["seams_file"] is None'
run check dest/prepared.obj
expect_ok "the prepared mesh passes check"

# ------------------------------------------------------------------ --edge, poses
run prepare bodice.obj --pose bodice.pose1.obj -o posed.obj --edge 15 --json --quiet
expect_ok "prepare --edge 15 with a pose"
json_checks "prepare --edge" \
    "target edge 15" 'd["target_edge_mm"] == 15' \
    "one pose" 'd["counts"]["poses"] == 1 and d["pose_files"] == ["posed.pose1.obj"]' \
    "pose within the bound" 'd["pose_hausdorff_mm"] < d["hausdorff_bound_mm"]'
check "--quiet leaves stderr empty" [ ! -s "$WORK/err" ]
check "the pose has the rest pose's faces" python3 - posed.obj posed.pose1.obj <<'PY'
import sys
def read(path):
    v, f = 0, []
    for line in open(path):
        if line.startswith('v '): v += 1
        elif line.startswith('f '): f.append([c.split('/')[0] for c in line.split()[1:]])
    return v, f
a, b = read(sys.argv[1]), read(sys.argv[2])
assert a == b and a[0] > 0
PY

# ------------------------------------------------------------------ unwelded panels: seams come back
split_panels 2 bodice.obj panels.obj
echo '{"curves": []}' >seams.json # the user's own sketch file: never replaced
run prepare panels.obj -o welded.obj --json --quiet
expect_ok "prepare the unwelded panels"
json_checks "welding" \
    "vertices welded" 'd["counts"]["welded_vertices"] > 0' \
    "seam edges found" 'd["counts"]["seam_edges"] > 0' \
    "two seam curves" 'd["counts"]["seam_curves"] == 2' \
    "one component" 'd["counts"]["components"] == 1' \
    "seams file named after the output" 'd["seams_file"] == "welded.seams.json"'
check "welded.seams.json has two curves of points" json_true \
    'len(d["curves"]) == 2 and all(len(c) > 5 and all(len(p) == 3 for p in c) for c in d["curves"])' welded.seams.json
check "the user's seams.json is untouched" grep -qx '{"curves": \[\]}' seams.json
run field welded.obj --sketch welded.seams.json -o field --quiet
expect_ok "field --sketch welded.seams.json"
ln -s panels.obj clash.seams.json # the seams file would replace the input: refused, nothing written
expect_error 64 "clash.seams.json" --absent clash.obj -- prepare panels.obj -o clash.obj
check "the input is intact" cmp -s panels.obj clash.seams.json

# ------------------------------------------------------------------ --repair: no remeshing
run prepare panels.obj -o repaired.ply --repair --json --quiet
expect_ok "prepare --repair"
json_checks "--repair" \
    "no remeshing" 'd["steps"]["remesh"]["ran"] is False and d["steps"]["decimate"]["ran"] is False' \
    "faces kept" 'd["counts"]["output_faces"] == d["counts"]["input_faces"]'

# ------------------------------------------------------------------ --keep all: a separate part stays
python3 - panels.obj parts.obj <<'PY'
import sys
lines = open(sys.argv[1]).read().splitlines()
n = sum(1 for l in lines if l.startswith('v '))
with open(sys.argv[2], 'w') as out:
    out.write('\n'.join(lines) + '\n')
    out.write('v 0 0 2000\nv 30 0 2000\nv 0 30 2000\nf %d %d %d\n' % (n + 1, n + 2, n + 3))  # a 450 mm^2 part
PY
run prepare parts.obj -o parts-all.obj --repair --keep all --json --quiet
expect_ok "prepare --keep all"
json_checks "--keep all" \
    "two components, none dropped" 'd["counts"]["components"] == 2 and d["counts"]["dropped_components"] == 0' \
    "the step says --keep all" '"--keep all" in d["steps"]["fragments"]["detail"]'
run prepare parts.obj -o parts-largest.obj --repair --json --quiet
expect_ok "prepare --keep largest (default)"
json_checks "--keep largest" \
    "the small part dropped" 'd["counts"]["dropped_components"] == 1 and d["counts"]["dropped_component_faces"] == 1'

# ------------------------------------------------------------------ run --prepare auto
# The 8000-face bodice split into 4 unwelded panels (fine for auto: at most
# 10000 faces, well shaped): `run` welds it back, says so in
# report.json, and offers the 4 welded seams to the segmentation.
split_panels 4 bodice.obj panels4.obj
run run panels4.obj -o run-panels --quiet
expect_ok "run on the unwelded 4-panel export"
check "run wrote report.json" [ -s run-panels/report.json ]
report_checks "run --prepare auto, unwelded" run-panels \
    "mode auto" 'd["prepare"]["mode"] == "auto"' \
    "the weld step ran" '[s for s in d["prepare"]["steps"] if s["name"] == "weld"][0]["ran"] is True' \
    "welded seams offered" 'd["prepare"]["welded_seams"] >= 4' \
    "not remeshed (small, well shaped)" '[s for s in d["prepare"]["steps"] if s["name"] == "remesh"][0]["ran"] is False' \
    "the remesh step says why not" '"not needed" in [s for s in d["prepare"]["steps"] if s["name"] == "remesh"][0]["detail"]' \
    "faces kept" 'd["prepare"]["output_faces"] == d["prepare"]["input_faces"] == 8000' \
    "one surface came out: panels were cut" 'd["summary"]["panel_count"] >= 2 and d["summary"]["injective"]'

run run bodice.obj -o run-clean --quiet
expect_ok "run on the clean bodice"
report_checks "run --prepare auto, clean" run-clean \
    "mode auto" 'd["prepare"]["mode"] == "auto"' \
    "nothing changed" 'd["prepare"]["output_faces"] == d["prepare"]["input_faces"]' \
    "no step ran" 'not any(s["ran"] for s in d["prepare"]["steps"])' \
    "no welded seams" 'd["prepare"]["welded_seams"] == 0'

run run panels4.obj -o run-off --prepare off --quiet
expect_ok "run --prepare off"
report_checks "run --prepare off" run-off \
    "mode off, no steps" 'd["prepare"]["mode"] == "off" and "steps" not in d["prepare"]'

# ------------------------------------------------------------------ a NaN vertex (the OBJ reader passes "nan" on)
python3 - bodice.obj nan.obj <<'PY'
import sys
lines = open(sys.argv[1]).read().splitlines()
n = sum(1 for l in lines if l.startswith('v '))
with open(sys.argv[2], 'w') as out:
    out.write('\n'.join(lines) + '\n')
    out.write('v nan 0 0\nf 1 2 %d\nf 2 3 %d\n' % (n + 1, n + 1))
PY
run prepare nan.obj -o nan-out.obj --repair --json --quiet
expect_ok "prepare with a NaN vertex"
json_checks "NaN vertex" \
    "its two faces dropped" 'd["counts"]["nonfinite_faces"] == 2' \
    "the rest kept" 'd["counts"]["output_faces"] == d["counts"]["input_faces"] - 2'
run check nan-out.obj
expect_ok "the repaired mesh passes check"

# ------------------------------------------------------------------ a body scanned with the garment
# A closed "body" (a tall box inside the bodice, larger in area than it)
# apart from the garment: neither is a fragment (under 1% of the area), so
# both stay, as two components, with --keep largest (the default) or all;
# nothing tells a body from a garment (docs/prepare.md).
python3 - bodice.obj body.obj <<'PY'
import sys
lines = open(sys.argv[1]).read().splitlines()
v = [[float(x) for x in l.split()[1:4]] for l in lines if l.startswith('v ')]
n = len(v)
lo = [min(p[k] for p in v) for k in range(3)]
hi = [max(p[k] for p in v) for k in range(3)]
c = [(lo[k] + hi[k]) / 2 for k in range(3)]
up = max(range(3), key=lambda k: hi[k] - lo[k])
half = [(hi[k] - lo[k]) * 0.3 for k in range(3)]
half[up] = (hi[up] - lo[up]) * 1.5  # a tall box: the body, inside the garment, larger in area
corners = [[c[k] + (half[k] if (i >> k) & 1 else -half[k]) for k in range(3)] for i in range(8)]
quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
with open(sys.argv[2], 'w') as out:
    out.write('\n'.join(lines) + '\n')
    for p in corners: out.write('v %r %r %r\n' % tuple(p))
    for a, b, cc, d in quads:
        out.write('f %d %d %d\nf %d %d %d\n' % (n + 1 + a, n + 1 + b, n + 1 + cc, n + 1 + a, n + 1 + cc, n + 1 + d))
PY
run prepare body.obj -o body-largest.obj --repair --json --quiet
expect_ok "prepare a garment with its body (--keep largest)"
json_checks "body, --keep largest" \
    "two components, none dropped" 'd["counts"]["components"] == 2 and d["counts"]["dropped_components"] == 0' \
    "both kept" 'd["counts"]["output_faces"] == d["counts"]["input_faces"] == 8012'
run prepare body.obj -o body-all.obj --keep all --json --quiet
expect_ok "prepare a garment with its body (--keep all, remeshed)"
json_checks "body, --keep all" \
    "both kept" 'd["counts"]["components"] == 2 and d["counts"]["dropped_components"] == 0' \
    "remeshed, valid" 'd["steps"]["remesh"]["ran"] is True and d["within_bound"] is True'
run check body-all.obj
expect_ok "body and garment, --keep all: passes check"

# ------------------------------------------------------------------ errors
: >empty.obj
expect_error 65 empty.obj --absent e.obj --absent e.seams.json -- prepare empty.obj -o e.obj
printf 'v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3\nf 2 3 4\n' >line.obj
expect_error 65 "nothing left" --absent l.obj --absent l.seams.json -- prepare line.obj -o l.obj
expect_error 64 "too long" --absent big.obj --absent big.seams.json -- prepare panels.obj -o big.obj --edge 5000
expect_error 64 "--edge" --absent x.obj -- prepare bodice.obj -o x.obj --edge -3
expect_error 64 "--weld" --absent x.obj -- prepare bodice.obj -o x.obj --weld abc
expect_error 64 "--keep" --absent x.obj -- prepare bodice.obj -o x.obj --keep some
expect_error 64 "not both" --absent x.obj -- prepare bodice.obj -o x.obj --edge 5 --faces 100
expect_error 64 "-o" -- prepare bodice.obj
expect_error 64 "x.txt" -- prepare bodice.obj -o x.txt
expect_error 66 "missing.obj" --absent x.obj -- prepare missing.obj -o x.obj

finish
