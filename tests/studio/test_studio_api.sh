#!/usr/bin/env bash
# tests/studio/test_studio_api.sh -- `panelize studio`'s JSON API with curl (docs/studio.md): a garment
# loaded by path and by upload, a run and its result (a panel per face, pieces, seams, verdict), a new
# run cancelling the running one, cancel, a one-sided stroke (no plane; the run cache reused when only S
# changes; mirror_sketch), the pattern files downloaded and written; and every bad
# request answered 4xx with a message, the server still up after them: bad JSON, wrong types and
# ranges, unknown options, too many or too long strokes, points far from the garment, paths outside
# the allowed folder, a wrong Content-Type, a foreign Host, a body over the limit, unknown garments.
# Then SIGTERM stops it with exit 0 and its temporary folder gone.
#
# SPDX-License-Identifier: GPL-3.0-or-later
set -u

source "$(dirname "$0")/../cli/lib.sh"
source "$(dirname "$0")/studio_lib.sh"

# ------------------------------------------------------------------ the command's own errors
expect_error 64 "--port" -- studio --port 70000
expect_error 64 "--listen" -- studio --listen nowhere --port 0
expect_error 66 "missing.obj" -- studio missing.obj --port 0

mkdir -p garments outside
run generate bodice -o garments/bodice.obj --faces 2000
expect_ok "generate bodice"
echo "not a mesh" >garments/notes.txt
cp garments/bodice.obj outside/secret.obj
ln -s ../outside/secret.obj garments/link.obj
TMPDIR=$WORK/tmp
mkdir -p "$TMPDIR"
export TMPDIR
start_studio --root garments
check "the address is on 127.0.0.1" grep -q '^panelize studio: http://127.0.0.1:[0-9]*/$' "$WORK/studio.out"

# ------------------------------------------------------------------ loading
api POST /api/garments '{"path": "bodice.obj"}'
check "load by path: $code $(head -c 200 "$WORK/body")" [ "$code" = 201 ]
id=$(json "d['id']")
check "the loaded garment's faces" [ "$(json "len(d['mesh']['faces']) == 3 * d['faces'] and d['faces'] > 1000")" = True ]
check "the mean edge is measured" [ "$(json "d['mean_edge_mm'] > 0")" = True ]

bad_load() { # bad_load CODE BODY WORDS: a load refused with CODE and a message holding WORDS
    api POST /api/garments "$2"
    check "load $2: $code, expected $1" [ "$code" = "$1" ]
    check "load $2: message '$(head -c 200 "$WORK/body")' lacks '$3'" grep -qF -- "$3" "$WORK/body"
}
bad_load 400 '{"path": "/etc/passwd"}' "outside the allowed folder"
bad_load 400 '{"path": "../outside/secret.obj"}' "outside the allowed folder"
bad_load 400 '{"path": "link.obj"}' "outside the allowed folder"
bad_load 400 '{"path": "missing.obj"}' "no such file"
bad_load 400 '{"path": "notes.txt"}' "not a mesh file"
bad_load 400 '{"path": 3}' "path"
bad_load 400 '{"path": "bodice.obj"' "not valid JSON"
bad_load 400 '{}' "path: expected a non-empty string"

# ------------------------------------------------------------------ bad runs
bad_run() { # bad_run BODY WORDS
    api POST "/api/garments/$id/run" "$1"
    check "run ${1:0:60}: $code, expected 400" [ "$code" = 400 ]
    check "run ${1:0:60}: message '$(head -c 200 "$WORK/body")' lacks '$2'" grep -qF -- "$2" "$WORK/body"
}
bad_run '{"max_strain": "high"}' "max_strain: expected a number"
bad_run '{"max_strain": 11}' "max_strain"
bad_run '{"max_corners": 2.5}' "max_corners"
bad_run '{"max_pieces": -1}' "max_pieces"
bad_run '{"darts": 1}' "darts"
bad_run '{"consolidate": "yes"}' "consolidate: expected true or false"
bad_run '{"mirror_sketch": 1}' "mirror_sketch: expected true or false"
bad_run '{"symmetry": "w"}' "symmetry"
bad_run '{"fabric": [1, 0, 1]}' "fabric"
bad_run '{"speed": 1}' "speed: not an option"
bad_run '{"max_strain": 0.1, "max_strain": 0.2}' "given twice"
bad_run '[1, 2]' "not a JSON object"
bad_run '{"strokes": [[[0, 0, 0]]]}' "strokes[0]: expected 2"
bad_run '{"strokes": [[[0, 0, 0], [0, 0, "x"]]]}' "finite numbers"
bad_run '{"strokes": [[[0, 0, 0], [0, 0, 1e999]]]}' "finite numbers"
bad_run '{"strokes": [[[0, 0, 0], [1e9, 0, 0]]]}' "far from the garment"
bad_run '{"grain_strokes": [[[0, 0, 0]]]}' "grain_strokes[0]: expected 2"
bad_run '{"grain_strokes": [[[0, 0, 0], [0, 0, "x"]]]}' "grain_strokes[0][1]: coordinates must be finite numbers"
bad_run '{"grain_strokes": [[[0, 0, 0], [1e9, 0, 0]]]}' "far from the garment"
bad_run '{"grain_strokes": 3}' "grain_strokes: expected an array"
many=$(python3 -c 'print({"strokes": [[[0, 0, 0], [1, 1, 1]]] * 201}.__repr__().replace("\x27", "\""))')
bad_run "$many" "at most 200"
long=$(python3 -c 'import json; print(json.dumps({"strokes": [[[0, 0, i * 1e-3] for i in range(5001)]]}))')
bad_run "$long" "expected 2 .. 5000 points"
api POST "/api/garments/$id/run" '{}' text/plain
check "a run posted as text/plain: $code, expected 415" [ "$code" = 415 ]
code=$(curl -s -o "$WORK/body" -w '%{http_code}' -H 'Host: example.com' "${URL}api/garments")
check "a foreign Host: $code, expected 403" [ "$code" = 403 ]
head -c 70000000 /dev/zero >big.bin
code=$(curl -s -o "$WORK/body" -w '%{http_code}' -X POST -H 'Content-Type: application/octet-stream' \
    --data-binary @big.bin "${URL}api/garments/upload?name=big.obj")
check "a 70 MB upload: $code, expected 413" [ "$code" = 413 ]
api GET /api/garments/999/status
check "an unknown garment: $code, expected 404" [ "$code" = 404 ]
api GET "/api/garments/$id/result"
check "no result before a run: $code, expected 404" [ "$code" = 404 ]
api GET /api/nothing
check "an unknown request: $code, expected 404" [ "$code" = 404 ]
api DELETE "/api/garments/$id"
check "DELETE: $code, expected 405" [ "$code" = 405 ]

# ------------------------------------------------------------------ a run, a newer run, cancel
api POST "/api/garments/$id/run" '{"max_strain": 0.05}'
check "run 1: $code $(head -c 200 "$WORK/body")" [ "$code" = 202 ]
api POST "/api/garments/$id/run" '{"max_strain": 0.08, "darts": false}'
check "run 2: $code" [ "$code" = 202 ]
check "run 2 is numbered 2" [ "$(json "d['run']")" = 2 ]
state=$(wait_run "$id" 2)
check "run 2 ends done, not $state ($(head -c 300 "$WORK/body"))" [ "$state" = done ]
check "the result is run 2's (run 1 was cancelled)" [ "$(json "d['result_run']")" = 2 ]
api GET "/api/garments/$id/result"
check "result: $code" [ "$code" = 200 ]
check "a panel per face" [ "$(json "len(d['face_panel']) * 3 == len(d['garment']['faces']) and \
    all(0 <= p < d['panel_count'] for p in d['face_panel'])")" = True ]
check "a piece per panel" [ "$(json "len(d['pieces']) == d['panel_count'] > 0")" = True ]
check "the pattern's triangles and strain" [ "$(json "len(d['pattern']['strain']) * 3 == len(d['pattern']['faces'])")" = True ]
check "seams with 3D points and both sides" [ "$(json "len(d['seams']) > 0 and all(len(s['points']) // 3 == \
    len(s['uv_a']) // 2 == len(s['uv_b']) // 2 for s in d['seams'])")" = True ]
check "the options used (S = 0.08)" [ "$(json "d['verdict']['max_strain']")" = 0.08 ]
check "no dart with darts off" [ "$(json "sum(s['kind'] == 'dart' for s in d['seams'])")" = 0 ]
pieces=$(json "d['panel_count']")
api GET "/api/garments/$id/report"
check "report: $code" [ "$code" = 200 ]
check "the report's panels are the result's" [ "$(json "d['summary']['panel_count']")" = "$pieces" ]
# The run defers the marker and the trade-off (most runs are looked at, not written); the report makes them.
check "the report has no marker" [ "$(json "d['marker']['efficiency'] > 0.3 and d['marker']['length_mm'] > 0")" = True ]
check "the report has no trade-off" [ "$(json "len(d['tradeoff_sequence']) > 0 and len(d['tradeoff']) > 0")" = True ]
check "the report names the garment" grep -q '"bodice' "$WORK/body"

# A run long enough to be cancelled on a loaded machine (S = 0.01: about 3 s quiet; the defaults' 0.5 s run
# could end before the cancel's request arrives).
api POST "/api/garments/$id/run" '{"max_strain": 0.01}'
run3=$(json "d['run']")
api POST "/api/garments/$id/cancel" '{}'
check "cancel: $code" [ "$code" = 200 ]
state=$(wait_run "$id" "$run3")
check "a cancelled run ends cancelled, not $state" [ "$state" = cancelled ]
check "the last result stays run 2's" [ "$(json "d['result_run']")" = 2 ]

# A stroke on one side of the symmetric bodice: laid out without the plane (docs/run.md, "Sketches and
# symmetry"); the same stroke with another S reuses the garment's plane and field (the run cache); with
# mirror_sketch the stroke's mirror image joins it and the sketch no longer refuses the plane.
api GET "/api/garments/$id"
side=$(python3 -c '
import json, sys
p = json.load(open(sys.argv[1]))["mesh"]["positions"]
vs = [p[i:i + 3] for i in range(0, len(p), 3)]
top = max(v[2] for v in vs)
points = []
for i in range(13):
    best = min((v for v in vs if v[1] > 0), key=lambda v: (v[0] - 60) ** 2 + (v[2] - top * (0.1 + 0.8 * i / 12)) ** 2)
    if best not in points:
        points.append(best)
print(json.dumps(points))' "$WORK/body")
one_sided_run() { # one_sided_run BODY: its report into $WORK/body
    api POST "/api/garments/$id/run" "$1"
    local run
    run=$(json "d['run']")
    state=$(wait_run "$id" "$run")
    check "run ${1:0:50}: ends done, not $state" [ "$state" = done ]
    api GET "/api/garments/$id/report"
}
one_sided_run "{\"strokes\": [$side], \"consolidate\": false}"
check "a one-sided stroke kept the plane or did not say so" \
    [ "$(json "d['segmentation']['symmetry']['sketch_not_symmetric'] and not d['segmentation']['symmetry']['used']")" = True ]
one_sided_run "{\"strokes\": [$side], \"consolidate\": false, \"max_strain\": 0.06}"
check "the same stroke with another S did not reuse the plane and field" [ "$(json "d['segmentation']['field_reused']")" = True ]
one_sided_run "{\"strokes\": [$side], \"consolidate\": false, \"mirror_sketch\": true}"
check "mirror_sketch: the stroke still counted as one-sided" \
    [ "$(json "d['segmentation']['mirror_sketch'] and not d['segmentation']['symmetry']['sketch_not_symmetric'] and not d['segmentation']['field_reused']")" = True ]

# ------------------------------------------------------------------ files
code=$(curl -s -o pattern.dxf -w '%{http_code}' "${URL}api/garments/$id/files/pattern.dxf")
check "pattern.dxf: $code" [ "$code" = 200 ]
check "pattern.dxf is a DXF" grep -q '^SECTION' pattern.dxf
code=$(curl -s -o garment.glb -w '%{http_code}' "${URL}api/garments/$id/files/garment.glb")
check "garment.glb: $code, glTF magic" [ "$code" = 200 ] && check "garment.glb is a GLB" [ "$(head -c 4 garment.glb)" = glTF ]
api GET "/api/garments/$id/files/..%2F..%2Fetc%2Fpasswd"
check "an unknown file name: $code, expected 404" [ "$code" = 404 ]
api POST "/api/garments/$id/write" '{"folder": "out/bodice"}'
check "write: $code $(head -c 200 "$WORK/body")" [ "$code" = 200 ]
check "write: the files are there" [ -s garments/out/bodice/pattern.svg ] && [ -s garments/out/bodice/report.json ]
api POST "/api/garments/$id/write" '{"folder": "../outside/x"}'
check "write outside: $code, expected 400" [ "$code" = 400 ]
check "write outside: nothing written" [ ! -e outside/x ]
api POST "/api/garments/$id/write" '{"folder": "/tmp/x"}'
check "write to /tmp: $code, expected 400" [ "$code" = 400 ]

# ------------------------------------------------------------------ upload
api POST "/api/garments/upload?name=mine.obj" "$(cat garments/bodice.obj)" application/octet-stream
check "upload: $code $(head -c 200 "$WORK/body")" [ "$code" = 201 ]
check "upload: named" [ "$(json "d['name']")" = mine.obj ]
api POST "/api/garments/upload?name=../x.obj" "v 0 0 0" application/octet-stream
check "upload with a path as name: $code, expected 400" [ "$code" = 400 ]
api POST "/api/garments/upload?name=x.exe" "v 0 0 0" application/octet-stream
check "upload of another file kind: $code, expected 400" [ "$code" = 400 ]
api POST "/api/garments/upload?name=junk.obj" "f 1 2 3" application/octet-stream
check "upload of a bad mesh: $code, expected 422 ($(head -c 200 "$WORK/body"))" [ "$code" = 422 ]
check "upload of a bad mesh: named in the message" grep -q 'junk.obj' "$WORK/body"

# ------------------------------------------------------------------ prepared once, at load
# The bodice in two unwelded halves (x < 0 and x > 0 with vertices of their own): the preparation welds it
# when it is loaded, so the page draws on the mesh the runs use, and the welded seam stays a seam.
python3 - garments/bodice.obj garments/halves.obj <<'PY'
import sys
v, f = [], []
for line in open(sys.argv[1]):
    if line.startswith("v "): v.append(line)
    elif line.startswith("f "): f.append([int(t.split("/")[0]) - 1 for t in line.split()[1:4]])
x = [float(line.split()[1]) for line in v]
copy = {}
with open(sys.argv[2], "w") as out:
    for face in f:
        if sum(x[i] for i in face) > 0:
            face[:] = [copy.setdefault(i, len(v) + len(copy)) for i in face]
    out.writelines(v + [v[i] for i in sorted(copy, key=copy.get)])
    out.writelines("f %d %d %d\n" % tuple(i + 1 for i in face) for face in f)
PY
api POST /api/garments '{"path": "halves.obj"}'
check "load the halves: $code" [ "$code" = 201 ]
halves=$(json "d['id']")
check "the halves are welded at load: $(json "d['vertices']") vertices" [ "$(json "d['vertices']")" = "$(grep -c '^v ' garments/bodice.obj)" ]
api POST "/api/garments/$halves/run" '{"symmetry": "off"}'
state=$(wait_run "$halves" 1)
check "the halves' run: $state" [ "$state" = done ]
api GET "/api/garments/$halves/result"
check "the welded seam (x = 0) is a seam of the layout" [ "$(json "any(sum(abs(s['points'][i]) < 1 for i in range(0, len(s['points']), 3)) >= 5 for s in d['seams'])")" = True ]

# ------------------------------------------------------------------ still up, then stopped
api GET /api/garments
check "the server is up after it all: $code" [ "$code" = 200 ]
check "three garments listed" [ "$(json "len(d['garments'])")" = 3 ]
check "the temporary folder exists while serving" [ -n "$(ls "$TMPDIR")" ]
stop_studio
check "SIGTERM: exit $studio_rc" [ "$studio_rc" = 0 ]
check "the temporary folder is removed" [ -z "$(ls "$TMPDIR")" ]

finish
