#!/usr/bin/env bash
# bench/hostile_measure.sh [PANELIZE] [CASE-REGEX] -- every hostile case of
# tests/hostile/cases.txt run once under /usr/bin/time: exit code, wall time,
# peak resident memory and the input file's size, one line per case (the
# figures of docs/reliability.md). A case is stopped after $PZ_HOSTILE_LIMIT
# seconds (default 120; its time then reads ">LIMIT", its memory "-").
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
bin=$(realpath "${1:-$root/build/panelize}")
pattern=${2:-.}
limit=${PZ_HOSTILE_LIMIT:-120}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
source "$root/tests/hostile/corpus.sh"
hostile_corpus "$bin" "$work" || exit 1
mkdir "$work/out"
printf '%-22s %5s %9s %9s %9s  %s\n' case exit seconds peak_MB file_MB "stderr"
while IFS= read -r line; do
  hostile_args "$line" "$work/out" || continue
  [[ "$NAME" =~ $pattern ]] || continue
  size=0
  [ -f "${ARGS[0]}" ] && size=$(stat -Lc %s "${ARGS[0]}")
  /usr/bin/time -f '%e %M' -o "$work/time" timeout -s KILL "$limit" "$bin" "$COMMAND" "${ARGS[@]}" --quiet \
    >/dev/null 2>"$work/err" </dev/null
  rc=$?
  read -r seconds kb < <(tail -n 1 "$work/time")
  megabytes=$(echo "${kb:-0}/1024" | bc -l)
  if [ "$rc" -eq 137 ]; then seconds=">$limit" megabytes=-; else megabytes=$(printf '%.1f' "$megabytes"); fi
  printf '%-22s %5s %9s %9s %9.2f  %s\n' "$NAME" "$rc" "$seconds" "$megabytes" "$(echo "$size/1048576" | bc -l)" \
    "$(head -c 150 "$work/err" | tr '\n' ' ')"
  rm -rf "$work/out" 2>/dev/null; mkdir "$work/out"
done <"$HOSTILE_CASES"
