#!/bin/bash
# Slurm job array for a phantasm sweep: task i of N runs the i-th of N disjoint shards into one
# shared dataset folder. Resubmitting the array after a failure or a time limit finishes the
# subjects still missing (complete subjects are skipped). Number the tasks from 1 and resubmit the
# whole array: N is the number of tasks in it (docs/batch.md, Slurm job array).
#
#   sbatch --array=1-10 scripts/slurm-batch.sh data-synthetic/head-sweep.yaml /shared/sweep-out
#
#SBATCH --job-name=phantasm-sweep
#SBATCH --cpus-per-task=2
#SBATCH --mem=4G
#SBATCH --time=02:00:00
#SBATCH --output=phantasm-sweep-%A_%a.log
set -euo pipefail
sweep=${1:?usage: sbatch --array=1-N slurm-batch.sh SWEEP OUT}
out=${2:?usage: sbatch --array=1-N slurm-batch.sh SWEEP OUT}
task=${SLURM_ARRAY_TASK_ID:?submit it as an array: sbatch --array=1-N slurm-batch.sh SWEEP OUT}
phantasm=${PHANTASM:-phantasm}
export OMP_NUM_THREADS=${SLURM_CPUS_PER_TASK:-2}
exec "$phantasm" batch "$sweep" -o "$out" --shard "$task/$SLURM_ARRAY_TASK_COUNT" --jobs 1
