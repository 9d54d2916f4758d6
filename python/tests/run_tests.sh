#!/usr/bin/env bash
# The Python package's tests under pytest, as ctest runs them (test_python): skips with 77,
# saying why, when the package was not built (no python3-dev or python3-numpy) or pytest is
# missing (python3-pytest); scripts/install-deps.sh installs all three.
#   PZ_PYTHON       the interpreter the package was built for (CMake's Python3_EXECUTABLE)
#   PZ_PYTHON_PATH  build/python, where the package is
#   PZ_PYTHON_BUILT ON when CMake built it (else PZ_PYTHON_NOT_BUILT says why)
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
here=$(cd "$(dirname "$0")" && pwd)
python=${PZ_PYTHON:-/usr/bin/python3}
if [ "${PZ_PYTHON_BUILT:-}" != "ON" ]; then
    echo "SKIPPED: the Python package was not built (${PZ_PYTHON_NOT_BUILT:-it needs python3-dev and python3-numpy: scripts/install-deps.sh})"
    exit 77
fi
if ! "$python" -c "import pytest, numpy" 2>/dev/null; then
    echo "SKIPPED: $python has no pytest or numpy (python3-pytest, python3-numpy: scripts/install-deps.sh)"
    exit 77
fi
package_path=$(cd "${PZ_PYTHON_PATH:-}" && pwd) || exit 1
export PYTHONPATH="$package_path${PYTHONPATH:+:$PYTHONPATH}"
export PYTHONDONTWRITEBYTECODE=1
cd "$here" && exec "$python" -m pytest -q -p no:cacheprovider "$here" "$@"
