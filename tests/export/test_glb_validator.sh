#!/usr/bin/env bash
# tests/export/test_glb_validator.sh -- garment.glb passes the Khronos glTF
# validator with zero errors: the GLBs test_glb writes when PZ_GLB_OUT is set
# (a bodice in 4 panels with its marker texcoords and seam lines, and the
# same with a mirrored pair). The validator setup is that of
# tests/io/test_gltf_validator.sh (npm gltf-validator in .tools); without
# it the test is skipped (exit 77), except with CI=true.
#
# SPDX-License-Identifier: GPL-3.0-or-later
set -u

source "$(dirname "$0")/../gltf_validator_setup.sh"
if [ -z "$build_dir" ] || [ ! -x "$build_dir/test_glb" ]; then
    echo "FAIL: test_glb not found in PZ_BUILD_DIR='$build_dir'"
    exit 1
fi

work=$(mktemp -d "${TMPDIR:-/tmp}/pz_glb_validator.XXXXXX") || exit 1
trap 'rm -rf "$work"' EXIT
if ! PZ_GLB_OUT="$work" "$build_dir/test_glb" >"$work/test_glb.log" 2>&1; then
    cat "$work/test_glb.log"
    echo "FAIL: test_glb failed while writing the samples"
    exit 1
fi
ls "$work"/*.glb >/dev/null 2>&1 || { echo "FAIL: test_glb wrote no GLB"; exit 1; }

# Errors and warnings are listed; any error fails (tests/export/validate_glb.js).
if node "$source_dir/tests/export/validate_glb.js" "$validator" "$work"/*.glb; then
    echo "all garment GLBs valid"
    exit 0
fi
echo "FAIL: the glTF validator found errors"
exit 1
