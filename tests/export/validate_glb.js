// tests/export/validate_glb.js -- runs the Khronos glTF validator (npm
// gltf-validator) on GLB files and exits 1 when any has an error.
//   node validate_glb.js VALIDATOR_DIR FILE.glb...
// One line per file (errors, warnings, infos, hints), then every error and
// warning. External resources are refused: a GLB must be self-contained.
// Used by test_glb_validator.sh and test_run_patterns.c.
//
// SPDX-License-Identifier: GPL-3.0-or-later
const fs = require('fs');
const path = require('path');
const validator = require(process.argv[2]);
(async () => {
  let failed = 0;
  for (const file of process.argv.slice(3)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
      uri: path.basename(file), maxIssues: 200,
      externalResourceFunction: (uri) => Promise.reject(new Error('unexpected external resource ' + uri)),
    });
    const issues = report.issues;
    console.log(`${path.basename(file)}: ${issues.numErrors} errors, ${issues.numWarnings} warnings, ` +
                `${issues.numInfos} infos, ${issues.numHints} hints`);
    for (const message of issues.messages)
      if (message.severity <= 1)
        console.log(`  ${message.severity === 0 ? 'error' : 'warning'} ${message.code} ${message.pointer || ''}: ` +
                    message.message);
    failed += issues.numErrors > 0;
  }
  process.exit(failed ? 1 : 0);
})().catch((error) => { console.log('validator failed: ' + error); process.exit(1); });
