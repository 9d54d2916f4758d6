#!/usr/bin/env bash
# tests/export/test_export_b_cli.sh -- the files of export helper B as
# `panelize flatten` writes them: pattern.pdf (one page), pattern-tiled.pdf
# (--paper letter: Letter pages, cover + tiles, all rendered by pdftoppm),
# marker.svg (--fabric-width and its rendering by rsvg-convert), garment.glb
# (a GLB), report.html (self-contained, the strain map and the tables) and
# report.json's marker object (--fabric-width, --gap), for a generated bodice
# and, when ../shared/data is there, the T-shirt's own panels (--panels uv).
# Poppler and rsvg checks are skipped when the tools are missing (a skipped
# part: exit 77; a failure with CI=true, where scripts/install-deps.sh
# installs them), as is the T-shirt without ../shared/data.
#
# SPDX-License-Identifier: GPL-3.0-or-later
source "$(dirname "$0")/../cli/lib.sh"

have() { command -v "$1" >/dev/null 2>&1; }
# need TOOL...: succeeds when every tool is here; else a skipped part (a failure under CI=true).
need() {
    local tool
    for tool in "$@"; do
        have "$tool" && continue
        if [ "${CI:-}" = true ]; then
            fail "$tool is not installed (required when CI=true)"
        else
            skip_part "the checks by $tool (not installed)"
        fi
        return 1
    done
    return 0
}
py=/usr/bin/python3
[ -x "$py" ] || py=python3

# json_value FILE EXPR: a Python expression over the parsed report `r`, printed.
json_value() { "$py" -c "import json,sys; r=json.load(open(sys.argv[1])); print($2)" "$1"; }

check_outputs() { # check_outputs DIR WIDTH: every file of this part in DIR
    local dir=$1 width=$2 f
    for f in pattern.pdf pattern-tiled.pdf marker.svg garment.glb report.html report.json; do
        check "$dir/$f written" [ -s "$dir/$f" ]
    done
    check "$dir/garment.glb is a GLB" [ "$(head -c 4 "$dir/garment.glb")" = "glTF" ]
    check "$dir/marker.svg: fabric width" grep -q "width=\"$width.00mm\"" "$dir/marker.svg"
    check "$dir/report.html: self-contained" bash -c "! grep -q 'http' '$dir/report.html'"
    check "$dir/report.html: strain map and tables" bash -c \
        "grep -q '<svg id=\"strain\"' '$dir/report.html' && grep -q '<table id=\"panels\">' '$dir/report.html'"
    check "$dir/report.json: marker width" [ "$(json_value "$dir/report.json" "r['marker']['fabric_width_mm']")" = "$width" ]
    check "$dir/report.json: marker efficiency in (0, 1]" \
        [ "$(json_value "$dir/report.json" "0 < r['marker']['efficiency'] <= 1 and r['marker']['length_mm'] > 0")" = True ]
    if need pdfinfo pdftoppm; then
        check "$dir/pattern.pdf: one page" bash -c "pdfinfo '$dir/pattern.pdf' | grep -q '^Pages: *1$'"
        check "$dir/pattern-tiled.pdf: Letter" bash -c "pdfinfo '$dir/pattern-tiled.pdf' | grep -q '612 x 792'"
        check "$dir/pattern-tiled.pdf: cover and tiles" \
            [ "$(pdfinfo "$dir/pattern-tiled.pdf" | sed -n 's/^Pages: *//p')" -ge 2 ]
        check "$dir: both PDFs render" bash -c \
            "pdftoppm -r 5 '$dir/pattern.pdf' '$dir/r' && pdftoppm -r 5 '$dir/pattern-tiled.pdf' '$dir/t'"
    fi
    if need rsvg-convert; then
        check "$dir/marker.svg renders" rsvg-convert -o "$dir/marker.png" "$dir/marker.svg"
    fi
}

run generate bodice -o bodice.obj --faces 3000 --quiet
expect_ok "generate bodice"
run flatten bodice.obj -o bodice --paper letter --fabric-width 1200 --gap 8 --quiet
expect_ok "flatten bodice"
check_outputs bodice 1200

data=${PZ_SHARED_DATA:-}
if [ -n "$data" ] && [ -f "$data/garments/diffavatar-tshirt.obj" ]; then
    run flatten "$data/garments/diffavatar-tshirt.obj" --panels uv -o tshirt --paper letter \
        --fabric-width 1500 --quiet
    expect_ok "flatten tshirt --panels uv"
    check_outputs tshirt 1500
    check "tshirt: 4 pieces in the marker" [ "$(json_value tshirt/report.json "r['marker']['pieces']")" = 4 ]
else
    skip_part "the T-shirt (no ../shared/data)"
fi
finish
