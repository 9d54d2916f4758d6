# tests/cli/lib.sh -- the helpers every CLI test shares; sourced, not run
# (its name must not match test_*.sh, which CMake takes for a test):
#
#     source "$(dirname "$0")/lib.sh"
#
# On sourcing: finds the binary ($PZ_BINARY, else $PZ_BUILD_DIR/panelize,
# else build/panelize) and skips the test (exit 77) without one, then makes a
# scratch directory $WORK (removed on exit) and changes into it.
# A test ends with `finish`, which prints "N passed, M failed" and fails when
# anything did; a part that cannot run here (its data or a tool missing) calls
# `skip_part WHY`, and `finish` then exits 77 (ctest's skip) unless a check
# failed, so the test shows as skipped rather than passed.
#
# SPDX-License-Identifier: GPL-3.0-or-later

BIN=${PZ_BINARY:-${PZ_BUILD_DIR:-build}/panelize}
if [ ! -x "$BIN" ]; then
    echo "SKIPPED: no panelize binary at $BIN"
    exit 77
fi
case $BIN in /*) ;; *) BIN=$PWD/$BIN ;; esac # still found after the cd below
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
cd "$WORK" || exit 1

# ------------------------------------------------------------------ counting
passed=0
failed=0
parts_skipped=0
pass() { passed=$((passed + 1)); }
fail() { failed=$((failed + 1)); echo "FAIL: $*"; }
skip_part() { parts_skipped=$((parts_skipped + 1)); echo "SKIPPED part: $*"; }
check() { # check DESCRIPTION COMMAND...: passes when the command succeeds
    local what=$1; shift
    if "$@"; then pass; else fail "$what"; fi
}

# finish: the summary line; the script's last command, so its status is the test's
# (1 when a check failed, else 77 when a part was skipped, else 0).
finish() {
    if [ "$parts_skipped" -eq 0 ]; then
        echo "$passed passed, $failed failed"
    else
        echo "$passed passed, $failed failed, $parts_skipped skipped part(s)"
    fi
    [ "$failed" -eq 0 ] || return 1
    [ "$parts_skipped" -eq 0 ] || return 77
}

# ------------------------------------------------------------------ running panelize
# run ARGS...: runs panelize, stdout in $WORK/out, stderr in $WORK/err, exit code in $rc.
run() { "$BIN" "$@" >"$WORK/out" 2>"$WORK/err"; rc=$?; }

# expect_ok WHAT: the last run exited 0.
expect_ok() { check "$1: exit $rc ($(head -c 300 "$WORK/err"))" [ "$rc" -eq 0 ]; }

# ------------------------------------------------------------------ predicates for check
one_line() { [ "$(wc -l <"$1")" -eq 1 ]; }
differ() { ! cmp -s "$1" "$2"; }
no_temporaries() { [ -z "$(find "$WORK" -name '*.tmp-*' -print -quit)" ]; }

# expect_error CODE NAME [--absent FILE]... -- ARGS...: the run fails with CODE,
# one stderr line "panelize: ...NAME...", nothing on stdout, FILEs absent, no
# temporaries (the error contract of docs/cli.md).
expect_error() {
    local code=$1 name=$2 what
    shift 2
    local absent=()
    while [ "$1" != "--" ]; do absent+=("$2"); shift 2; done
    shift
    what="panelize $*"
    run "$@"
    check "$what: exit $rc, expected $code" [ "$rc" -eq "$code" ]
    check "$what: stderr is not one line: $(cat "$WORK/err")" one_line "$WORK/err"
    check "$what: stderr does not start with 'panelize: '" grep -q '^panelize: ' "$WORK/err"
    check "$what: stderr does not name '$name': $(cat "$WORK/err")" grep -qF -- "$name" "$WORK/err"
    check "$what: wrote to stdout" [ ! -s "$WORK/out" ]
    check "$what: left a temporary file" no_temporaries
    local file
    for file in "${absent[@]}"; do
        check "$what: left $file behind" [ ! -e "$file" ]
    done
}

# ------------------------------------------------------------------ JSON output
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

# json_true EXPR [FILE]: evaluates a Python expression over a JSON file (bound
# to d; json imported), by default the last run's stdout. For check.
# report_checks WHAT DIR DESCRIPTION EXPR...: json_checks over DIR/report.json.
report_checks() {
    local what=$1 dir=$2
    shift 2
    cp "$dir/report.json" "$WORK/out"
    json_checks "$what" "$@"
}

json_true() {
    python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); sys.exit(0 if eval(sys.argv[2]) else 1)' \
        "${2:-$WORK/out}" "$1" 2>/dev/null
}
