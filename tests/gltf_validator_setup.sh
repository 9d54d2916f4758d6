# tests/gltf_validator_setup.sh -- sourced by the glTF validator tests: sets
# source_dir, build_dir and validator (the npm gltf-validator that
# scripts/install-deps.sh puts in .tools/), and skips the test (exit 77) when
# node or the validator is missing, except with CI=true where that fails.
#
# SPDX-License-Identifier: GPL-3.0-or-later
source_dir=${PZ_SOURCE_DIR:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)}
build_dir=${PZ_BUILD_DIR:-}
validator="$source_dir/.tools/node_modules/gltf-validator"

missing_tool() {
    if [ "${CI:-}" = "true" ]; then
        echo "FAIL: $1 (required when CI=true)"
        exit 1
    fi
    echo "SKIPPED: $1"
    exit 77
}

command -v node >/dev/null 2>&1 || missing_tool "node is not installed"
[ -d "$validator" ] ||
    missing_tool "gltf-validator not in $source_dir/.tools (npm install --prefix $source_dir/.tools gltf-validator)"
