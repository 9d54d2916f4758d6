#!/usr/bin/env bash
# tests/cli/test_cli_field.sh -- `panelize field`: the three outputs exist,
# report.json has its keys and sane figures, field.obj parses (two `l`
# segments per face, one `p` per singularity), field.glb passes the Khronos
# glTF validator (when node and .tools/node_modules/gltf-validator exist),
# a sketch and extra poses are taken, and failures (bad sketch -> 65, missing
# sketch -> 66, bad --scales/--smoothness or no -o -> 64) write nothing.
#
# SPDX-License-Identifier: GPL-3.0-or-later
set -u

source "$(dirname "$0")/lib.sh"

run generate bodice -o bodice.obj --faces 3000 --poses 1 --quiet
expect_ok "generate bodice"

# A diagonal across the front (-y), points near the surface: the field snaps them.
cat >sketch.json <<'EOF'
{"curves": [[[-59.2, -105.4, 188.5], [0, -101.7, 308.3], [69.3, -124.6, 410.3]]]}
EOF

run field bodice.obj --pose bodice.pose1.obj --sketch sketch.json -o result --json --quiet
expect_ok "field bodice.obj"
for file in field.obj field.glb report.json; do
    check "result/$file missing" [ -s "result/$file" ]
done
check "--quiet: stderr should be empty" [ ! -s "$WORK/err" ]
check "stdout is the report" cmp -s "$WORK/out" result/report.json
json_checks "report" \
    "keys" "all(k in d for k in ('timings_ms', 'singularities', 'curvature_alignment_deg', 'boundary_alignment_deg', 'sketch_alignment_deg', 'faces', 'poses'))" \
    "timings" "all(d['timings_ms'][k] >= 0 for k in ('read', 'curvature', 'solve', 'singularities', 'write', 'total'))" \
    "singularities are {vertex, index} with index +-0.25k" \
    "all(set(s) == {'vertex', 'index'} and s['index'] != 0 and abs(s['index'] * 4 - round(s['index'] * 4)) < 1e-9 for s in d['singularities'])" \
    "singularity_count" "d['singularity_count'] == len(d['singularities'])" \
    "boundary alignment below 2 degrees" "0 <= d['boundary_alignment_deg'] < 2" \
    "sketch alignment below 2 degrees" "0 <= d['sketch_alignment_deg'] < 2 and d['sketch_faces'] > 5" \
    "curvature alignment is an angle" "0 <= d['curvature_alignment_deg'] <= 45" \
    "one extra pose" "d['poses'] == 1"

faces=$(python3 -c 'import json; print(json.load(open("result/report.json"))["faces"])')
singular=$(python3 -c 'import json; print(json.load(open("result/report.json"))["singularity_count"])')
python3 - result/field.obj "$faces" "$singular" <<'PY' >obj.log 2>&1
import sys
path, faces, singular = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
v = l = p = 0
for line in open(path):
    w = line.split()
    if not w or w[0].startswith('#') or w[0] == 'g':
        continue
    if w[0] == 'v':
        assert len(w) == 4 and all(abs(float(x)) < 1e5 for x in w[1:]), line
        v += 1
    elif w[0] == 'l':
        assert len(w) == 3 and all(1 <= int(x) <= v for x in w[1:]), line
        l += 1
    elif w[0] == 'p':
        assert len(w) == 2 and 1 <= int(w[1]) <= v, line
        p += 1
    else:
        raise SystemExit('unexpected line: ' + line)
assert l == 2 * faces, (l, faces)
assert p == singular, (p, singular)
PY
check "field.obj does not parse: $(tail -2 obj.log)" [ $? -eq 0 ]

# Plain text summary without --json; the default output directory is created.
run field bodice.obj -o new/dir --quiet
check "a missing parent: exit 73, got $rc" [ "$rc" -eq 73 ]
run field bodice.obj -o fresh --scales 2 --smoothness 10
expect_ok "field --scales 2 --smoothness 10"
check "text summary on stdout" grep -q 'singularities' "$WORK/out"
check "scales in the report" json_true "d['scales'] == 2 and d['smoothness'] == 10" fresh/report.json

# ------------------------------------------------------------------ failures leave nothing
echo '{"curves": [[[0, 0, 0]]]}' >short.json
echo 'not json' >garbage.json
expect_error 65 short.json --absent bad/field.obj --absent bad/field.glb --absent bad/report.json -- \
    field bodice.obj --sketch short.json -o bad
expect_error 65 garbage.json --absent bad/report.json -- field bodice.obj --sketch garbage.json -o bad
expect_error 66 missing.json --absent bad/report.json -- field bodice.obj --sketch missing.json -o bad
expect_error 64 scales --absent bad/report.json -- field bodice.obj --scales 0 -o bad
expect_error 64 smoothness --absent bad/report.json -- field bodice.obj --smoothness -1 -o bad
expect_error 64 "-o" -- field bodice.obj
expect_error 66 nothere.obj -- field nothere.obj -o bad

# ------------------------------------------------------------------ the glTF validator
source_dir=${PZ_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}
validator="$source_dir/.tools/node_modules/gltf-validator"
if command -v node >/dev/null 2>&1 && [ -d "$validator" ]; then
    cat >validate.js <<'EOF'
const fs = require('fs');
const validator = require(process.argv[2]);
validator.validateBytes(new Uint8Array(fs.readFileSync(process.argv[3])), {
  uri: 'field.glb', maxIssues: 50,
  externalResourceFunction: (uri) => Promise.reject(new Error('unexpected external resource ' + uri)),
}).then((report) => {
  const issues = report.issues;
  console.log(`errors ${issues.numErrors} warnings ${issues.numWarnings}`);
  for (const m of issues.messages) if (m.severity <= 1) console.log(`${m.code} ${m.pointer || ''}: ${m.message}`);
  process.exit(issues.numErrors > 0 ? 1 : 0);
}).catch((error) => { console.log('validator failed: ' + error); process.exit(1); });
EOF
    node validate.js "$validator" result/field.glb >validator.log 2>&1
    check "field.glb fails the glTF validator: $(cat validator.log)" [ $? -eq 0 ]
    node validate.js "$validator" fresh/field.glb >validator.log 2>&1
    check "fresh/field.glb fails the glTF validator: $(cat validator.log)" [ $? -eq 0 ]
else
    echo "note: node or gltf-validator missing, field.glb not validated"
fi

finish
