#!/usr/bin/env bash
# tests/hostile/test_hostile.sh -- every case of tests/hostile/cases.txt
# (issue 15: hostile and mistaken input; docs/reliability.md) run through its
# command on a corpus made now (tests/hostile/make_corpus.py, nothing large
# committed). Each case must:
#  - end with its expected exit code, within $PZ_HOSTILE_LIMIT seconds (a hang
#    detector, not a speed goal: 300 by default; bench/hostile_measure.sh
#    gives the times);
#  - on failure, print exactly one stderr line "panelize: ..." (no progress
#    before an early error) and leave nothing: no output folder or file, no
#    hidden temporary folder, no probe, no `.tmp`;
#  - leave its inputs untouched (the garment, the file given as -o).
# PZ_HOSTILE_ONLY=REGEX runs only the cases whose names match.
# SPDX-License-Identifier: GPL-3.0-or-later
here=$(cd "$(dirname "$0")" && pwd) # lib.sh changes into a scratch folder
source "$here/../cli/lib.sh"
source "$here/corpus.sh"
limit=${PZ_HOSTILE_LIMIT:-300}

if ! command -v python3 >/dev/null; then
    echo "SKIPPED: no python3 to make the corpus"
    exit 77
fi
hostile_corpus "$BIN" "$WORK" || { echo "FAIL: could not make the corpus"; exit 1; }
mkdir "$WORK/out"
inputs_sum() { cat "$G" "$C/empty.obj" | md5sum; }
before=$(inputs_sum)
leftovers() { find "$WORK" \( -name '*.tmp-*' -o -name '*.tmp' -o -name '*probe*' -o -name '.out*' \) -print; }

while IFS= read -r line; do
    hostile_args "$line" "$WORK/out" || continue
    [[ -n "${PZ_HOSTILE_ONLY:-}" && ! "$NAME" =~ $PZ_HOSTILE_ONLY ]] && continue
    start=$(date +%s%N)
    timeout -s KILL "$limit" "$BIN" "$COMMAND" "${ARGS[@]}" >"$WORK/stdout" 2>"$WORK/err" </dev/null
    rc=$?
    ms=$(( ($(date +%s%N) - start) / 1000000 ))
    echo "$NAME: exit $rc, $ms ms"
    check "$NAME: ran past the ${limit} s limit (a hang)" [ "$rc" -ne 137 ]
    check "$NAME: exit $rc, expected $EXPECTED: $(head -c 300 "$WORK/err")" [ "$rc" -eq "$EXPECTED" ]
    if [ "$EXPECTED" -ne 0 ]; then
        check "$NAME: stderr is not one line: $(head -c 600 "$WORK/err")" one_line "$WORK/err"
        check "$NAME: stderr does not start with 'panelize: '" grep -q '^panelize: ' "$WORK/err"
        check "$NAME: left an output behind" [ ! -e "$O" ] && [ ! -e "$O.obj" ]
        check "$NAME: an empty output file or folder was left" [ -z "$(ls -A "$WORK/out")" ]
    fi
    check "$NAME: left temporaries: $(leftovers | head -3)" [ -z "$(leftovers)" ]
    check "$NAME: changed an input" [ "$(inputs_sum)" = "$before" ]
    rm -rf "$WORK/out" && mkdir "$WORK/out"
done <"$HOSTILE_CASES"
finish
