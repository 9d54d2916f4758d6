#!/usr/bin/env bash
# Installs every Debian package (and the one npm tool) that panelize's build,
# tests and tools need. Does nothing when they are all present.
# SPDX-License-Identifier: GPL-3.0-or-later
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  build-essential cmake python3   # build-essential brings binutils: readelf and nm (tests/install)
  pkg-config              # finds cairo; tests/install builds programs with the installed panelize.pc
  libsuitesparse-dev      # CHOLMOD: every sparse solve
  libcgal-dev             # remeshing, exact predicates, polygon offsets
  libtinygltf-dev nlohmann-json3-dev libstb-dev   # glTF in and out (libtinygltf.so)
  libcjson-dev            # JSON reports and JSON inputs
  libcairo2-dev           # pattern.pdf and pattern-tiled.pdf
  python3-ezdxf librsvg2-bin poppler-utils   # tests read our DXF, SVG and PDF with real readers
  # The measuring tools (bench/bench_layouts, ../shared/tools/seamscore.py, gtpattern.py, render.py)
  # run under /usr/bin/python3 and need these; nothing panelize builds or tests links them.
  python3-numpy python3-scipy python3-matplotlib
  # The Python package (python/, docs/python.md): built against Debian's Python and numpy C APIs,
  # tested under pytest; python3-distributed runs the Dask example of docs/python.md.
  python3-dev python3-pytest python3-distributed
  libeigen3-dev           # only the benchmarks' libigl peers (targets igl_peer, igl_truth_peer) include it
  clang libclang-rt-14-dev  # libFuzzer targets
  slurm-wlm munge         # tests/batch/test_batch_slurm.sh runs a batch as a Slurm job array (docs/batch.md)
  libmicrohttpd-dev curl  # panelize studio's web server (docs/studio.md); its API test talks to it with curl
  chromium                # the studio's browser test drives it headless (playwright-core from npm, at build time)
)

missing=()
for package in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
# The glTF validator runs on Node.js. Some images ship a Node.js that bundles npm
# (and conflicts with Debian's npm package): only ask for it when npm is absent.
command -v npm >/dev/null 2>&1 || missing+=(nodejs npm)
if ((${#missing[@]})); then
  echo "install-deps: installing ${missing[*]}" >&2
  sudo=""
  [[ $(id -u) -eq 0 ]] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# The Khronos glTF validator (npm), kept inside the checkout under .tools/ (git-ignored).
if [[ ! -f .tools/node_modules/gltf-validator/package.json ]]; then
  echo "install-deps: installing gltf-validator into .tools/" >&2
  mkdir -p .tools
  npm install --silent --no-audit --no-fund --prefix .tools gltf-validator@2.0.0-dev.3.10 >/dev/null
fi
