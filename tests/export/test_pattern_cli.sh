#!/bin/bash
# tests/export/test_pattern_cli.sh -- pattern.svg and pattern.dxf through
# `panelize flatten` (the export options of the CLI reach the writers):
#  - a generated skirt (one panel, opened by a self-seam; a wide fabric so the
#    marker takes it): pattern.svg renders (rsvg-convert) and is as large as
#    its mm size says at 1 px/mm;
#  - --seam-allowance 15 --hem-allowance 25: the DXF's cut line (layer 1) lies
#    15 or 25 mm outside the sew line (layer 14) at its vertices, read with
#    ezdxf; --dxf-strict: no TABLES section, 7-bit ASCII, audit() clean;
#  - --notch-spacing 50: about twice the notches of the default 100 mm;
#  - --allowances FILE: the seam it names gets its allowance (read back from
#    the DXF); a bad line is exit 65 naming the file and line, and no
#    pattern file is left behind;
#  - an output folder that cannot be written: exit 73, one line naming it,
#    no file left: a read-only folder (a read-only tmpfs in a private mount
#    namespace, which stops root too; chmod 555 when that is not allowed and
#    we are not root), and a disk that fills up half-way through the files
#    (a small tmpfs), for `flatten` and `run`.
# Readers that are missing (rsvg-convert, /usr/bin/python3 + ezdxf), and the
# unwritable-folder checks where nothing can stop the writes (root without
# mount namespaces), skip (exit 77 when nothing failed); with CI=true a skip
# fails the test.
#
# SPDX-License-Identifier: GPL-3.0-or-later
# fontconfig (cairo, pattern.pdf) keeps its caches until exit: not a leak of ours (sanitizer builds).
export LSAN_OPTIONS="suppressions=$(cd "$(dirname "$0")" && pwd)/lsan-fontconfig.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
here=$(cd "$(dirname "$0")" && pwd)
source "$here/../cli/lib.sh"

# A check that cannot run here: a skipped part (the test exits 77), and a failure under CI=true (CI must
# run every check).
skipped() {
    if [ "${CI:-}" = true ]; then
        fail "$1 skipped, not allowed with CI=true"
    else
        skip_part "$1"
    fi
}

run generate skirt -o skirt.obj --faces 2000 --quiet
expect_ok "generate skirt"
run flatten skirt.obj -o plain --quiet --fabric-width 4000
expect_ok "flatten skirt"
check "pattern.svg written" test -s plain/pattern.svg
check "pattern.dxf written" test -s plain/pattern.dxf

if command -v rsvg-convert >/dev/null; then
    check "rsvg-convert renders pattern.svg" rsvg-convert --dpi-x 25.4 --dpi-y 25.4 -o plain.png plain/pattern.svg
    width_mm=$(grep -o 'width="[0-9.]*mm"' plain/pattern.svg | head -1 | tr -dc '0-9.')
    width_px=$(od -An -j16 -N4 -tu1 plain.png | awk '{print $1 * 16777216 + $2 * 65536 + $3 * 256 + $4}')
    check "png is ${width_px} px for ${width_mm} mm" awk -v a="$width_px" -v b="$width_mm" \
        'BEGIN { d = a - b; exit !(d < 1.5 && d > -1.5) }'
else
    skipped "rendering (rsvg-convert not installed)"
fi

run flatten skirt.obj -o strict --quiet --fabric-width 4000 --seam-allowance 15 --hem-allowance 25 --dxf-strict
expect_ok "flatten --dxf-strict"
check "strict: no TABLES" bash -c '! grep -qx "TABLES" strict/pattern.dxf'
check "strict: 7-bit ASCII" bash -c '! LC_ALL=C grep -q "[^[:print:][:space:]]" strict/pattern.dxf'

if /usr/bin/python3 -c 'import ezdxf' 2>/dev/null; then
    check "ezdxf: allowances 15/25 mm, audit clean" env PYTHONPATH="$here" /usr/bin/python3 - strict/pattern.dxf <<'PY'
import math, sys
import ezdxf
from sew_distance import distance_to_loop  # tests/export, on PYTHONPATH
doc = ezdxf.readfile(sys.argv[1])
assert not doc.audit().has_errors
blocks = [b for b in doc.blocks if not b.name.startswith('*')]
assert blocks, 'no piece blocks'
for block in blocks:
    cut = [e for e in block if e.dxftype() == 'POLYLINE' and e.dxf.layer == '1' and e.is_closed]
    sew = [e for e in block if e.dxftype() == 'POLYLINE' and e.dxf.layer == '14' and e.is_closed]
    assert len(cut) == 1 and len(sew) == 1, block.name
    cut = [(v.dxf.location.x, v.dxf.location.y) for v in cut[0].vertices]
    sew = [(v.dxf.location.x, v.dxf.location.y) for v in sew[0].vertices]
    d = [distance_to_loop(p, sew) for p in cut]
    # every cut vertex: at least the seam allowance, at most the mitre limit of the hem allowance
    assert min(d) > 15 - 0.1 and max(d) < 2 * 25 + 0.1, (block.name, min(d), max(d))
    # both allowances occur
    assert any(abs(x - 15) < 0.1 for x in d) and any(abs(x - 25) < 0.1 for x in d), (block.name, sorted(d)[:3])
print('ok', len(blocks), 'blocks')
PY
else
    skipped "DXF read-back (ezdxf for /usr/bin/python3 not installed)"
fi

# --notch-spacing: half the spacing, about twice the notches (layer-4 LINEs of the DXF).
run flatten skirt.obj -o notch50 --quiet --fabric-width 4000 --notch-spacing 50
expect_ok "flatten --notch-spacing 50"
count_notches() { awk 'prev == "LINE" && $0 == "  8" { getline; if ($0 == "4") n++ } { prev = $0 } END { print n + 0 }' "$1"; }
notches_100=$(count_notches plain/pattern.dxf)
notches_50=$(count_notches notch50/pattern.dxf)
check "--notch-spacing 50: $notches_50 notches, $notches_100 at 100 mm" \
    awk -v a="$notches_50" -v b="$notches_100" 'BEGIN { exit !(b >= 4 && a >= 1.6 * b && a <= 2.4 * b) }'

# --allowances FILE: the skirt's one seam (panel 0 with itself) at 22 mm, the hem at the default 10.
printf '# panel panel mm\n0 0 22\n' >good.txt
run flatten skirt.obj -o seam22 --quiet --fabric-width 4000 --allowances good.txt
expect_ok "flatten --allowances good.txt"
if /usr/bin/python3 -c 'import ezdxf' 2>/dev/null; then
    check "ezdxf: the seam at 22 mm, the hem at 10" env PYTHONPATH="$here" /usr/bin/python3 - seam22/pattern.dxf <<'PY'
import math, sys
import ezdxf
from sew_distance import distance_to_loop  # tests/export, on PYTHONPATH
doc = ezdxf.readfile(sys.argv[1])
block = [b for b in doc.blocks if not b.name.startswith('*')][0]
cut = [e for e in block if e.dxftype() == 'POLYLINE' and e.dxf.layer == '1'][0]
sew = [e for e in block if e.dxftype() == 'POLYLINE' and e.dxf.layer == '14'][0]
sew = [(v.dxf.location.x, v.dxf.location.y) for v in sew.vertices]
d = [distance_to_loop((v.dxf.location.x, v.dxf.location.y), sew) for v in cut.vertices]
assert min(d) > 10 - 0.1 and any(abs(x - 22) < 0.1 for x in d) and any(abs(x - 10) < 0.1 for x in d), sorted(d)
PY
fi

printf '# bad\n0 1 x\n' >bad.txt
run flatten skirt.obj -o bad --quiet --fabric-width 4000 --allowances bad.txt
check "bad allowance file: exit 65 (got $rc)" [ "$rc" -eq 65 ]
check "bad allowance file: names file and line" grep -q "bad.txt: line 2" err
check "bad allowance file: no pattern files" bash -c '[ ! -e bad/pattern.svg ] && [ ! -e bad/pattern.dxf ]'

# ------------------------------------------------------------------ an output folder that cannot be written
# on_disk MOUNT_OPTIONS ARGS...: panelize ARGS with ./disk a fresh tmpfs mounted with MOUNT_OPTIONS (user and
# mount namespaces: no privileges needed, nothing outside changes); rc, out, err as `run`; what is left on
# the disk afterwards in ./disk.left. rc 200 when the namespace or the mount is refused.
on_disk() {
    local options=$1
    shift
    mkdir -p disk
    unshare -rm bash -c 'mount -t tmpfs -o "$1" tmpfs disk 2>/dev/null || exit 200; work=$2; shift 2
        "$@" >"$work/out" 2>"$work/err"; rc=$?; (cd disk && find . -mindepth 1) >"$work/disk.left"; exit $rc' \
        _ "$options" "$WORK" "$BIN" "$@" 2>/dev/null
    rc=$?
}

# expect_nothing_written WHAT PATH: exit 73, one stderr line naming PATH or the file that failed in it (the
# writers are given the file's name only), nothing left on the disk.
expect_nothing_written() {
    local files='garment\.obj|pattern\.svg|pattern\.dxf|pattern\.pdf|pattern-tiled\.pdf|marker\.svg|garment\.glb'
    files="$files|layout\.obj|report\.json|report\.html"
    check "$1: exit $rc, expected 73 ($(head -c 200 "$WORK/err"))" [ "$rc" -eq 73 ]
    check "$1: stderr is not one line naming $2 or a file in it: $(head -c 300 "$WORK/err")" \
        bash -c "[ \$(wc -l <'$WORK/err') -eq 1 ] && grep -Eq '^panelize: .*($2|$files)' '$WORK/err'"
    check "$1: left on the disk: $(head -c 300 "$WORK/disk.left")" [ ! -s "$WORK/disk.left" ]
}

on_disk ro true
if command -v unshare >/dev/null && [ "$rc" -ne 200 ]; then
    on_disk ro,size=4m flatten skirt.obj -o disk/out --quiet --fabric-width 4000
    expect_nothing_written "flatten into a read-only folder" disk/out
    # A disk a quarter or three quarters the size of the files (plain/: the same run) fills up half-way:
    # every file written before the one that fails must go again.
    total_kb=$(du -sk plain | cut -f1)
    for size in $((total_kb / 4))k $((total_kb * 3 / 4))k; do
        on_disk size=$size flatten skirt.obj -o disk/out --quiet --fabric-width 4000
        expect_nothing_written "flatten onto a $size disk (the files take ${total_kb}k)" disk/out
    done
    on_disk size=$((total_kb / 2))k run skirt.obj -o disk/run --quiet --fabric-width 4000
    expect_nothing_written "run onto a $((total_kb / 2))k disk" disk/run
elif [ "$(id -u)" -ne 0 ]; then
    echo "note: no private mount namespace here: chmod 555 instead (no full-disk case)"
    mkdir -p locked && chmod 555 locked
    expect_error 73 locked --absent locked/out -- flatten skirt.obj -o locked/out --fabric-width 4000
    check "a read-only folder got files: $(ls -A locked)" [ -z "$(ls -A locked)" ]
    chmod 755 locked
else
    skipped "unwritable-folder checks (root without mount namespaces: nothing stops root)"
fi
finish
