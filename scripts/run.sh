#!/usr/bin/env bash
# The main job: installs what is missing, builds (Release), and runs the default scene
# data-synthetic/head.yaml into out/ (replacing what an earlier run wrote there).
# Extra arguments go to `phantasm run`, e.g. scripts/run.sh data-synthetic/abdomen.yaml -o out-abdomen
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
bash scripts/build.sh release
if [ $# -eq 0 ]; then
  set -- data-synthetic/head.yaml -o out --force
fi
exec build/release/apps/phantasm/phantasm run "$@"
