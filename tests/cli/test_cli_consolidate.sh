#!/usr/bin/env bash
# tests/cli/test_cli_consolidate.sh -- consolidation (docs/run.md, "Consolidation"): once the layout of a
# garment with a mirror plane meets its goals, `panelize run` makes it again with a budget of one piece fewer
# and keeps that pattern when it meets every goal too and has no more seam on the mirror plane.
#
# On generated garments: the 6K skirt's layout of 4 pieces becomes 3 meeting every goal (report.json says it
# came from 4; `--consolidate off` keeps 4); the 6K bodice's budget layout would cut it into left and right
# halves (a centre front and back where it had side seams: more seam on the plane), so its first layout
# stands, as with `--consolidate off`; goals stricter than the defaults (laid out over the ladder of looser
# ones, docs/segment.md "Monotone panel counts") and piece budgets are never consolidated; a bad value is
# exit 64.
source "$(dirname "$0")/lib.sh"

panel_count() { python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["summary"]["panel_count"])' "$1"; }

run generate skirt -o skirt.obj --faces 6000
expect_ok "generate skirt"
run generate bodice -o bodice.obj --faces 6000
expect_ok "generate bodice"

run run skirt.obj -o skirt-on
expect_ok "run skirt (consolidation on)"
check "run skirt: no note that the consolidated layout is kept: $(grep consolidation "$WORK/err")" \
    grep -q "^panelize: run: consolidation: the layout of at most 3 pieces has [0-9]*, every goal met .*: kept$" "$WORK/err"
run run skirt.obj -o skirt-off --consolidate off --quiet
expect_ok "run skirt --consolidate off"
check "--consolidate off still consolidated: $(grep consolidation "$WORK/err")" sh -c '! grep -q consolidation "$1"' _ "$WORK/err"
off=$(panel_count skirt-off/report.json)
report_checks "run skirt (consolidation on)" skirt-on \
    "not fewer pieces than the first layout, or not every goal met: $(grep -o '"consolidated_from":[^,]*' skirt-on/report.json), $(grep -o '"panel_count":[^,]*' skirt-on/report.json | head -1)" \
    "d['segmentation']['consolidated_from'] == $off and d['summary']['panel_count'] < $off and d['summary']['goals_met'] is True" \
    "the report shows a piece budget nobody asked for" "'max_pieces' not in d['segmentation']" \
    "the trade-off needs more pieces at S = 0.05 than the pattern has" \
    "[t['pieces'] for t in d['tradeoff'] if t['max_strain'] == 0.05] == [d['summary']['panel_count']]"

run run bodice.obj -o bodice-on
expect_ok "run bodice (consolidation on)"
check "run bodice: not refused for more seam on the mirror plane: $(grep consolidation "$WORK/err")" \
    grep -q "consolidation: .*more seam on the mirror plane.*: the first stands" "$WORK/err"
run run bodice.obj -o bodice-off --consolidate off --quiet
expect_ok "run bodice --consolidate off"
check "run bodice: the refused consolidation changed the pattern" \
    cmp -s <(python3 -c 'import json,sys; r=json.load(open(sys.argv[1])); print([p["faces"] for p in r["panels"]])' bodice-on/report.json) \
    <(python3 -c 'import json,sys; r=json.load(open(sys.argv[1])); print([p["faces"] for p in r["panels"]])' bodice-off/report.json)

run run skirt.obj -o skirt-strict --max-strain 0.045 --quiet
expect_ok "run skirt --max-strain 0.045"
report_checks "run skirt --max-strain 0.045" skirt-strict \
    "goals stricter than the defaults were consolidated" "'consolidated_from' not in d['segmentation']" \
    "a stricter S gave fewer pieces than the default's consolidated pattern" \
    "d['summary']['panel_count'] >= $(panel_count skirt-on/report.json)"
run run skirt.obj -o skirt-budget --max-pieces 4 --quiet
expect_ok "run skirt --max-pieces 4"
report_checks "run skirt --max-pieces 4" skirt-budget "a piece budget was consolidated" "'consolidated_from' not in d['segmentation']"

expect_error 64 "--consolidate" --absent bad -- run skirt.obj -o bad --consolidate maybe

finish
