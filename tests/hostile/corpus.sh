# tests/hostile/corpus.sh -- sourced (not a test: its name does not match
# test_*.sh) by tests/hostile/test_hostile.sh and bench/hostile_measure.sh:
#
#     hostile_corpus PANELIZE DIR
#
# makes the hostile corpus in DIR (a 7K-face bodice made by PANELIZE, then
# tests/hostile/make_corpus.py) and sets the variables tests/hostile/cases.txt
# names: C, G, FIFO, ZERO, LINK, ALIAS. hostile_args LINE OUTDIR then sets
# NAME, EXPECTED, COMMAND, O (OUTDIR/NAME) and ARGS (an array) from a line of
# cases.txt, returning 1 for a comment or a blank line.
#
# SPDX-License-Identifier: GPL-3.0-or-later

HOSTILE_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
HOSTILE_CASES=$HOSTILE_DIR/cases.txt

hostile_corpus() {
    local bin=$1 dir=$2
    C=$dir/corpus G=$dir/corpus/bodice.obj FIFO=$dir/fifo.obj ZERO=$dir/zero.ply LINK=$dir/link.obj
    ALIAS=$dir/corpus/../corpus/bodice.obj
    mkdir -p "$C" || return 1
    "$bin" generate bodice -o "$G" --faces 7000 --quiet || return 1
    python3 "$HOSTILE_DIR/make_corpus.py" "$C" || return 1
    python3 "$HOSTILE_DIR/make_corpus.py" "$C" "$G" || return 1
    mkfifo "$FIFO" && ln -s /dev/zero "$ZERO" && ln -s "$G" "$LINK"
}

hostile_args() {
    local line=$1 rest
    [[ -z "${line// /}" || "$line" == \#* ]] && return 1
    read -r NAME EXPECTED COMMAND rest <<<"$line"
    O=$2/$NAME
    eval "ARGS=($rest)"
}
