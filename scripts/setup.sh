#!/usr/bin/env bash
# First command of README.md: installs what is missing, builds panelize, and
# runs the main job (panelize run) on the bundled default garment (the generated bodice).
# SPDX-License-Identifier: GPL-3.0-or-later
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"
mkdir -p build/default
./build/panelize generate bodice -o build/default/bodice.obj --faces 7000
# The main job: garment in, sewable pattern out (docs/run.md).
./build/panelize run build/default/bodice.obj -o build/default/pattern
