#!/usr/bin/env bash
# Installs what is missing, builds, and runs the whole test suite optimized, then builds the
# sanitizer tree, runs the fuzz targets in it for 20 s each (scripts/fuzz.sh: clang, libFuzzer)
# and the tests labelled "fast" again with AddressSanitizer + UndefinedBehaviorSanitizer. The fast tests cover
# the libraries on small inputs; the slow and heavy tests
# (whole runs of the command, larger models, sweeps) would take most of the CI budget under the
# sanitizers (see tests/CMakeLists.txt). Arguments go to both ctest runs (e.g. -R Sphere).
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
jobs=$(nproc)
# Each phase ends with its wall time and the processor time of everything it ran: docs/performance.md
# gives the test command's time by phase, and wall x cores against processor time shows how busy
# the cores were.
TIMEFORMAT="   (%0R s wall, %0U s user + %0S s system processor time)"
# ctest runs one test per core, and a test's phantasm run has an OpenMP thread per core: OpenMP
# threads that spin while they wait for work (libgomp's and libomp's default) take the core from
# the test beside them. Waiting passively changes no result; the coarse shipped scenes' tests
# (ctest -R ShippedScene --parallel 2) took 87-90 s of processor time instead of 128-144 s.
export OMP_WAIT_POLICY=passive
# glibc's malloc asks the kernel for transparent huge pages in the test programs that call the
# libraries directly (the phantasm command allocates through tcmalloc instead; docs/performance.md,
# Memory allocator): they allocate volumes of tens of megabytes too, and mapping them 4 KiB at a
# time cost the fast tests a twelfth of their wall time and the Colin head's body test a fifth. A
# tunable set by the user is kept. A compile gained nothing measurable and the sanitizers bring
# their own allocator: only the Release tests get it.
tunables=${GLIBC_TUNABLES:-}
case ":$tunables:" in
  *:glibc.malloc.hugetlb=*) ;;
  *) tunables="${tunables:+$tunables:}glibc.malloc.hugetlb=1" ;;
esac

echo "== Release build and tests"
time bash scripts/build.sh release
time env GLIBC_TUNABLES="$tunables" ctest --test-dir build/release --output-on-failure --parallel "$jobs" "$@"

echo "== ASan + UBSan build"
time bash scripts/build.sh asan

# The fuzz targets are part of the sanitizer tree (fuzz/CMakeLists.txt): only their own sources are
# compiled here.
echo "== Fuzzing: scene and sweep parsers, NIfTI and mesh readers (clang, libFuzzer, ASan + UBSan)"
time bash scripts/fuzz.sh 20

echo "== ASan + UBSan tests"
# The tree is compiled by clang (scripts/build.sh): its sanitizers print a report's stack with
# file and line through llvm-symbolizer (the llvm-14 package; scripts/install-deps.sh).
export ASAN_SYMBOLIZER_PATH=/usr/lib/llvm-14/bin/llvm-symbolizer
time env ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build/asan --output-on-failure --parallel "$jobs" -L fast "$@"
