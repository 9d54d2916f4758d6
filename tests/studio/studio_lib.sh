# tests/studio/studio_lib.sh -- helpers of the studio's tests; sourced after tests/cli/lib.sh (not run:
# its name must not match test_*.sh).
#
#   start_studio ARGS...   starts `panelize studio --port 0 ARGS...` in the background; sets $URL (the
#                          printed address) and $STUDIO_PID; fails the test when it does not come up
#   api METHOD PATH [BODY [TYPE]]  one request with curl: the answer in $WORK/body, the code in $code
#   json EXPR              evaluates a Python expression on the last answer `d`
#   wait_run ID RUN        polls the status until run RUN of garment ID is over; prints its state
#
# The server is stopped (SIGTERM) when the test exits.
#
# SPDX-License-Identifier: GPL-3.0-or-later

STUDIO_PID=
stop_studio() {
    if [ -n "$STUDIO_PID" ]; then
        kill -TERM "$STUDIO_PID" 2>/dev/null
        wait "$STUDIO_PID" 2>/dev/null
        studio_rc=$?
        STUDIO_PID=
    fi
}
trap 'stop_studio; rm -rf "$WORK"' EXIT

if ! command -v curl >/dev/null; then
    echo "SKIPPED: curl is missing (scripts/install-deps.sh installs it)"
    exit 77
fi

start_studio() {
    "$BIN" studio --port 0 "$@" >"$WORK/studio.out" 2>"$WORK/studio.err" &
    STUDIO_PID=$!
    URL=
    local i
    for i in $(seq 1 100); do
        URL=$(sed -n 's/^panelize studio: \(http[^ ]*\)$/\1/p' "$WORK/studio.out")
        [ -n "$URL" ] && return 0
        kill -0 "$STUDIO_PID" 2>/dev/null || break
        sleep 0.1
    done
    echo "FAIL: the studio did not start: $(cat "$WORK/studio.err")"
    exit 1
}

api() {
    local method=$1 path=$2 body=${3-} type=${4:-application/json}
    if [ -n "$body" ]; then
        code=$(curl -s -m 60 -o "$WORK/body" -w '%{http_code}' -X "$method" -H "Content-Type: $type" \
            --data-binary "$body" "$URL${path#/}")
    else
        code=$(curl -s -m 60 -o "$WORK/body" -w '%{http_code}' -X "$method" "$URL${path#/}")
    fi
}

json() { python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))' "$WORK/body" "$1"; }

wait_run() {
    local id=$1 run=$2 i state
    for i in $(seq 1 600); do
        api GET "/api/garments/$id/status"
        state=$(json "d['state'] if d['run'] == $run else 'other'")
        case $state in done | failed | cancelled) echo "$state"; return 0 ;; esac
        sleep 0.1
    done
    echo "timeout"
}
