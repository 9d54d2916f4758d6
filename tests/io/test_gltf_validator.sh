#!/usr/bin/env bash
# tests/io/test_gltf_validator.sh -- every GLB panelize writes passes the
# Khronos glTF validator with zero errors.
#
# GLBs checked: the samples test_gltf writes when PZ_GLB_OUT is set (a plain
# mesh; UVs with a seam and two labels; UVs, labels and two poses) and, when
# the CLI can generate, a bodice with poses and a skirt without.
# The validator is the npm package gltf-validator, installed by the project's
# setup into $PZ_SOURCE_DIR/.tools (npm install --prefix .tools gltf-validator).
# Without it (or without node) the test is skipped (exit 77), except with
# CI=true, where a missing validator is a failure.
#
# SPDX-License-Identifier: GPL-3.0-or-later
set -u

source "$(dirname "$0")/../gltf_validator_setup.sh"

work=$(mktemp -d "${TMPDIR:-/tmp}/pz_gltf_validator.XXXXXX") || exit 1
trap 'rm -rf "$work"' EXIT
mkdir "$work/glb"

# Library samples from the C test.
test_program="$build_dir/test_gltf"
if [ -z "$build_dir" ] || [ ! -x "$test_program" ]; then
    echo "FAIL: test_gltf not found in PZ_BUILD_DIR='$build_dir'"
    exit 1
fi
if ! (cd "$work" && PZ_GLB_OUT="$work/glb" "$test_program" >"$work/test_gltf.log" 2>&1); then
    cat "$work/test_gltf.log"
    echo "FAIL: test_gltf failed while writing the samples"
    exit 1
fi
for sample in plain labelled posed; do
    if [ ! -s "$work/glb/$sample.glb" ]; then
        echo "FAIL: test_gltf did not write $sample.glb"
        exit 1
    fi
done

# CLI samples, when `panelize generate` is there.
if [ -n "${PZ_BINARY:-}" ] && [ -x "$PZ_BINARY" ]; then
    if "$PZ_BINARY" generate bodice -o "$work/glb/bodice.glb" --faces 2000 --poses 2 >"$work/cli.log" 2>&1 &&
        "$PZ_BINARY" generate skirt -o "$work/glb/skirt.glb" --faces 1500 >>"$work/cli.log" 2>&1; then
        echo "checking CLI output too: bodice.glb (2 poses), skirt.glb"
    else
        echo "note: 'panelize generate' did not produce GLBs, only the library samples are checked:"
        sed 's/^/  /' "$work/cli.log" | head -5
        rm -f "$work/glb/bodice.glb" "$work/glb/skirt.glb"
    fi
fi

cat >"$work/validate.js" <<'EOF'
// Validates each GLB given on the command line; exit 1 if any has errors.
const fs = require('fs');
const path = require('path');
const validator = require(process.argv[2]);
(async () => {
  let failed = 0;
  for (const file of process.argv.slice(3)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
      uri: path.basename(file),
      maxIssues: 200,
      // A GLB of ours never references other files.
      externalResourceFunction: (uri) => Promise.reject(new Error('unexpected external resource ' + uri)),
    });
    const issues = report.issues;
    console.log(`${path.basename(file)}: ${issues.numErrors} errors, ${issues.numWarnings} warnings, ` +
                `${issues.numInfos} infos, ${issues.numHints} hints`);
    for (const message of issues.messages)
      if (message.severity <= 1)
        console.log(`  ${message.severity === 0 ? 'error' : 'warning'} ${message.code} ` +
                    `${message.pointer || ''}: ${message.message}`);
    if (issues.numErrors > 0)
      failed++;
  }
  process.exit(failed ? 1 : 0);
})().catch((error) => {
  console.log('validator failed: ' + error);
  process.exit(1);
});
EOF

if node "$work/validate.js" "$validator" "$work"/glb/*.glb; then
    echo "all GLBs valid"
    exit 0
fi
echo "FAIL: the glTF validator found errors"
exit 1
