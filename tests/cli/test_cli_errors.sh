#!/usr/bin/env bash
# tests/cli/test_cli_errors.sh -- every way a panelize run can fail, and the
# invalid meshes `info` must describe rather than refuse.
#
# Each failing run must: exit with the documented code (64 usage, 65 bad or
# invalid data, 66 missing input, 73 cannot create output), print exactly one
# line on stderr, starting "panelize: " and naming the file or option at
# fault, and leave no output file and no temporary (*.tmp-*) behind.
#
# SPDX-License-Identifier: GPL-3.0-or-later
set -u

source "$(dirname "$0")/lib.sh"

# expect_described FILE KEYWORD: info exits 0 and reports the mesh as not
# manifold, with a problem mentioning KEYWORD (a Python regex, case-insensitive).
expect_described() {
    local file=$1 keyword=$2
    run info "$file" --json --quiet
    check "info $file: exit $rc, expected 0 ($(cat "$WORK/err"))" [ "$rc" -eq 0 ]
    json_checks "info $file" \
        "manifold should be false" 'd["manifold"] is False' \
        "no problem matching '$keyword'" "any(re.search(r'$keyword', p, re.I) for p in d['problems'])" \
        "genus should be unknown (null)" 'd["genus"] is None and d["boundary_loops"] is None' \
        "counts should still be reported" 'd["faces"] > 0 and d["components"] >= 1 and d["edges"] > 0'
}

# ------------------------------------------------------------------ unreadable inputs
: >empty.obj
expect_error 65 empty.obj -- info empty.obj
: >empty.ply
expect_error 65 empty.ply -- info empty.ply
expect_error 66 missing.obj -- info missing.obj
expect_error 66 missing.obj -- check missing.obj

run generate cylinder -o cyl.ply --faces 600 --quiet
check "generate cylinder.ply failed: $(cat "$WORK/err")" [ "$rc" -eq 0 ]
size=$(wc -c <cyl.ply)
head -c $((size / 2)) cyl.ply >truncated.ply
expect_error 65 truncated.ply -- info truncated.ply
head -c $((size - 7)) cyl.ply >short.ply
expect_error 65 short.ply -- info short.ply

printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n' >range.obj
expect_error 65 range.obj -- info range.obj
expect_error 65 range.obj -- check range.obj

# ------------------------------------------------------------------ poses that do not fit
run generate cylinder -o rest.obj --faces 600 --quiet
run generate cylinder -o other.obj --faces 1200 --quiet
expect_error 65 other.obj -- info rest.obj --pose other.obj
check "mismatched pose message should name the rest file too: $(cat "$WORK/err")" grep -qF rest.obj "$WORK/err"
expect_error 66 nopose.obj -- info rest.obj --pose nopose.obj

# ------------------------------------------------------------------ outputs that cannot be created
expect_error 73 /nonexistent/dir/x.obj -- generate cylinder -o /nonexistent/dir/x.obj --faces 600
expect_error 73 /nonexistent/dir/x.glb -- generate bodice -o /nonexistent/dir/x.glb --faces 600 --poses 1
expect_error 73 nodir/x.ply --absent nodir -- generate hemisphere -o nodir/x.ply --faces 600
expect_error 73 nodir/x --absent nodir -- generate bodice -o nodir/x.obj --faces 600 --poses 2
# A pose file that cannot be written must take the already written ones with it.
mkdir blocked
mkdir blocked/b.pose2.obj # a directory where the second pose file should go
expect_error 73 b.pose2.obj --absent blocked/b.obj --absent blocked/b.pose1.obj -- \
    generate bodice -o blocked/b.obj --faces 600 --poses 2

# ------------------------------------------------------------------ usage errors
expect_error 64 frobnicate -- frobnicate x.obj
expect_error 64 --frobnicate -- info rest.obj --frobnicate
expect_error 64 --frobnicate -- --frobnicate
expect_error 64 --pose -- info rest.obj --pose
expect_error 64 abc --absent x.obj -- generate cylinder -o x.obj --faces abc
expect_error 64 12x --absent x.obj -- generate cylinder -o x.obj --faces=12x
expect_error 64 --poses --absent x.obj -- generate cylinder -o x.obj --poses -1
expect_error 64 furlong -- info rest.obj --units furlong
expect_error 64 --repair -- info rest.obj --repair
expect_error 64 --json -- info rest.obj --json=yes
expect_error 64 info -- info
expect_error 64 extra.obj -- info rest.obj extra.obj
expect_error 64 teapot --absent x.obj -- generate teapot -o x.obj
expect_error 64 -o -- generate cylinder
expect_error 64 x.stl --absent x.stl -- generate cylinder -o x.stl
expect_error 64 --open --absent x.obj -- generate bodice --open -o x.obj

# ------------------------------------------------------------------ meshes that parse but are invalid
square='v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n'
printf "${square}f 1 2 3\nf 1 3 4\n" >good.obj
printf "${square}f 1 2 3\nf 1 4 3\n" >flipped.obj
printf "${square}f 1 2 3\nf 1 3 4\nf 3 1 4\n" >duplicate.obj
# Edge 1-2 carries three faces (a fin): no repair can fix that.
printf "${square}v 0.5 -1 0\nv 0.5 0 1\nf 1 2 3\nf 1 3 4\nf 2 1 5\nf 1 2 6\n" >nonmanifold.obj
printf "${square}v 1 2 0\nf 1 2 3\nf 1 3 4\nf 3 2 5\n" >degenerate.obj
printf 'v 0 0 0\nv nan 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n' >nan.obj

expect_described flipped.obj 'orient|inconsistent'
expect_described duplicate.obj 'duplicate'
expect_described nonmanifold.obj 'non-?manifold'
expect_described degenerate.obj 'degenerate|zero.area'
expect_described nan.obj 'nan|finite'

for bad in flipped duplicate nonmanifold degenerate nan; do
    expect_error 65 $bad.obj -- check $bad.obj
done

run check good.obj --quiet
check "check good.obj: exit $rc ($(cat "$WORK/err"))" [ "$rc" -eq 0 ]
for fixable in flipped duplicate degenerate; do
    run check $fixable.obj --repair --quiet --json
    check "check $fixable.obj --repair: exit $rc ($(cat "$WORK/err"))" [ "$rc" -eq 0 ]
    check "check $fixable.obj --repair: not reported valid" json_true 'd["valid"] is True and d["faces"] == 2'
done
# A successful repair says what it did (on stderr, unless --quiet).
run check flipped.obj --repair
check "check flipped.obj --repair: exit $rc" [ "$rc" -eq 0 ]
check "check flipped.obj --repair: should note the flip on stderr" grep -qiE 'flip|orient' "$WORK/err"
run check flipped.obj --repair --quiet
check "check flipped.obj --repair --quiet: stderr should be empty" [ ! -s "$WORK/err" ]

# Repairs that happen before a mesh is refused must not add lines to the error.
printf "${square}v 0.5 -1 0\nv 0.5 0 1\nv 3 3 3\nf 1 2 3\nf 1 3 4\nf 2 1 5\nf 1 2 6\nf 1 2 6\n" >unfixable.obj
expect_error 65 nonmanifold.obj -- check nonmanifold.obj --repair
expect_error 65 unfixable.obj -- check unfixable.obj --repair

# Unreferenced vertices are a note, not a reason to call a mesh broken.
printf "${square}v 5 5 5\nf 1 2 3\nf 1 3 4\n" >unreferenced.obj
run info unreferenced.obj --json --quiet
check "info unreferenced.obj: exit $rc" [ "$rc" -eq 0 ]
check "info unreferenced.obj: should be manifold with the note listed" \
    json_true 'd["manifold"] is True and d["boundary_loops"] == 1 and len(d["problems"]) >= 1'
run check unreferenced.obj --quiet
check "check unreferenced.obj: exit $rc" [ "$rc" -eq 0 ]

# Inputs that are not regular files are refused at once (exit 66) instead of blocking for ever (a FIFO
# with no writer) or reading without end (/dev/zero), and a large file that is not what its name says is
# refused from its first bytes (exit 65) without being read whole.
mkfifo fifo.obj fifo-pose.obj fifo-sketch.json
expect_error 66 "fifo.obj" -- info fifo.obj
ln -s /dev/zero zero.obj
expect_error 66 "zero.obj" -- check zero.obj
printf "${square}f 1 2 3\nf 1 3 4\n" >ok.obj
expect_error 66 "fifo-pose.obj" -- info ok.obj --pose fifo-pose.obj
expect_error 66 "fifo-sketch.json" --absent sk -- run ok.obj -o sk --sketch fifo-sketch.json
truncate -s 200M sparse.ply
truncate -s 200M sparse.obj
truncate -s 200M sparse.glb
for sparse in sparse.ply sparse.obj sparse.glb; do
    expect_error 65 "$sparse" -- info $sparse
done

# A sketch far off the garment (other units, another garment, 1e306) is refused at once, naming the
# curve, the point and the distance; it used to hang the field's snapping.
"$BIN" generate bodice -o sk-bodice.obj --faces 2000 --quiet
printf '{"curves":[[[1e306,0,0],[0,1e306,0]]]}' >far-sketch.json
expect_error 65 "far-sketch.json: curve 0 point 0" --absent sk1 -- field sk-bodice.obj -o sk1 --sketch far-sketch.json
expect_error 65 "far-sketch.json: curve 0 point 0" --absent sk2 -- run sk-bodice.obj -o sk2 --sketch far-sketch.json
printf '{"curves":[[[0,0,0],[1700000,0,0]]]}' >km-sketch.json
expect_error 65 "km-sketch.json: curve 0" --absent sk3 -- run sk-bodice.obj -o sk3 --sketch km-sketch.json

finish
