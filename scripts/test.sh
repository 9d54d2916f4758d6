#!/usr/bin/env bash
# Second command of README.md (and what .ci/run runs): the whole test suite.
#  1. Release build, every test under ctest;
#  2. the same tests built with AddressSanitizer + UndefinedBehaviorSanitizer;
#  3. every libFuzzer target, a short run on its seed corpus: the mesh
#     parsers for PZ_FUZZ_SECONDS each (default 45), the other input files
#     (sketch, features, panels, seams and darts, allowances) for
#     PZ_FUZZ_INPUT_SECONDS each (default 15), the whole run on tiny meshes for
#     PZ_FUZZ_RUN_SECONDS (default 40). An input that takes over 20 s is a hang.
# SPDX-License-Identifier: GPL-3.0-or-later
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
jobs=$(nproc)
bash scripts/install-deps.sh

echo "== Release build and tests"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$jobs"
(cd build && ctest --output-on-failure -j"$jobs")

echo "== AddressSanitizer + UndefinedBehaviorSanitizer build and tests"
cmake -S . -B build-sanitize -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPZ_SANITIZE=ON -DPZ_BUILD_BENCH=OFF >/dev/null
cmake --build build-sanitize -j"$jobs"
(cd build-sanitize && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
   ctest --output-on-failure -j"$jobs")

echo "== Fuzzing the parsers, the input files and the run"
CC=clang CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=Debug -DPZ_FUZZ=ON \
  -DPZ_BUILD_TESTS=OFF -DPZ_BUILD_BENCH=OFF >/dev/null
cmake --build build-fuzz -j"$jobs"
fuzz_passed=0
fuzz_failed=0
for fuzzer in build-fuzz/fuzz_*; do
  name=$(basename "$fuzzer")
  format=${name#fuzz_}
  case $format in
    obj|ply|off|gltf) seconds=${PZ_FUZZ_SECONDS:-45} ;;
    run) seconds=${PZ_FUZZ_RUN_SECONDS:-40} ;;
    *) seconds=${PZ_FUZZ_INPUT_SECONDS:-15} ;;
  esac
  work=$(mktemp -d)
  # The fuzzer adds what it finds to its corpus: give it a copy, never the tree.
  cp -r "$root/tests/fuzz/corpus/$format/." "$work/" 2>/dev/null || true
  if (cd "$work" && "$root/$fuzzer" -max_total_time="$seconds" -max_len=65536 -rss_limit_mb=2048 -timeout=20 \
        -print_final_stats=0 "$work" >"$work.log" 2>&1); then
    fuzz_passed=$((fuzz_passed + 1))
    echo "fuzz $name: ok ($seconds s)"
  else
    fuzz_failed=$((fuzz_failed + 1))
    echo "fuzz $name: FAILED"; tail -n 40 "$work.log"
  fi
  rm -rf "$work" "$work.log"
done
echo "fuzz: $fuzz_passed passed, $fuzz_failed failed"
((fuzz_failed == 0))
