# tests/batch/lib_garments.sh -- small generated garments for the batch tests; sourced after
# tests/cli/lib.sh (not a test itself: its name does not match test_*.sh).
#
#     make_garments DIR COUNT [BROKEN]: COUNT garments of 600-900 faces named g00.obj, g01.obj, ...
#     (every generator shape in turn, the size varying), and with BROKEN a DIR/BROKEN.obj that
#     reads but has no faces (a garment that fails with exit category "data").
#
# SPDX-License-Identifier: GPL-3.0-or-later

GARMENT_SHAPES=(cylinder cone hemisphere quarter-sphere saddle sleeve skirt)

make_garments() {
    local dir=$1 count=$2 broken=${3:-} i shape
    mkdir -p "$dir"
    for ((i = 0; i < count; ++i)); do
        shape=${GARMENT_SHAPES[i % ${#GARMENT_SHAPES[@]}]}
        "$BIN" generate "$shape" -o "$dir/$(printf 'g%02d' "$i").obj" --faces $((600 + 50 * (i % 7))) --quiet ||
            return 1
    done
    if [ -n "$broken" ]; then
        printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\n' >"$dir/$broken.obj"
    fi
}

# summary_field FILE NAME FIELD: a garment's field in a summary.jsonl ("" when null, "missing" when absent).
summary_field() {
    python3 - "$@" <<'PY'
import json, sys
path, name, field = sys.argv[1:4]
for line in open(path):
    row = json.loads(line)
    if row["name"] == name:
        value = row.get(field, "missing")
        print("" if value is None else str(value).lower() if isinstance(value, bool) else value)
        break
else:
    print("missing")
PY
}
