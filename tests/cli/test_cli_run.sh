#!/usr/bin/env bash
# tests/cli/test_cli_run.sh -- `panelize run` end to end on generated garments:
# every panel a disk with at most C corners, every triangle's strain within
# +-S, no flip or boundary self-intersection, seams' sides within 0.5% in
# length; the symmetric bodice gives a mirror-symmetric layout and pattern; a
# stricter S or a smaller C never gives fewer panels (a sweep over S and C);
# the output does not depend on the thread count (byte for byte); --pose,
# --sketch (adding at most 2 pieces), --darts off, --symmetry and --max-pieces do
# what they say; the trade-off curve is monotone; --panels skips
# segmentation; bad input fails cleanly or ends as a best effort marked as
# failing its goals (one summary line), never a hang.
# The shared garments are checked by test_cli_run_garments.sh.
#
# SPDX-License-Identifier: GPL-3.0-or-later
set -u

source "$(dirname "$0")/lib.sh"

# goal_checks WHAT DIR S C: report.json says the goals hold, and so do its own figures.
goal_checks() {
    local what=$1 dir=$2 strain=$3 corners=$4
    report_checks "$what" "$dir" \
        "summary.goals_met is not true: $(grep -o '"goals_reasons":[^\n]*' "$dir/report.json" | head -c 300)" \
        "d['summary']['goals_met'] is True" \
        "not injective" "d['summary']['injective'] is True" \
        "a panel has more than $corners corners" "all(p['corners'] <= $corners for p in d['panels'])" \
        "a triangle's strain exceeds $strain" "d['summary']['max_abs_strain'] <= $strain + 1e-9" \
        "a seam's sides differ by more than 0.5%" "d['summary']['max_seam_mismatch_rel'] <= 0.005" \
        "flipped triangles" "sum(p['flipped_triangles'] for p in d['panels']) == 0" \
        "boundary self-intersections" "sum(p['boundary_self_intersections'] for p in d['panels']) == 0" \
        "panels not from segmentation" "d['segmentation']['panels'] == 'automatic'"
}

panel_count() { python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["summary"]["panel_count"])' "$1"; }

# ------------------------------------------------------------------ the bodice (symmetric)
run generate bodice -o bodice.obj --faces 3000
expect_ok "generate bodice"

OMP_NUM_THREADS=2 run run bodice.obj -o bodice2 --quiet
expect_ok "run bodice"
for file in garment.obj layout.obj report.json; do
    check "run bodice: no $file" [ -s "bodice2/$file" ]
done
goal_checks "run bodice" bodice2 0.05 8
# The mirror plane (docs/segment.md, "Symmetry"): found on x; the layout made on one half and mirrored is kept
# only when it has at most max(+2, +25 %) the panels of the one without the plane, and dropped when the joint
# flattening rejects it. The 3K bodice's first layouts have 3 panels either way; the mirrored one's front
# reaches 0.052 in the joint flattening: the plane is found, dropped, and report.json says so and both counts.
report_checks "run bodice symmetry" bodice2 \
    "no mirror plane found on x" "d['segmentation']['symmetry']['found'] and d['segmentation']['symmetry']['axis'] == 'x'" \
    "the plane's figures" "d['segmentation']['symmetry']['normal'] == [1, 0, 0] and d['segmentation']['symmetry']['mesh_residual_rel'] < 1e-6" \
    "the plane used though its layout has more panels (or the verdict rejected it)" \
    "d['segmentation']['symmetry']['used'] == (d['segmentation']['symmetry']['pieces_with_plane'] <= max(d['segmentation']['symmetry']['pieces_without_plane'] + 2, 1.25 * d['segmentation']['symmetry']['pieces_without_plane']) and not d['segmentation']['symmetry']['rejected_by_verdict'])" \
    "not both layouts counted" "d['segmentation']['symmetry']['pieces_with_plane'] >= 1 and d['segmentation']['symmetry']['pieces_without_plane'] >= 1"

# Without darts, at S = 0.06, the mirrored layout is kept (3 panels: the front crossed by the plane, the back
# in two mirror halves; at S = 0.05 the joint flattening takes the front to 0.052 and the plane is dropped):
# every panel is its own mirror image or its partner's, a piece made exact is exact within 0.1 mm, and --fold
# draws the front as its half.
run run bodice.obj -o bodice-fold --darts off --fold --max-strain 0.06 --quiet
expect_ok "run bodice --darts off --fold"
report_checks "run bodice mirrored" bodice-fold \
    "the plane not used" "d['segmentation']['symmetry']['used']" \
    "panels not mirror images" "all(p['mirror_panel'] >= 0 and d['panels'][p['mirror_panel']]['mirror_panel'] == p['id'] for p in d['panels'])" \
    "no piece made exact" "d['segmentation']['symmetry']['exact_mirror_pieces'] >= 1" \
    "a piece reported exact is not (0.1 mm)" \
    "sum(1 for p in d['panels'] if 0 <= p['mirror_residual_mm'] < 0.1) >= d['segmentation']['symmetry']['exact_mirror_pieces']" \
    "layout residual over a quarter of the mean edge" "d['segmentation']['symmetry']['layout_residual_mm'] < 5"
check "run bodice --fold: no piece cut on the fold in pattern.svg" grep -q 'Cut 1 on fold' bodice-fold/pattern.svg
check "run bodice --fold: no fold (layer 6) in pattern.dxf" grep -q 'Place on fold' bodice-fold/pattern.dxf

# Forcing a plane never multiplies the pieces: a plane across the bodice (y) and its own (x) give at most
# max(+2, +25 %) the panels of the run without symmetry (the mirrored layout is dropped when it has more).
run run bodice.obj -o bodice-off --symmetry off --outputs json --quiet
expect_ok "run bodice --symmetry off"
for plane in y x 0,1,0,0 0,0,0,1,0,0; do
    run run bodice.obj -o "bodice-force-$plane" --symmetry $plane --outputs json --quiet
    expect_ok "run bodice --symmetry $plane"
    check "run bodice --symmetry $plane: the plane multiplied the panels" python3 -c '
import json, sys
forced, off = (json.load(open(f + "/report.json")) for f in sys.argv[1:3])
sym = forced["segmentation"]["symmetry"]
n, n_off = forced["summary"]["panel_count"], off["summary"]["panel_count"]
ok = not sym["used"] or sym["pieces_with_plane"] <= max(sym["pieces_without_plane"] + 2, 1.25 * sym["pieces_without_plane"])
sys.exit(0 if ok and n <= max(n_off + 2, 1.25 * n_off) else 1)' "bodice-force-$plane" bodice-off
done
expect_error 64 "--symmetry" --absent bodice-bad -- run bodice.obj -o bodice-bad --symmetry 0,0,0,1 --quiet
expect_error 64 "--symmetry" --absent bodice-bad -- run bodice.obj -o bodice-bad --symmetry 1,0,0 --quiet
# Piece names and shapes in report.json: every piece named, no two alike, a mirror pair named alike but for
# its side; each piece's width, area share and extent across the grain; each dart's intake.
report_checks "run bodice names" bodice2 \
    "a piece without a name or two alike: $(grep -o '"name": "[^"]*' bodice2/report.json | tr '\n' ' ')" \
    "len(set(p['name'] for p in d['panels'])) == len(d['panels']) and all(p['name'] for p in d['panels'])" \
    "mirror partners not named X_left / X_right" \
    "all(p['mirror_panel'] in (-1, p['id']) or sorted([p['name'], d['panels'][p['mirror_panel']]['name']]) == sorted([p['name'].replace('_right', '_left'), p['name'].replace('_left', '_right')]) for p in d['panels'])" \
    "no piece-shape figures" \
    "all(p['width_mm'] > 0 and 0 < p['area_share'] <= 1 and p['across_grain_mm'] > 0 for p in d['panels'])" \
    "a dart without its intake" "all(x['intake_mm'] >= 0 for x in d['darts'])" \
    "no count of merged slivers" "d['segmentation']['merged_slivers'] >= 0"

check "layout.obj has polylines" grep -q '^l ' bodice2/layout.obj

# Same input, same output, whatever the thread count: every file, byte for
# byte, but for what says when and how fast (report.json's timings, which
# report.html shows, and the PDFs' creation date).
without_timings() {
    python3 -c 'import json, sys
def drop(x):
    if isinstance(x, dict):
        return {k: drop(v) for k, v in x.items() if k not in ("timings_ms", "ms")}
    return [drop(v) for v in x] if isinstance(x, list) else x
print(json.dumps(drop(json.load(open(sys.argv[1]))), indent=0))' "$1"
}
same_output() { # same_output FILE1 FILE2
    case $1 in
    *.json) cmp -s <(without_timings "$1") <(without_timings "$2") ;;
    *.pdf) cmp -s <(sed 's/CreationDate ([^)]*)//' "$1") <(sed 's/CreationDate ([^)]*)//' "$2") ;;
    *) cmp -s "$1" "$2" ;;
    esac
}
for threads in 1 4; do
    OMP_NUM_THREADS=$threads run run bodice.obj -o bodice-t$threads --quiet
    expect_ok "run bodice, $threads threads"
    for path in bodice2/*; do
        file=${path#bodice2/}
        [ "$file" = report.html ] && continue
        check "run bodice: $file differs between $threads and 2 threads" same_output "bodice-t$threads/$file" "$path"
    done
done

# Stricter goals never give fewer panels (docs/segment.md, "Monotone panel counts"): a sweep over S and C,
# every pair where the looser setting is an ancestor of the stricter one on the ladder's grid (S rungs at
# multiples of 0.01 up to 0.05, C rungs every integer up to 8) compared. The code before the ladder gave
# 2 panels at S 0.045 and 0.04 against 3 at 0.05.
for strain in 0.05 0.045 0.04 0.03; do
    for corners in 8 6; do
        [ "$strain" = 0.05 ] && [ "$corners" = 8 ] && continue  # bodice2
        run run bodice.obj -o "sweep-$strain-$corners" --max-strain $strain --max-corners $corners --quiet
        expect_ok "run bodice --max-strain $strain --max-corners $corners"
        goal_checks "run bodice S $strain C $corners" "sweep-$strain-$corners" $strain $corners
    done
done
ln -sfn bodice2 sweep-0.05-8
cat >monotone.py <<'PY'
import json, math, sys
def count(s, c):
    return json.load(open('sweep-%s-%d/report.json' % (s, c)))['summary']['panel_count']
def parents(s, c):
    # the ladder of pipeline/cmd_run.c: (next S rung up, C) when S < 0.05, (S, C + 1) when C < 8
    out = []
    if float(s) < 0.05:
        out.append(('%g' % (min(math.floor(float(s) / 0.01 + 1e-9) + 1, 5) / 100.0), c))
    if c < 8:
        out.append((s, c + 1))
    return out
def ancestors(s, c):
    seen, todo = set(), parents(s, c)
    while todo:
        node = todo.pop()
        if node not in seen:
            seen.add(node)
            todo += parents(*node)
    return seen
sweep = [(s, c) for s in ('0.05', '0.045', '0.04', '0.03') for c in (8, 6)]
pairs = [(s, c, a) for s, c in sweep for a in ancestors(s, c) if a in sweep]
bad = ['S %s C %d: %d panels < S %s C %d: %d' % (s, c, count(s, c), a[0], a[1], count(*a))
       for s, c, a in pairs if count(s, c) < count(*a)]
print('; '.join(bad) if bad else '%d pairs compared' % len(pairs))
sys.exit(1 if bad or len(pairs) < 12 else 0)
PY
check "panel counts not monotone over the sweep: $(python3 monotone.py)" sh -c 'python3 monotone.py >/dev/null'
# The looser settings laid out first do not depend on the thread count either.
OMP_NUM_THREADS=1 run run bodice.obj -o sweep-1thread --max-strain 0.045 --max-corners 6 --quiet
expect_ok "run bodice S 0.045 C 6, 1 thread"
for file in layout.obj garment.obj report.json; do
    check "run bodice S 0.045 C 6: $file differs between 1 thread and the default" \
        same_output sweep-1thread/$file sweep-0.045-6/$file
done

# ------------------------------------------------------------------ the trade-off and the piece budget
# report.json's trade-off (docs/run.md, "The trade-off"): the grid of strain goals, each with the pieces it
# needs or null; a stricter S never needs fewer pieces; the run's own S needs no more than it made; the share
# of the area over S and the outlook are there.
report_checks "run bodice: trade-off" bodice2 \
    "no trade-off grid" "[p['max_strain'] for p in d['tradeoff']] == [0.03, 0.04, 0.05, 0.07, 0.1, 0.15, 0.2]" \
    "a stricter S needs fewer pieces: $(python3 -c 'import json; print(json.load(open("bodice2/report.json"))["tradeoff"])')" \
    "all(a['pieces'] is None or (b['pieces'] is not None and a['pieces'] >= b['pieces']) for a, b in zip(d['tradeoff'], d['tradeoff'][1:]))" \
    "the run's own S needs more pieces than it made" \
    "[p['pieces'] for p in d['tradeoff'] if p['max_strain'] == 0.05][0] <= d['summary']['panel_count']" \
    "the merge sequence does not start at the layout" \
    "d['tradeoff_sequence'][0]['pieces'] == d['summary']['panel_count'] and all(a['pieces'] > b['pieces'] for a, b in zip(d['tradeoff_sequence'], d['tradeoff_sequence'][1:]))" \
    "the area share over S is not 0 although every triangle is within S" \
    "d['summary']['area_over_max_strain'] == 0 and d['summary']['max_abs_strain'] <= 0.05" \
    "no outlook" "d['strain_outlook']['reachable'] is True and d['strain_outlook']['samples'] > 0" \
    "truing neither on nor dropped" "d['segmentation']['truing']['on'] is not d['segmentation']['truing']['dropped']"
check "report.html shows no trade-off" grep -q 'id="tradeoff"' bodice2/report.html

# --max-pieces N: at most N pieces (a mirror pair counts as two), every one a disk flattening injectively;
# the budget is reported as met.
for pieces in 2 1; do
    run run bodice.obj -o budget-$pieces --max-pieces $pieces --quiet
    expect_ok "run bodice --max-pieces $pieces"
    report_checks "run bodice --max-pieces $pieces" budget-$pieces \
        "more than $pieces pieces" "d['summary']['panel_count'] <= $pieces" \
        "the budget is not reported as met" \
        "d['segmentation']['max_pieces']['pieces'] == $pieces and d['segmentation']['max_pieces']['met'] is True" \
        "not injective" "d['summary']['injective'] is True" \
        "flipped triangles" "sum(p['flipped_triangles'] for p in d['panels']) == 0" \
        "the area share over S disagrees with the worst strain" \
        "(d['summary']['area_over_max_strain'] > 0) == (d['summary']['max_abs_strain'] > 0.05)"
done
check "run bodice --max-pieces 2: not fewer pieces than the defaults (the budget did nothing to check)" \
    [ "$(panel_count bodice2/report.json)" -gt 2 ]
for bad in 0 -1 1.5 x; do
    run run bodice.obj -o budget-bad --max-pieces "$bad" --quiet
    check "run --max-pieces $bad: exit $rc, not 64" [ "$rc" -eq 64 ]
done

# ------------------------------------------------------------------ skirt and sleeve
for shape in skirt sleeve; do
    run generate $shape -o $shape.obj --faces 3000
    expect_ok "generate $shape"
    run run $shape.obj -o $shape --quiet
    expect_ok "run $shape"
    goal_checks "run $shape" $shape 0.05 8
done

# ------------------------------------------------------------------ options
# --pose: the goal holds in every pose. A 2-pose bodice (its poses stretch some triangles by over 10 %
# against the rest pose, so S = 0.05 cannot be met in all three; S = 0.07 can): goals_met must agree
# with the strain measured over the poses. Before, goals_met judged the rest pose only and said true
# next to a worst pose strain of 0.070 > S.
run generate bodice -o posed.obj --faces 3000 --poses 2
expect_ok "generate bodice --poses 2"
run run posed.obj -o posed --pose posed.pose1.obj --pose posed.pose2.obj --max-strain 0.07 --quiet
expect_ok "run --pose x2"
report_checks "run --pose x2" posed \
    "goals_met although a pose's strain exceeds S" \
    "not d['summary']['goals_met'] or max(d['summary']['max_abs_strain_by_pose']) <= 0.07 + 1e-9" \
    "goals not met at S = 0.07 over 3 poses: $(grep -o '"goals_reasons":[^\n]*' posed/report.json | head -c 200)" \
    "d['summary']['goals_met'] is True and len(d['summary']['max_abs_strain_by_pose']) == 3"

# --sketch: a line down the front (garment vertices from the hem up, off the mirror plane) is a seam of
# the layout: every sketch point is a vertex of layout.obj's polylines (--truing off keeps them in place).
cat >sketch.py <<'PY'
import json, sys
vs = [tuple(map(float, l.split()[1:4])) for l in open('bodice.obj') if l.startswith('v ')]
if sys.argv[1] == 'make':
    top = max(v[2] for v in vs if v[1] > 0 and abs(v[0] - 60) < 15)
    points = []
    for i in range(17):
        z = top * i / 16
        best = min((v for v in vs if v[1] > 0), key=lambda v: (v[0] - 60) ** 2 + (v[2] - z) ** 2)
        if best not in points:
            points.append(best)
    json.dump({'curves': [[list(p) for p in points]]}, open('sketch.json', 'w'))
    sys.exit(0)
points = json.load(open('sketch.json'))['curves'][0]
layout = [tuple(map(float, l.split()[1:4])) for l in open(sys.argv[1] + '/layout.obj') if l.startswith('v ')]
hits = sum(min(sum((a - b) ** 2 for a, b in zip(p, q)) for q in layout) < 1e-6 for p in points)
print('%d of %d sketch points on the layout' % (hits, len(points)))
sys.exit(0 if hits == len(points) and len(points) >= 10 else 1)
PY
python3 sketch.py make
run run bodice.obj -o sketched --sketch sketch.json --truing off --quiet
expect_ok "run --sketch"
check "run --sketch: the sketch is not a seam of layout.obj: $(python3 sketch.py sketched)" sh -c 'python3 sketch.py sketched >/dev/null'
check "without --sketch the line is no seam (the check can fail)" sh -c '! python3 sketch.py bodice2 >/dev/null'
goal_checks "run --sketch" sketched 0.05 8
# A sketched seam adds about one piece, not eight (docs/segment.md, "Where seams go"): at most 2 more than
# the same run without it.
run run bodice.obj -o bodice-untrued --truing off --quiet
expect_ok "run bodice --truing off"
check "run --sketch: $(panel_count sketched/report.json) pieces, more than 2 above the $(panel_count bodice-untrued/report.json) without" \
    [ "$(panel_count sketched/report.json)" -le $(($(panel_count bodice-untrued/report.json) + 2)) ]

# A sketch on one side of a symmetric garment asks for a pattern that is not symmetric: the plane is found
# and not used (a layout made on one half cannot honour it), and report.json says why (docs/run.md,
# "Sketches and symmetry").
report_checks "run --sketch (one side)" sketched \
    "the plane used, or not said, though the sketch is on one side" \
    "d['segmentation']['symmetry']['found'] and not d['segmentation']['symmetry']['used'] and d['segmentation']['symmetry']['sketch_not_symmetric'] and not d['segmentation']['mirror_sketch']"
# --mirror-sketch: the stroke's mirror image is drawn too, so both are seams and the sketch no reason to
# drop the plane.
cat >mirrored.py <<'PY'
import json, math, sys
vs = [tuple(map(float, l.split()[1:4])) for l in open('bodice.obj') if l.startswith('v ')]
fs = [[int(t.split('/')[0]) - 1 for t in l.split()[1:4]] for l in open('bodice.obj') if l.startswith('f ')]
edges = [math.dist(vs[f[k]], vs[f[(k + 1) % 3]]) for f in fs for k in range(3)]
mean_edge = sum(edges) / len(edges)
d = json.load(open(sys.argv[1] + '/report.json'))['segmentation']['symmetry']
n, off = d['normal'], d['offset']
points = json.load(open('sketch.json'))['curves'][0]
layout = [tuple(map(float, l.split()[1:4])) for l in open(sys.argv[1] + '/layout.obj') if l.startswith('v ')]
def near(p):
    return min(math.dist(p, q) for q in layout) <= mean_edge
def mirror(p):
    t = 2 * (sum(a * b for a, b in zip(n, p)) - off)
    return [a - t * b for a, b in zip(p, n)]
hits = sum(near(p) for p in points)
mirrored = sum(near(mirror(p)) for p in points)
print('%d of %d sketch points and %d of their mirror images within a mean edge (%.1f mm) of a seam' %
      (hits, len(points), mirrored, mean_edge))
sys.exit(0 if hits == len(points) and mirrored == len(points) and len(points) >= 10 else 1)
PY
run run bodice.obj -o mirrored-sketch --sketch sketch.json --mirror-sketch --truing off --quiet
expect_ok "run --sketch --mirror-sketch"
check "run --mirror-sketch: the stroke and its mirror image are not both seams: $(python3 mirrored.py mirrored-sketch)" \
    sh -c 'python3 mirrored.py mirrored-sketch >/dev/null'
check "without --mirror-sketch the mirror image is no seam (the check can fail): $(python3 mirrored.py sketched)" \
    sh -c '! python3 mirrored.py sketched >/dev/null'
goal_checks "run --mirror-sketch" mirrored-sketch 0.05 8
report_checks "run --mirror-sketch" mirrored-sketch \
    "the sketch, mirrored, still counted as one-sided" \
    "d['segmentation']['symmetry']['found'] and not d['segmentation']['symmetry']['sketch_not_symmetric'] and d['segmentation']['mirror_sketch']"
# A sketch that is its own mirror image (a centre front line) leaves the plane to the layout.
python3 - <<'PY'
import json
vs = [tuple(map(float, l.split()[1:4])) for l in open('bodice.obj') if l.startswith('v ')]
top = max(v[2] for v in vs if v[1] > 0 and abs(v[0]) < 15)
points = []
for i in range(17):
    best = min((v for v in vs if v[1] > 0), key=lambda v: v[0] ** 2 + (v[2] - top * i / 16) ** 2)
    if list(best) not in points:
        points.append(list(best))
json.dump({'curves': [points]}, open('centre.json', 'w'))
PY
run run bodice.obj -o centre-sketch --sketch centre.json --quiet
expect_ok "run --sketch (centre line)"
report_checks "run --sketch (centre line)" centre-sketch \
    "a centre line counted as one-sided" "d['segmentation']['symmetry']['found'] and not d['segmentation']['symmetry']['sketch_not_symmetric']"

# --darts off: no dart anywhere, where darts on makes some (S = 0.045 without the mirror plane).
run run bodice.obj -o darts --max-strain 0.045 --symmetry off --quiet
expect_ok "run --max-strain 0.045 --symmetry off"
report_checks "darts on" darts "no dart at S 0.045 with darts on" "d['summary']['dart_count'] > 0"
run run bodice.obj -o nodarts --max-strain 0.045 --symmetry off --darts off --quiet
expect_ok "run --darts off"
report_checks "run --darts off" nodarts \
    "darts with --darts off" "d['summary']['dart_count'] == 0 and d['segmentation']['dart_count'] == 0" \
    "darts listed in the report" "all(p['darts'] == 0 for p in d['panels'])"
check "run --darts off: layout.obj has dart groups" sh -c '! grep -q "^g dart_" nodarts/layout.obj'
goal_checks "run --darts off" nodarts 0.045 8

# --symmetry off|x|y|z: the plane asked for is the one used (a given axis whatever its residual).
for mode in off x y z; do
    run run bodice.obj -o "sym-$mode" --symmetry $mode --quiet
    expect_ok "run --symmetry $mode"
    if [ $mode = off ]; then
        expected="not d['segmentation']['symmetry']['found']"
    else
        expected="d['segmentation']['symmetry']['found'] and d['segmentation']['symmetry']['axis'] == '$mode'"
    fi
    report_checks "run --symmetry $mode" "sym-$mode" \
        "not the plane asked for: $(grep -o '"symmetry": {[^}]*' sym-$mode/report.json | tr -d '\n' | head -c 200)" "$expected"
done
# The bodice's own plane (x) or none: the goals hold. A forced y or z plane is no mirror plane of the
# bodice (its residual is reported); the layout made through it is not judged here.
goal_checks "run --symmetry off" sym-off 0.05 8
goal_checks "run --symmetry x" sym-x 0.05 8

# ------------------------------------------------------------------ --panels skips segmentation
python3 - <<'PY'
faces = sum(1 for line in open('bodice.obj') if line.startswith('f '))
open('halves.txt', 'w').write(''.join('%d\n' % (0 if i < faces // 2 else 1) for i in range(faces)))
PY
run run bodice.obj -o given --panels halves.txt --quiet
expect_ok "run --panels FILE"
report_checks "run --panels FILE" given \
    "segmentation ran" "d['segmentation']['panels'] == 'given'" \
    "not 2 panels" "d['summary']['panel_count'] == 2" \
    "no corners per panel" "all('corners' in p and 'darts' in p for p in d['panels'])"

# ------------------------------------------------------------------ hard and bad input
# Unreachable goal: S = 0 on a curved surface. A best effort, marked as failing, in bounded time.
run generate hemisphere -o hemi.obj --faces 1500
start=$(date +%s)
run run hemi.obj -o hemi0 --max-strain 0
expect_ok "run --max-strain 0 (best effort)"
check "run --max-strain 0 took over 120 s" [ $(($(date +%s) - start)) -lt 120 ]
check "run --max-strain 0: not one 'goals unreachable' line on stderr: $(grep 'goals' "$WORK/err" | head -c 300)" \
    [ "$(grep -c '^panelize: run: goals unreachable: [0-9]* of [0-9]* panels miss them, [0-9]* exceed S = 0, worst strain' "$WORK/err")" -eq 1 ]
report_checks "run --max-strain 0" hemi0 \
    "goals_met is not false" "d['summary']['goals_met'] is False" \
    "the reasons do not start with a summary: $(grep -o '"goals_reasons":[^\n]*' hemi0/report.json | head -c 200)" \
    "re.match(r'\d+ of \d+ panels miss the goals \(\d+ exceed S = 0, worst strain [0-9.e-]+\): panel', d['summary']['goals_reasons'])" \
    "a strain printed as 0.0000 > 0" "'0.0000 >' not in d['summary']['goals_reasons']" \
    "no reachable S from the looser settings (one of S = 0.05 ... 0.01 met its goals on the hemisphere)" \
    "0 < d['segmentation']['looser_goals']['reachable_strain'] <= 0.05 and d['segmentation']['looser_goals']['reachable_panels'] >= 1"
# The diagnosis names the S that can be met, the same as the report's (issue 15: impossible goals say so).
reachable=$(python3 -c "import json; print('%g' % json.load(open('hemi0/report.json'))['segmentation']['looser_goals'].get('reachable_strain', -1))")
check "run --max-strain 0: the note does not name the reachable S = $reachable: $(grep unreachable "$WORK/err" | tail -c 200)" \
    grep -q "; S = 0 cannot be met here, S = $reachable can ([0-9]* panels)" "$WORK/err"
# The best sound layout is written (issue 15), not a best effort of slivers: the reachable S's layout.
report_checks "run --max-strain 0: written layout" hemi0 \
    "not the layout of the reachable S written: $(grep -o '"looser_goals":[^}]*' hemi0/report.json | head -c 300)" \
    "d['segmentation']['looser_goals']['written_strain'] == d['segmentation']['looser_goals']['reachable_strain'] and d['summary']['panel_count'] == d['segmentation']['looser_goals']['reachable_panels']"
check "run --max-strain 0: no note that the reachable layout is written" grep -q "is written instead, flattened for that S" "$WORK/err"
# Impossible goals end quickly (issue 15): the outlook's doubt confirmed by one layout that stopped early, the
# settings from the outlook's suggestion up laid out each on its own, not the ladder of five rungs from 0.05
# down; the written layout flattened within its S (the final flattening used to run without a strain goal at
# S = 0: 0.0695 where the S = 0.01 layout flattens within 0.0098). Fails if the path goes back to the ladder.
report_checks "run --max-strain 0: the short path" hemi0 \
    "the looser settings were climbed as a ladder: $(grep -o '"looser_goals":[^}]*' hemi0/report.json | head -c 300)" \
    "d['segmentation']['looser_goals'].get('direct') is True and d['segmentation']['looser_goals']['settings'] <= 2 and d['segmentation']['looser_goals']['probe_panels'] >= 1" \
    "the written layout exceeds the S it was written for: $(grep -o '"max_abs_strain":[^,]*' hemi0/report.json | head -c 100)" \
    "d['summary']['max_abs_strain'] <= 1.05 * d['segmentation']['looser_goals']['written_strain']"
check "run --max-strain 0: no note that the layout stopped" grep -q "^panelize: run: S = 0: the layout stopped at [0-9]* panels" "$WORK/err"
# Said before the long work, in one line naming an S that would work (docs/run.md, "Can S be met?").
check "run --max-strain 0: not one 'cannot be met' line before the layout: $(grep -n 'cannot be met\|goals unreachable' "$WORK/err" | head -c 300)" \
    python3 -c 'import re, sys
lines = open(sys.argv[1]).read().splitlines()
said = [i for i, l in enumerate(lines) if re.match(r"panelize: run: S = 0 cannot be met with sound pieces: .*; S = 0\.\d\d would work$", l)]
field = [i for i, l in enumerate(lines) if l.startswith("panelize: run: field:")]
sys.exit(0 if len(said) == 1 and field and said[0] < field[0] else 1)' "$WORK/err"
# --strict: exit 3, its one line naming the reachable S first.
run run hemi.obj -o hemi0-strict --max-strain 0 --strict --quiet
check "run --max-strain 0 --strict: exit $rc, expected 3" [ "$rc" -eq 3 ]
check "run --max-strain 0 --strict: not one line naming the reachable S: $(head -c 300 "$WORK/err")" \
    grep -q "S = 0 cannot be met here, S = $reachable can" "$WORK/err"
# An impossible goal on a symmetric garment is laid out once (issue 15): when the written looser layout does
# not use the plane, the symmetric garment's layout is kept rather than the whole run made again on the
# garment as loaded (the 7K bodice: 9.5 -> 2.8 s on an idle machine, docs/run.md "Impossible goals"). Fails
# if the run lays the garment out a second time or the kept layout is not the reachable S's.
run generate bodice -o bodice7k.obj --faces 7000
run run bodice7k.obj -o bodice7k-0001 --max-strain 0.001
expect_ok "run --max-strain 0.001 on the 7K bodice"
check "run --max-strain 0.001 (7K bodice): the garment was laid out again: $(grep 'laid out again' "$WORK/err")" \
    sh -c '! grep -q "laid out again" "$1"' _ "$WORK/err"
report_checks "run --max-strain 0.001 (7K bodice)" bodice7k-0001 \
    "not the symmetric garment's sound layout: $(grep -o '"looser_goals":[^}]*' bodice7k-0001/report.json | head -c 300)" \
    "d['segmentation']['symmetry']['symmetrized'] is True and d['segmentation']['looser_goals'].get('direct') is True and d['segmentation']['looser_goals']['written_strain'] == d['segmentation']['looser_goals']['reachable_strain'] and d['summary']['max_abs_strain'] <= 1.05 * d['segmentation']['looser_goals']['written_strain']"
report_checks "run --max-strain 0: outlook" hemi0 \
    "the outlook does not say S = 0 is out of reach" \
    "d['strain_outlook']['reachable'] is False and d['strain_outlook']['suggested_max_strain'] > 0" \
    "the outlook flattened no sample piece" "d['strain_outlook']['samples'] > 0 and d['strain_outlook']['piece_strain'] > 0"

# Two components (two garment parts side by side): each is segmented; every panel stays in one part.
python3 - <<'PY'
lines = [l for l in open('bodice.obj') if l.startswith(('v ', 'f '))]
vs = [l for l in lines if l.startswith('v ')]
fs = [l for l in lines if l.startswith('f ')]
n = len(vs)
out = vs + ['v %s %s %s\n' % (float(x) + 600.0, y, z) for x, y, z in (l.split()[1:4] for l in vs)]
out += fs + ['f ' + ' '.join(str(int(t.split('/')[0]) + n) for t in l.split()[1:]) + '\n' for l in fs]
open('two.obj', 'w').writelines(out)
PY
run run two.obj -o two --quiet
expect_ok "run two components"
report_checks "run two components" two \
    "fewer panels than two parts need" "d['summary']['panel_count'] >= 2" \
    "not injective" "d['summary']['injective'] is True"

# A closed surface (no boundary): loops are needed; it must not hang or crash.
python3 - <<'PY'
import math
# An ellipsoid from a UV sphere with poles, about 30 x 40 quads.
rings, segs = 24, 32
verts = [(0, 0, 300.0)]
for i in range(1, rings):
    t = math.pi * i / rings
    for j in range(segs):
        p = 2 * math.pi * j / segs
        verts.append((200 * math.sin(t) * math.cos(p), 150 * math.sin(t) * math.sin(p), 300 * math.cos(t)))
verts.append((0, 0, -300.0))
faces = []
for j in range(segs):
    faces.append((0, 1 + j, 1 + (j + 1) % segs))
for i in range(rings - 2):
    for j in range(segs):
        a = 1 + i * segs + j; b = 1 + i * segs + (j + 1) % segs
        c = a + segs; d = b + segs
        faces += [(a, c, d), (a, d, b)]
last = len(verts) - 1
base = 1 + (rings - 2) * segs
for j in range(segs):
    faces.append((base + j, last, base + (j + 1) % segs))
with open('closed.obj', 'w') as f:
    for v in verts:
        f.write('v %.6f %.6f %.6f\n' % v)
    for a, b, c in faces:
        f.write('f %d %d %d\n' % (a + 1, b + 1, c + 1))
PY
start=$(date +%s)
run run closed.obj -o closed --quiet
check "run closed surface: exit $rc ($(head -c 300 "$WORK/err"))" [ "$rc" -eq 0 ]
check "run closed surface took over 120 s" [ $(($(date +%s) - start)) -lt 120 ]
[ "$rc" -eq 0 ] && report_checks "run closed surface" closed \
    "fewer than 2 panels on a closed surface" "d['summary']['panel_count'] >= 2"

# Bad options and files: one line, the right exit code, nothing written.
expect_error 64 "--max-strain" --absent bad1 -- run bodice.obj -o bad1 --max-strain -1
expect_error 64 "--max-corners" --absent bad2 -- run bodice.obj -o bad2 --max-corners zero
expect_error 64 "--symmetry" --absent bad3 -- run bodice.obj -o bad3 --symmetry w
expect_error 64 "--darts" --absent bad4 -- run bodice.obj -o bad4 --darts maybe
expect_error 64 "--prepare" --absent bad5 -- run bodice.obj -o bad5 --prepare always
expect_error 66 "missing.obj" --absent bad6 -- run missing.obj -o bad6
printf 'v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n' >nan.obj
expect_error 65 "nan.obj" --absent bad7 -- run nan.obj -o bad7 --prepare off
printf '{"curves": [[[0,0,0]]]}' >short-sketch.json
expect_error 65 "short-sketch.json" --absent bad8 -- run bodice.obj -o bad8 --sketch short-sketch.json
expect_error 64 "--seam-allowance" --absent bad11 -- run bodice.obj -o bad11 --seam-allowance 1e300
expect_error 64 "--hem-allowance" --absent bad12 -- run bodice.obj -o bad12 --hem-allowance 101
expect_error 64 "--outputs" --absent bad9 -- run bodice.obj -o bad9 --outputs svg,pdfx
expect_error 64 "--max-seam-mismatch" --absent bad10 -- run bodice.obj -o bad10 --max-seam-mismatch -0.1
expect_error 64 "--min-piece-width" --absent bad11 -- run bodice.obj -o bad11 --min-piece-width -1
expect_error 64 "--min-piece-area" --absent bad12 -- run bodice.obj -o bad12 --min-piece-area 0.6
expect_error 64 "--min-dart-intake" --absent bad13 -- run bodice.obj -o bad13 --min-dart-intake 6mm
expect_error 64 "--strict" --absent bad14 -- run bodice.obj -o bad14 --strict=yes

# --strict: a pattern that misses its goals exits 3 (docs/cli.md) once its files are written, with one line
# naming why; one that meets them exits 0. Without --strict the same run exits 0.
run run bodice.obj -o strict-miss --max-seam-mismatch 1e-9 --strict --quiet
check "run --strict, goals not met: exit $rc, expected 3" [ "$rc" -eq 3 ]
check "run --strict, goals not met: stderr is not one line 'panelize: run: goals not met (--strict): ...': \
$(head -c 300 "$WORK/err")" grep -q '^panelize: run: goals not met (--strict): [0-9]* of [0-9]* panels miss' "$WORK/err"
check "run --strict, goals not met: stderr has more than one line" one_line "$WORK/err"
[ -s strict-miss/report.json ] && report_checks "run --strict, goals not met" strict-miss \
    "goals_met is not false" "d['summary']['goals_met'] is False"
check "run --strict, goals not met: no report.json" [ -s strict-miss/report.json ]
run run bodice.obj -o strict-met --strict --quiet
expect_ok "run --strict, goals met"
run run bodice.obj -o lenient-miss --max-seam-mismatch 1e-9 --quiet
expect_ok "run without --strict, goals not met"

# --outputs: exactly the files asked for.
run run bodice.obj -o some --outputs dxf,layout,json --quiet
expect_ok "run --outputs dxf,layout,json"
check "run --outputs dxf,layout,json wrote $(ls some | tr '\n' ' ')" \
    [ "$(ls some | tr '\n' ' ')" = "layout.obj pattern.dxf report.json " ]

# The seam-length goal is judged: no flattening keeps every seam within 1e-9.
run run bodice.obj -o exact-seams --max-seam-mismatch 1e-9 --quiet
expect_ok "run --max-seam-mismatch 1e-9"
report_checks "run --max-seam-mismatch 1e-9" exact-seams \
    "goals met with seams 1e-9 apart" "d['summary']['goals_met'] is False" \
    "the reasons do not name the seams" "'seam mismatch' in d['summary']['goals_reasons']" \
    "the goal is not in the report" "d['segmentation']['max_seam_mismatch'] == 1e-9"

# Ctrl-C (SIGINT) stops a run: exit 130, one line, nothing written. The signal goes once the field is
# done (its note is on stderr), in the middle of the segmentation of a 50K-face bodice (seconds of work).
"$BIN" generate bodice -o big.obj --faces 50000 --quiet
"$BIN" run big.obj -o interrupted --prepare off >"$WORK/out" 2>"$WORK/err" &
pid=$!
for _ in $(seq 600); do grep -q 'run: field:' "$WORK/err" && break; sleep 0.1; done
kill -INT $pid
wait $pid
rc=$?
check "run interrupted: exit $rc, expected 130 ($(tail -c 300 "$WORK/err"))" [ "$rc" -eq 130 ]
check "run interrupted: the last line is not 'cancelled': $(tail -n 1 "$WORK/err")" \
    grep -q 'cancelled' <(tail -n 1 "$WORK/err")
check "run interrupted: wrote files" [ ! -e interrupted ]
check "run interrupted: left a temporary file" no_temporaries

# A mesh the automatic preparation repairs (one face turned the wrong way: the counts stay) is flattened,
# not refused as the repair had never happened.
python3 - <<'PY'
lines = open('bodice.obj').read().split('\n')
faces = [i for i, line in enumerate(lines) if line.startswith('f ')]
p = lines[faces[10]].split()
lines[faces[10]] = ' '.join([p[0], p[1], p[3], p[2]])
open('flipped.obj', 'w').write('\n'.join(lines))
PY
run run flipped.obj -o flipped-out --quiet
check "run of a mesh with one flipped face: exit $rc ($(head -c 300 "$WORK/err"))" [ "$rc" -eq 0 ]

# Poses that cannot be the same garment are refused (exit 65, naming the pose), not repaired: a
# non-finite coordinate, or a pose in other units (ten times the rest pose's size).
python3 - <<'PY'
rest = [l for l in open('bodice.obj').read().split('\n')]
def write(name, change):
    out = []
    seen = 0
    for line in rest:
        if line.startswith('v '):
            x, y, z = map(float, line.split()[1:4])
            out.append(change(seen, x, y, z))
            seen += 1
        else:
            out.append(line)
    open(name, 'w').write('\n'.join(out))
write('pose-nan.obj', lambda i, x, y, z: 'v %r %r %r' % (float('nan') if i == 5 else x, y, z))
write('pose-cm.obj', lambda i, x, y, z: 'v %r %r %r' % (10 * x, 10 * y, 10 * z))
PY
expect_error 65 "pose 1: vertex 5" --absent posebad1 -- run bodice.obj --pose pose-nan.obj -o posebad1
expect_error 65 "pose 1 is" --absent posebad2 -- run bodice.obj --pose pose-cm.obj -o posebad2

# A valid mesh too coarse for the automatic preparation's density (a two-triangle strip) is kept as it
# is and flattened: no usage error the user did not make.
printf 'v 0 0 0\nv 1000 0 0\nv 1000 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n' >strip.obj
run run strip.obj -o strip-out --quiet
check "run of a two-triangle strip: exit $rc ($(head -c 300 "$WORK/err"))" [ "$rc" -eq 0 ]

finish
