#!/bin/bash
# Part K of N of a still per task of a Slurm job array (N: the size of a contiguous --array range):
#   sbatch --array=1-16 tools/slurm/part.sh scenes/plant2.toml parts \
#     --points 4000000000 --width 8192 --height 8192
# Any `nlifs render` options may follow the parts folder (the same in every task); then:
#   nlifs merge parts/*.part -o plant2.png
#SBATCH --cpus-per-task=8
set -euo pipefail
SCENE=$1; PARTS=$2; shift 2
K=$(( SLURM_ARRAY_TASK_ID - SLURM_ARRAY_TASK_MIN + 1 ))
mkdir -p "$PARTS"
nlifs render "$SCENE" "$@" --part "$K/$SLURM_ARRAY_TASK_COUNT" --raw "$PARTS/p$K.part"
