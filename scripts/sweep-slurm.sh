#!/usr/bin/env bash
# The force-feedback sweep (talus sweep) as a Slurm job array: each array task runs one shard of
# the samples, and a dependent job merges the shards into sweep.csv, sweep.png and summary.json.
#
#   scripts/sweep-slurm.sh OUT_DIR [SHARDS] [talus sweep options...]
#   e.g. scripts/sweep-slurm.sh /scratch/fb35 25 --scenario fb35 --fidelity D200,D100 --samples 50
#
# Every task needs build/talus on a shared file system and OUT_DIR shared by all nodes. Without
# Slurm, the same shards run anywhere: talus sweep ... --shard K/N, then --collect.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:?usage: scripts/sweep-slurm.sh OUT_DIR [SHARDS] [talus sweep options...]}
shards=${2:-10}
[[ "$shards" =~ ^[1-9][0-9]*$ ]] || { echo "sweep-slurm: SHARDS must be a positive integer, got '$shards'" >&2; exit 2; }
shift $(( $# >= 2 ? 2 : 1 ))
talus="$root/build/talus"
[ -x "$talus" ] || { echo "sweep-slurm: build talus first (scripts/demo or scripts/test)" >&2; exit 2; }
mkdir -p "$out/logs"
# one task per shard; each runs its samples i with i mod SHARDS = task id
array_job=$(sbatch --parsable --array=0-$((shards - 1)) --job-name=talus-sweep \
  --output="$out/logs/shard-%a.log" \
  --wrap="POCL_CACHE_DIR=$root/build/pocl-cache $talus sweep $* --out $out --shard \$SLURM_ARRAY_TASK_ID/$shards --quiet")
# the merge, once every shard has finished
sbatch --parsable --dependency=afterok:"$array_job" --job-name=talus-sweep-collect \
  --output="$out/logs/collect.log" --wrap="$talus sweep $* --out $out --collect"
echo "sweep-slurm: array job $array_job with $shards shards; results in $out once the collect job ends"
