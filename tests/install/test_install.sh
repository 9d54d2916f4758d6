#!/usr/bin/env bash
# tests/install/test_install.sh -- the installed library (docs/install.md):
# installs the build tree ($PZ_BUILD_DIR) into a temporary prefix with
# `cmake --install`, then checks what is there and builds programs against
# it the ways a user would:
#  - the files: libpanelize.so.MAJOR (SONAME) exporting pz_* symbols only,
#    libpanelize.a, the panelize command, panelize.pc, the CMake package;
#  - the headers: exactly the public ones (<folder>/<folder>.h, core's
#    vec.h, util.h, heap.h and version.h, the umbrella panelize.h), each compiling on
#    its own (C and C++) with nothing but `pkg-config --cflags panelize`;
#  - tests/install/consumer.c built with `pkg-config --cflags --libs` (shared),
#    with `pkg-config --static` against libpanelize.a, and by a CMake project
#    with find_package(panelize) (both targets), each run and its output read;
#  - examples/run_bodice.c (pz_run) built the same way and run;
#  - the Python package (when the tree built it): imported from the installed
#    site-packages alone, out of the source and build trees, and run once.
# Skips (77) only without pkg-config or a C compiler. In a sanitizer build the
# installed panelize.pc and CMake targets carry the sanitizer's link flags, so
# the programs need nothing special here.
#
# SPDX-License-Identifier: GPL-3.0-or-later
set -uo pipefail

source_dir=${PZ_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}
build_dir=${PZ_BUILD_DIR:-$source_dir/build}
cc=${PZ_C_COMPILER:-cc}
cxx=${PZ_CXX_COMPILER:-c++}
cmake=${PZ_CMAKE:-cmake}
if ! command -v pkg-config >/dev/null 2>&1; then
    echo "SKIPPED: pkg-config is not installed (scripts/install-deps.sh installs it)"
    exit 77
fi
if ! command -v "$cc" >/dev/null 2>&1; then
    echo "SKIPPED: no C compiler ($cc)"
    exit 77
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
prefix=$work/prefix

passed=0
failed=0
pass() { passed=$((passed + 1)); }
fail() { failed=$((failed + 1)); echo "FAIL: $*"; }
check() { # check DESCRIPTION COMMAND...: passes when the command succeeds
    local what=$1
    shift
    if "$@"; then pass; else fail "$what"; fi
}
finish() {
    echo "$passed passed, $failed failed"
    [ "$failed" -eq 0 ]
}

# ------------------------------------------------------------------ install
if ! "$cmake" --install "$build_dir" --prefix "$prefix" >"$work/install.log" 2>&1; then
    cat "$work/install.log"
    fail "cmake --install $build_dir failed (is the whole tree built?)"
    finish
    exit 1
fi
pc_file=$(find "$prefix" -name panelize.pc -path '*/pkgconfig/*' | head -n 1)
if [ -z "$pc_file" ]; then
    fail "no panelize.pc installed"
    finish
    exit 1
fi
libdir=$(dirname "$(dirname "$pc_file")")
include_dir=$prefix/include/panelize
export PKG_CONFIG_PATH=$libdir/pkgconfig${PKG_CONFIG_PATH:+:$PKG_CONFIG_PATH}
version=$(pkg-config --modversion panelize)
major=${version%%.*}
cflags=$(pkg-config --cflags panelize)
libs=$(pkg-config --libs panelize)

# ------------------------------------------------------------------ files
check "panelize.pc's version '$version' is not the headers' PZ_VERSION_STRING" \
    grep -qF "#define PZ_VERSION_STRING \"$version\"" "$include_dir/core/version.h"
check "libpanelize.a missing" [ -f "$libdir/libpanelize.a" ]
check "libpanelize.so.$version missing" [ -f "$libdir/libpanelize.so.$version" ]
check "libpanelize.so.$major is not a link to libpanelize.so.$version" \
    [ "$(readlink "$libdir/libpanelize.so.$major")" = "libpanelize.so.$version" ]
check "libpanelize.so is not a link to libpanelize.so.$major" \
    [ "$(readlink "$libdir/libpanelize.so")" = "libpanelize.so.$major" ]
soname=$(readelf -d "$libdir/libpanelize.so.$version" | sed -n 's/.*SONAME.*\[\(.*\)\].*/\1/p')
check "SONAME is '$soname', expected libpanelize.so.$major" [ "$soname" = "libpanelize.so.$major" ]
check "panelize command missing or without --version" \
    grep -qx "panelize $version" <("$prefix/bin/panelize" --version 2>&1)
for file in panelizeConfig.cmake panelizeConfigVersion.cmake panelizeTargets.cmake; do
    check "$file missing" [ -f "$libdir/cmake/panelize/$file" ]
done

# The shared library exports the public API and nothing else (cmake/panelize.map).
nm -D --defined-only "$libdir/libpanelize.so.$version" | awk '{print $NF}' | sort -u >"$work/exported"
grep -v '^pz_' "$work/exported" | head -n 20 >"$work/foreign"
check "libpanelize.so exports symbols outside pz_*: $(tr '\n' ' ' <"$work/foreign")" [ ! -s "$work/foreign" ]
for symbol in pz_version pz_generate pz_mesh_validate pz_ctx_init; do
    check "libpanelize.so does not export $symbol" grep -qx "$symbol" "$work/exported"
done

# ------------------------------------------------------------------ headers
# Exactly the public headers: <folder>/<folder>.h, core's small ones and the umbrella.
(cd "$include_dir" && find . -type f | sed 's|^\./||' | sort) >"$work/headers"
while read -r header; do
    folder=${header%%/*}
    case $header in
        panelize.h | core/vec.h | core/util.h | core/heap.h | core/version.h) ;;
        "$folder/$folder.h") ;;
        *) fail "private file installed: include/panelize/$header" ;;
    esac
done <"$work/headers"
check "core/core.h not installed" grep -qx core/core.h "$work/headers"
check "mesh/mesh.h not installed" grep -qx mesh/mesh.h "$work/headers"
# Installed headers are the tree's own (version.h and panelize.h are generated).
while read -r header; do
    case $header in panelize.h | core/version.h) continue ;; esac
    check "include/panelize/$header differs from the source tree's" \
        cmp -s "$include_dir/$header" "$source_dir/$header"
done <"$work/headers"
# The umbrella includes every other installed header, and only those.
sed -n 's/^#include "\(.*\)"$/\1/p' "$include_dir/panelize.h" | sort >"$work/umbrella"
grep -vx -e panelize.h -e core/version.h "$work/headers" >"$work/expected_umbrella"
check "panelize.h does not include exactly the public headers: $(diff "$work/expected_umbrella" "$work/umbrella" | tr '\n' ' ')" \
    cmp -s "$work/expected_umbrella" "$work/umbrella"
# Each header stands alone with the installed include path only (the source tree is nowhere on it).
while read -r header; do
    printf '#include "%s"\n' "$header" >"$work/alone.c"
    check "$header does not compile on its own: $("$cc" -std=c11 -Wall -Wextra -Werror -fsyntax-only $cflags \
        "$work/alone.c" 2>&1 | head -n 5)" \
        "$cc" -std=c11 -Wall -Wextra -Werror -fsyntax-only $cflags "$work/alone.c"
done <"$work/headers"
if command -v "$cxx" >/dev/null 2>&1; then
    printf '#include "panelize.h"\nint main() { return pz_version() == nullptr; }\n' >"$work/umbrella.cpp"
    check "panelize.h does not compile as C++: $("$cxx" -std=c++17 -fsyntax-only $cflags "$work/umbrella.cpp" 2>&1 |
        head -n 5)" "$cxx" -std=c++17 -fsyntax-only $cflags "$work/umbrella.cpp"
fi

# ------------------------------------------------------------------ programs
# needs_libpanelize BINARY: whether the binary loads libpanelize.so.MAJOR.
needs_libpanelize() { readelf -d "$1" | grep -qF "[libpanelize.so.$major]"; }
# consumer_output FILE: what tests/install/consumer.c printed holds up.
consumer_output() {
    local file=$1 faces
    grep -qx "version: $version headers $version" "$file" || return 1
    counts=$(sed -n 's/^bodice: \([0-9]* vertices, [0-9]* faces\), valid$/\1/p' "$file")
    faces=${counts#* vertices, }
    faces=${faces% faces}
    # pz_generate's face count is approximate: 3000 asked for. The GLB read back has the same counts.
    [ -n "$counts" ] && [ "$faces" -ge 2000 ] && [ "$faces" -le 4000 ] && grep -qx "glb: $counts" "$file"
}
# run_program WHAT BINARY [ARGS...]: runs it against the installed library; its stdout in $work/WHAT.out.
run_program() {
    local what=$1 binary=$2
    shift 2
    if LD_LIBRARY_PATH=$libdir${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH} "$binary" "$@" >"$work/$what.out" \
        2>"$work/$what.err"; then
        pass
        return 0
    fi
    fail "$what: exit $? ($(head -c 300 "$work/$what.err"))"
    return 1
}

consumer=$source_dir/tests/install/consumer.c
# Shared: pkg-config --cflags --libs.
if "$cc" -std=c11 -Wall -Wextra -Werror $cflags "$consumer" -o "$work/consumer_shared" $libs 2>"$work/build.err"; then
    pass
    check "consumer (pkg-config) does not load libpanelize.so.$major" needs_libpanelize "$work/consumer_shared"
    run_program consumer_shared "$work/consumer_shared" "$work/shared.glb" &&
        check "consumer (pkg-config) printed: $(cat "$work/consumer_shared.out")" consumer_output "$work/consumer_shared.out"
else
    fail "consumer does not build with pkg-config --cflags --libs: $(head -n 20 "$work/build.err")"
fi

# Static: pkg-config --static --libs, with libpanelize.a in place of -lpanelize.
static_libs=$(pkg-config --static --libs panelize | sed "s|-lpanelize\\b|$libdir/libpanelize.a|")
if "$cc" -std=c11 $cflags "$consumer" -o "$work/consumer_static" $static_libs 2>"$work/build.err"; then
    pass
    check "consumer (static) loads libpanelize.so" bash -c "! readelf -d '$work/consumer_static' | grep -q libpanelize"
    run_program consumer_static "$work/consumer_static" "$work/static.glb" &&
        check "consumer (static) printed: $(cat "$work/consumer_static.out")" consumer_output "$work/consumer_static.out"
else
    fail "consumer does not build with pkg-config --static: $(head -n 20 "$work/build.err")"
fi

# CMake: find_package(panelize) and both targets, in a C-only project.
mkdir -p "$work/cmake-consumer"
cat >"$work/cmake-consumer/CMakeLists.txt" <<EOF
cmake_minimum_required(VERSION 3.18)
project(consumer LANGUAGES C)
find_package(panelize $version REQUIRED)
add_executable(consumer_shared "$consumer")
target_link_libraries(consumer_shared PRIVATE panelize::panelize)
add_executable(consumer_static "$consumer")
target_link_libraries(consumer_static PRIVATE panelize::panelize_static)
EOF
if "$cmake" -S "$work/cmake-consumer" -B "$work/cmake-consumer/build" -DCMAKE_C_COMPILER="$cc" \
        -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release >"$work/cmake.log" 2>&1 &&
    "$cmake" --build "$work/cmake-consumer/build" >>"$work/cmake.log" 2>&1; then
    pass
    for kind in shared static; do
        binary=$work/cmake-consumer/build/consumer_$kind
        run_program "cmake_$kind" "$binary" "$work/cmake_$kind.glb" &&
            check "consumer (find_package, $kind) printed: $(cat "$work/cmake_$kind.out")" \
                consumer_output "$work/cmake_$kind.out"
    done
    check "consumer (find_package, shared) does not load libpanelize.so.$major" \
        needs_libpanelize "$work/cmake-consumer/build/consumer_shared"
    check "consumer (find_package, static) loads libpanelize.so" \
        bash -c "! readelf -d '$work/cmake-consumer/build/consumer_static' | grep -q libpanelize"
else
    fail "find_package(panelize) project does not build: $(tail -n 30 "$work/cmake.log")"
fi
# The package refuses another major version.
sed -i "s/find_package(panelize $version REQUIRED)/find_package(panelize $((major + 1)).0 REQUIRED)/" \
    "$work/cmake-consumer/CMakeLists.txt"
check "find_package(panelize $((major + 1)).0) accepted version $version" \
    bash -c "! '$cmake' -S '$work/cmake-consumer' -B '$work/cmake-consumer/build-next' -DCMAKE_C_COMPILER='$cc' \
        -DCMAKE_PREFIX_PATH='$prefix' >/dev/null 2>&1"

# examples/run_bodice.c: the whole pipeline through pz_run, built like a user would.
check_example() {
    if ! "$cc" -std=c11 -Wall -Wextra -Werror $cflags "$source_dir/examples/run_bodice.c" -o "$work/run_bodice" \
            $libs 2>"$work/build.err"; then
        fail "examples/run_bodice.c does not build with pkg-config: $(head -n 20 "$work/build.err")"
        return
    fi
    pass
    run_program run_bodice "$work/run_bodice" || return
    local out=$work/run_bodice.out
    check "run_bodice: no panels in: $(cat "$out")" grep -qE '^panels: [1-9][0-9]*$' "$out"
    check "run_bodice: no dart count in: $(cat "$out")" grep -qE '^darts: [0-9]+$' "$out"
    check "run_bodice: no verdict in: $(cat "$out")" grep -qE '^goals_met: (yes|no)$' "$out"
    check "run_bodice: no worst strain in: $(cat "$out")" grep -qE '^worst_strain: [0-9]+\.[0-9]{4}$' "$out"
    if grep -qx 'goals_met: yes' "$out"; then
        check "run_bodice: goals met but reasons given: $(cat "$out")" grep -qx 'reasons: none' "$out"
    else
        check "run_bodice: goals not met and no reason given: $(cat "$out")" bash -c "! grep -qx 'reasons: none' '$out'"
    fi
}
check_example

# ------------------------------------------------------------------ the Python package (docs/python.md)
check_python() {
    local package
    package=$(find "$prefix" -path '*/site-packages/panelize/__init__.py' | head -n 1)
    if ! ls "$build_dir"/python/panelize/_panelize*.so >/dev/null 2>&1; then
        check "the Python package is installed though the tree did not build it" [ -z "$package" ]
        return
    fi
    check "no site-packages/panelize/__init__.py under the prefix" [ -n "$package" ]
    [ -n "$package" ] || return
    local out=$work/python.out
    if (cd "$work" && PYTHONPATH=$(dirname "$(dirname "$package")") /usr/bin/python3 -c '
import panelize
assert panelize.__file__.startswith("'"$prefix"'"), panelize.__file__
result = panelize.run(panelize.generate("bodice", faces=1500), symmetry="off")
print("panels", result.panel_count, "goals_met", result.goals_met)' >"$out" 2>&1); then
        check "installed package printed: $(cat "$out")" grep -qE '^panels [1-9][0-9]* goals_met (True|False)$' "$out"
    else
        fail "the installed Python package does not import and run: $(tail -n 5 "$out")"
    fi
}
check_python

finish
