#!/usr/bin/env bash
# The main job: installs what is missing, builds the phantasm program (Release; the tests and
# benchmarks are left to scripts/test.sh, which builds them in the same tree), and runs the
# default scene data-synthetic/colin-head.yaml (the Colin 27 head, derived from Debian's
# mricron-data) into out/ (replacing what an earlier run wrote there). The built anatomy is
# kept in build/anatomy-cache, so a second run reads it instead of building it again
# (docs/batch.md, The anatomy cache).
# Extra arguments go to `phantasm run`, e.g. scripts/run.sh data-synthetic/head.yaml -o out-head --force
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
bash scripts/build.sh release phantasm
if [ $# -eq 0 ]; then
  set -- data-synthetic/colin-head.yaml -o out --force --cache build/anatomy-cache
fi
exec build/release/apps/phantasm/phantasm run "$@"
