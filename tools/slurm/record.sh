#!/bin/bash
# One chunk of an animation's frames per task of a Slurm job array (a contiguous --array range):
#   sbatch --array=0-5 tools/slurm/record.sh scenes/twist-anim.toml frames --fps 24
# splits the frames (96 here) evenly over the tasks (6 × 16). Any `nlifs record` options may
# follow the frames folder; give the same ones to the run that encodes afterwards:
#   nlifs record scenes/twist-anim.toml -o frames --fps 24 --resume --video twist.mp4
#SBATCH --cpus-per-task=8
set -euo pipefail
SCENE=$1; FRAMES=$2; shift 2
N=$(nlifs record "$SCENE" -o "$FRAMES" "$@" --print-frame-count)
TASK=$(( SLURM_ARRAY_TASK_ID - SLURM_ARRAY_TASK_MIN ))
CHUNK=$(( (N + SLURM_ARRAY_TASK_COUNT - 1) / SLURM_ARRAY_TASK_COUNT ))
A=$(( TASK * CHUNK )); B=$(( A + CHUNK < N ? A + CHUNK : N ))
if (( A < B )); then
  nlifs record "$SCENE" -o "$FRAMES" "$@" --backend cpu --resume --frames "$A..$B"
fi
