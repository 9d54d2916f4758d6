#!/usr/bin/env bash
# tests/cli/test_cli_generate.sh -- `panelize generate` for every shape, the
# help and version texts, and the option syntax (--opt value, --opt=value,
# options before or after the positional argument).
#
# SPDX-License-Identifier: GPL-3.0-or-later
set -u

BIN=${PZ_BINARY:-${PZ_BUILD_DIR:-build}/panelize}
if [ ! -x "$BIN" ]; then
    echo "SKIPPED: no panelize binary at $BIN"
    exit 77
fi
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
cd "$WORK" || exit 1

passed=0
failed=0
pass() { passed=$((passed + 1)); }
fail() { failed=$((failed + 1)); echo "FAIL: $*"; }
check() { # check DESCRIPTION COMMAND...: passes when the command succeeds
    local what=$1; shift
    if "$@"; then pass; else fail "$what"; fi
}

# run ARGS...: runs panelize, stdout in $WORK/out, stderr in $WORK/err, exit code in $rc.
run() { "$BIN" "$@" >"$WORK/out" 2>"$WORK/err"; rc=$?; }

# json_checks WHAT DESCRIPTION EXPR [DESCRIPTION EXPR]...: evaluates each Python
# expression over the JSON on stdout (bound to d; json and re imported) in ONE
# interpreter run, since starting python3 costs more than the runs under test.
json_checks() {
    local what=$1 line
    shift
    while read -r line; do
        case $line in
            PASS) pass ;;
            *) fail "$what: ${line#FAIL }" ;;
        esac
    done < <(python3 - "$WORK/out" "$@" <<'PY'
import json, re, sys
try:
    d = json.load(open(sys.argv[1]))
except Exception as error:
    d = None
    print("FAIL stdout is not JSON: %s" % error)
pairs = sys.argv[2:]
for description, expression in zip(pairs[0::2], pairs[1::2]):
    try:
        ok = d is not None and bool(eval(expression))
    except Exception:
        ok = False
    print("PASS" if ok else "FAIL " + description)
PY
)
}

# json_true EXPR: evaluates a Python expression over the JSON on stdout (bound to d).
json_true() {
    python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); sys.exit(0 if eval(sys.argv[2]) else 1)' \
        "$WORK/out" "$1" 2>/dev/null
}

expect_ok() { check "$1: exit $rc ($(head -c 300 "$WORK/err"))" [ "$rc" -eq 0 ]; }
one_line() { [ "$(wc -l <"$1")" -eq 1 ]; }
no_temporaries() { [ -z "$(find "$WORK" -name '*.tmp-*' -print -quit)" ]; }

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

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
