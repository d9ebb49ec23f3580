#!/usr/bin/env bash
# Configures and builds one build tree. Usage: scripts/build.sh release|asan [TARGET...]
# With targets (e.g. `scripts/build.sh release phantasm`) only those and what they link are built;
# the tree is configured the same way, so a later build without targets (scripts/test.sh) builds
# the rest in it and keeps what was built.
# release: optimized (-O3), tests and benchmarks; asan: AddressSanitizer + UBSan, tests only, at
# -O1 (most tests' own code at -O0, tests/CMakeLists.txt) with line tables only (-g1): enough for
# the sanitizers' stack traces, and the build is
# shorter than with full debug information; compiled by clang 14, which takes less processor time
# than g++ for the same sanitizers (docs/performance.md, Build and tests). A tree configured
# earlier keeps its compiler: remove build/asan to rebuild it with clang. The asan tree also holds
# the libFuzzer targets of fuzz/, built only when named (scripts/fuzz.sh).
set -euo pipefail
cd "$(dirname "$0")/.."

kind=${1:-release}
shift $(($# > 0 ? 1 : 0))
case "$kind" in
  release) flags=(-DCMAKE_BUILD_TYPE=Release) ;;
  asan) flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG"
              -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14
              -DPHANTASM_SANITIZE=ON -DPHANTASM_BUILD_BENCHMARKS=OFF) ;;
  *) echo "usage: $0 release|asan [TARGET...]" >&2; exit 2 ;;
esac

build_dir="build/$kind"
if [ ! -f "$build_dir/CMakeCache.txt" ]; then
  cmake -S . -B "$build_dir" -G Ninja "${flags[@]}"
fi
targets=()
if [ $# -gt 0 ]; then targets=(--target "$@"); fi
cmake --build "$build_dir" --parallel "$(nproc)" "${targets[@]}"
