#!/usr/bin/env bash
# tests/cli/test_cli_grain_hints.sh -- grain hints (`--grain-hints FILE`, docs/run.md "Grain hints"): a short
# stroke drawn on a piece turns that piece's warp along it, with every back-end; the piece without a hint keeps
# the global grain; report.json names each piece's turn; the strain stays as low (a developable cylinder cut on
# the bias is still developable); hints off the garment, malformed or empty are refused with one line naming
# the file (exit 65, 66, 64) and nothing written.
#
# The measure: the hint's end points are mapped into the pattern through garment.obj (3D positions with the
# pattern's vt), and the angle between their chord and +v (the warp) is taken. Without hints a 45-degree helix
# stroke on the upright cylinder lies at 45 degrees to the warp; with it as a hint, within 1 degree.
source "$(dirname "$0")/lib.sh"

run generate cylinder -o cyl.obj --faces 3000
expect_ok "generate cylinder"

# A helix stroke on the cylinder (radius 150 mm, z up) at ANGLE degrees from the vertical, around PHI degrees.
helix() { # helix PHI ANGLE FILE
    python3 - "$@" <<'EOF'
import json, math, sys
phi0, angle, out = math.radians(float(sys.argv[1])), math.radians(float(sys.argv[2])), sys.argv[3]
points = []
for t in (-30, -15, 0, 15, 30):
    phi = phi0 + t * math.sin(angle) / 150.0
    points.append([150 * math.cos(phi), 150 * math.sin(phi), 200 + t * math.cos(angle)])
json.dump({"curves": [points]}, open(out, "w"))
EOF
}

# The angle (degrees) between the flattened chord of FILE's first curve and +v, from RUN_DIR/garment.obj.
hint_angle() { # hint_angle RUN_DIR FILE
    python3 - "$@" <<'EOF'
import json, math, sys
run, hints = sys.argv[1], json.load(open(sys.argv[2]))["curves"][0]
V, T, F = [], [], []
for line in open(run + "/garment.obj"):
    w = line.split()
    if w and w[0] == "v": V.append([float(x) for x in w[1:4]])
    elif w and w[0] == "vt": T.append([float(x) for x in w[1:3]])
    elif w and w[0] == "f": F.append([[int(x) - 1 for x in c.split("/")[:2]] for c in w[1:4]])
def sub(a, b): return [a[i] - b[i] for i in range(len(a))]
def dot(a, b): return sum(a[i] * b[i] for i in range(len(a)))
def to_uv(p):
    best = min(F, key=lambda f: sum((sum(V[c[0]][k] for c in f) / 3 - p[k]) ** 2 for k in range(3)))
    a, b, c = (V[x[0]] for x in best)
    ta, tb, tc = (T[x[1]] for x in best)
    e1, e2, q = sub(b, a), sub(c, a), sub(p, a)
    # least squares: q = s e1 + t e2
    m11, m12, m22, r1, r2 = dot(e1, e1), dot(e1, e2), dot(e2, e2), dot(q, e1), dot(q, e2)
    det = m11 * m22 - m12 * m12
    s, t = (r1 * m22 - r2 * m12) / det, (r2 * m11 - r1 * m12) / det
    return [ta[k] + s * (tb[k] - ta[k]) + t * (tc[k] - ta[k]) for k in range(2)]
p0, p1 = to_uv(hints[0]), to_uv(hints[-1])
du, dv = p1[0] - p0[0], p1[1] - p0[1]
print("%.3f" % math.degrees(math.atan2(abs(du), abs(dv))))
EOF
}

helix 90 45 hint45.json
run run cyl.obj -o plain --quiet
expect_ok "run without hints"
plain=$(hint_angle plain hint45.json)
check "without hints the 45-degree stroke is not at 45 degrees to the warp: $plain" \
    python3 -c "import sys; sys.exit(0 if abs($plain - 45) < 2 else 1)"

for backend in textile lscm wirewarp springmass; do
    run run cyl.obj -o "hinted-$backend" --grain-hints hint45.json --backend $backend --quiet
    expect_ok "run --grain-hints ($backend)"
    angle=$(hint_angle "hinted-$backend" hint45.json)
    check "--grain-hints ($backend): the hinted stroke lies $angle degrees off the warp, expected < 1" \
        python3 -c "import sys; sys.exit(0 if $angle < 1 else 1)"
    report_checks "--grain-hints ($backend)" "hinted-$backend" \
        "the report does not count one hint: $(grep -o '"grain_hints":[^,]*' "hinted-$backend/report.json")" \
        "d['parameters']['grain_hints'] == 1" \
        "not one piece turned by about 45 degrees and the others not: $(grep -o '"grain_turn_deg":[^,]*' "hinted-$backend/report.json" | tr '\n' ' ')" \
        "sorted(round(abs(p['grain_turn_deg'])) for p in d['panels'] if abs(p['grain_turn_deg']) > 1) == [45] and all(abs(p['grain_turn_deg']) < 1e-9 or abs(abs(p['grain_turn_deg']) - 45) < 1 for p in d['panels'])" \
        "a bias-cut developable cylinder strains: $(grep -o '"max_abs_strain":[^,]*' "hinted-$backend/report.json" | head -1)" \
        "d['summary']['max_abs_strain'] < 0.01 and d['summary']['injective']"
done

# The other piece keeps the global grain: a vertical stroke on it stays along the warp.
helix 270 0 vertical_other.json
angle=$(hint_angle hinted-textile vertical_other.json)
check "the piece without a hint turned too: a vertical stroke on it lies $angle degrees off the warp" \
    python3 -c "import sys; sys.exit(0 if $angle < 1 else 1)"

# flatten takes hints for the user's panels too.
run flatten hinted-textile/garment.obj -o flat-hinted --panels uv --grain-hints hint45.json --quiet
expect_ok "flatten --grain-hints"
angle=$(hint_angle flat-hinted hint45.json)
check "flatten --grain-hints: the stroke lies $angle degrees off the warp" python3 -c "import sys; sys.exit(0 if $angle < 1 else 1)"

# Refused: a hint off the garment (65, named), a malformed file (65), a missing file (66), an empty name (64);
# nothing written.
printf '{"curves": [[[0, 0, 5000], [0, 10, 5000]]]}' >far.json
expect_error 65 "far.json" --absent bad1 -- run cyl.obj -o bad1 --grain-hints far.json
printf '{"curves": [[[0, 0, 0]]' >broken.json
expect_error 65 "broken.json" --absent bad2 -- run cyl.obj -o bad2 --grain-hints broken.json
python3 -c 'import json; json.dump({"curves": [[[150, 0, 100], [150, 0, 110]]] * 201}, open("many.json", "w"))'
expect_error 65 "at most 200" --absent bad5 -- run cyl.obj -o bad5 --grain-hints many.json
expect_error 66 "missing.json" --absent bad3 -- run cyl.obj -o bad3 --grain-hints missing.json
expect_error 64 "--grain-hints" --absent bad4 -- run cyl.obj -o bad4 --grain-hints=

finish
