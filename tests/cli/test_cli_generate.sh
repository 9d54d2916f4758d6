#!/usr/bin/env bash
# tests/cli/test_cli_generate.sh -- `panelize generate` for every shape, the
# help and version texts, and the option syntax (--opt value, --opt=value,
# options before or after the positional argument).
#
# SPDX-License-Identifier: GPL-3.0-or-later
set -u

source "$(dirname "$0")/lib.sh"

# ------------------------------------------------------------------ version and help
run --version
expect_ok "--version"
check "--version should print 'panelize 0.1.0'" [ "$(cat "$WORK/out")" = "panelize 0.1.0" ]

run --help
expect_ok "--help"
for command in info check generate; do
    check "--help should list $command" grep -qE "^  $command " "$WORK/out"
done

run
check "no arguments: exit $rc, expected 64" [ "$rc" -eq 64 ]
check "no arguments: the usage goes to stderr" grep -q '^usage: panelize' "$WORK/err"
check "no arguments: nothing on stdout" [ ! -s "$WORK/out" ]

for command in info check generate; do
    run "$command" --help
    expect_ok "$command --help"
    check "$command --help: usage on stdout" grep -q "^usage: panelize $command" "$WORK/out"
    check "$command --help: nothing on stderr" [ ! -s "$WORK/err" ]
    run help "$command"
    check "help $command: usage on stdout" grep -q "^usage: panelize $command" "$WORK/out"
    # --help wins over arguments that would otherwise be an error.
    run "$command" --no-such-option --help
    check "$command --no-such-option --help: exit $rc" [ "$rc" -eq 0 ]
done

# ------------------------------------------------------------------ every shape
shapes="bodice skirt sleeve hemisphere quarter-sphere saddle cylinder cone"
run generate --help
for shape in $shapes; do
    check "generate --help should list $shape" grep -qE "^  $shape " "$WORK/out"
done

for shape in $shapes; do
    run generate "$shape" -o "$shape.obj" --faces 1000 --json --quiet
    expect_ok "generate $shape"
    cp "$WORK/out" "$shape.json"
    check "generate $shape: file written" test -s "$shape.obj"
    json_checks "generate $shape" \
        "JSON summary" \
        "d['file'] == '$shape.obj' and d['shape'] == '$shape' and d['poses'] == 0 and d['pose_files'] == []" \
        "face count near --faces 1000" "500 <= d['faces'] <= 2000 and d['vertices'] > 0"
    check "generate $shape --quiet: stderr should be empty" [ ! -s "$WORK/err" ]
    run check "$shape.obj" --quiet
    check "generated $shape should pass check: $(cat "$WORK/err")" [ "$rc" -eq 0 ]
done
check "no temporaries left by generate" no_temporaries

# ------------------------------------------------------------------ summary line, option syntax
run generate cylinder -o summary.glb --faces 800
expect_ok "generate cylinder (not quiet)"
check "summary: stdout should be empty without --json" [ ! -s "$WORK/out" ]
check "summary: one line on stderr" one_line "$WORK/err"
check "summary: names the file" grep -q '^panelize: .*summary.glb' "$WORK/err"

run generate --faces=800 --output=syntax.obj --quiet cylinder --open
expect_ok "--opt=value and the positional last"
check "--output=FILE should have been written" test -s syntax.obj
run info syntax.obj --json --quiet
check "--open cylinder: one boundary loop" json_true "d['boundary_loops'] == 1"

run generate cylinder -o big.obj --faces 4000 --json --quiet
check "--faces 4000 should give over twice the faces of --faces 1000" \
    json_true "d['faces'] > 2 * json.load(open('cylinder.json'))['faces']"

# Generating is deterministic: the same command gives the same bytes.
run generate skirt -o again.obj --faces 1000 --quiet
check "generate skirt twice should give identical files" cmp -s skirt.obj again.obj

# ------------------------------------------------------------------ poses
run generate sleeve --poses 3 -o sleeve3.obj --faces 800 --json --quiet
expect_ok "generate sleeve --poses 3 -o sleeve3.obj"
check "pose files listed in JSON" \
    json_true "d['poses'] == 3 and d['pose_files'] == ['sleeve3.pose1.obj', 'sleeve3.pose2.obj', 'sleeve3.pose3.obj']"
check "pose files exist" test -s sleeve3.pose1.obj -a -s sleeve3.pose2.obj -a -s sleeve3.pose3.obj
run generate sleeve --poses 3 -o sleeve3.glb --faces 800 --json --quiet
check "glb keeps poses inside" json_true "d['poses'] == 3 and d['pose_files'] == []"
check "no pose files for glb" test ! -e sleeve3.pose1.glb

finish
