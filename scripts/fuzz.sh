#!/usr/bin/env bash
# Builds the libFuzzer targets in the sanitizer tree (scripts/build.sh asan: clang, ASan + UBSan;
# fuzz/CMakeLists.txt) and runs each for a
# bounded time on seeds from the repository: the scene target on tests/data/scenes,
# tests/data/bad-scenes and data-synthetic; the sweep target on tests/data/sweeps and the shipped
# sweep; the NIfTI and mesh targets on small files fuzz_seeds writes. Prints the inputs each target
# executed and exits non-zero on any finding (a crash, a sanitizer report, an exception other than
# InputError, a hang over the timeout, memory beyond the limit); libFuzzer then leaves the input as
# build/asan/fuzzing/findings/<target>/crash-... (rerun it: build/asan/fuzz/fuzz_<target> FILE).
# Usage: scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]   (default 20 s, every target)
# Inputs that reached new code are kept in build/asan/fuzzing/corpus/<target> for the next run.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=${1:-20}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(scene sweep nifti mesh)

# The sanitizer tree holds the targets only when clang compiles it (a tree keeps the compiler it
# was configured with: scripts/build.sh).
if [ -f build/asan/CMakeCache.txt ] && ! grep -q '^CMAKE_CXX_COMPILER:[A-Z]*=.*clang' build/asan/CMakeCache.txt; then
  echo "build/asan was configured with a compiler other than clang and has no fuzz targets: remove it" >&2
  exit 2
fi
bash scripts/build.sh asan fuzz_scene fuzz_sweep fuzz_nifti fuzz_mesh fuzz_seeds
bin=build/asan/fuzz
build=build/asan/fuzzing
seeds=$build/seeds
rm -rf "$seeds"
mkdir -p "$seeds"/{scene,sweep}
cp tests/data/scenes/*.yaml tests/data/bad-scenes/*.yaml "$seeds/scene/"
for f in data-synthetic/*.yaml; do
  if grep -q '^phantasm_sweep:' "$f"; then cp "$f" "$seeds/sweep/"; else cp "$f" "$seeds/scene/"; fi
done
cp tests/data/sweeps/*.yaml "$seeds/sweep/"
# VTK keeps a few objects alive until exit; the seed writer is no fuzz target.
ASAN_OPTIONS=detect_leaks=0 "$bin/fuzz_seeds" "$seeds/nifti" "$seeds/mesh"

# Most input of a target is bounded by its own checks; -max_len keeps a mutated input near the
# seeds' size (the largest seed is a few kB), where the fuzzer explores faster.
export ASAN_OPTIONS=abort_on_error=1:detect_leaks=1:allocator_may_return_null=0
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
export LSAN_OPTIONS=suppressions=$PWD/fuzz/lsan.supp
# The targets write the files the readers take by path into folders of their own under TMPDIR.
export TMPDIR=$PWD/$build/tmp
rm -rf "$TMPDIR"
mkdir -p "$TMPDIR"
# One target per core at a time: each is one process on one thread, so side by side they run as
# many inputs each as one after another, in a fraction of the wall time.
run_target() {
  local target=$1 corpus=$build/corpus/$1 findings=$build/findings/$1 log=$build/fuzz-$1.log
  mkdir -p "$corpus" "$findings"
  set +e
  "$bin/fuzz_$target" -max_total_time="$seconds" -timeout=5 -rss_limit_mb=2048 -max_len=16384 \
    -print_final_stats=1 -artifact_prefix="$findings/" "$corpus" "$seeds/$target" >"$log" 2>&1
  echo $? >"$build/fuzz-$target.code"
}
cores=$(nproc)
for ((first = 0; first < ${#targets[@]}; first += cores)); do
  batch=("${targets[@]:first:cores}")
  echo "== ${batch[*]/#/fuzz_} for $seconds s"
  for target in "${batch[@]}"; do run_target "$target" & done
  wait
done
status=0
summary=""
for target in "${targets[@]}"; do
  findings=$build/findings/$target log=$build/fuzz-$target.log
  code=$(cat "$build/fuzz-$target.code")
  executed=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  if [ "$code" -ne 0 ]; then
    status=1
    echo "fuzz_$target: FINDING (exit code $code) after ${executed:-?} inputs; the end of $log:"
    tail -60 "$log"
    ls "$findings"
  fi
  summary+=$(printf '%-12s %10s inputs executed in %s s%s' "fuzz_$target" "${executed:-?}" "$seconds" \
    "$([ "$code" -ne 0 ] && echo ', FINDING')")$'\n'
done
echo "== fuzzing summary"
printf '%s' "$summary"
exit "$status"
