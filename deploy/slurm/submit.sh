#!/usr/bin/env bash
# Renders one frame on a SLURM cluster: a job array of TILES horizontal bands (render-tiles.sbatch,
# indexed by SLURM_ARRAY_TASK_ID) and a job that merges them once every band has succeeded
# (merge.sbatch, --dependency=afterok). Prints the merge job's id.
# usage: submit.sh SCENE.pbrt OUT.exr TILES [acr render arguments...]
#   ACR: the acr binary (default: acr on the PATH); tiles go to OUT's folder, tiles-OUTNAME/.
#   The paths must be visible to every node (a shared file system).
set -euo pipefail
[ $# -ge 3 ] || { sed -n 2,7p "$0" >&2; exit 2; }
here=$(cd "$(dirname "$0")" && pwd)
scene=$(realpath "$1"); out=$(realpath -m "$2"); tiles=$3; shift 3
acr=$(command -v "${ACR:-acr}") || { echo "acr not found (set ACR)" >&2; exit 2; }
out_dir="$(dirname "$out")/tiles-$(basename "$out" .exr)"
mkdir -p "$out_dir"
export ACR="$acr" SCENE="$scene" OUT_DIR="$out_dir" TILES="$tiles" OUT="$out" ACR_ARGS="$*"
array=$(sbatch --parsable --chdir="$out_dir" --array="0-$((tiles - 1))" --export=ALL \
  "$here/render-tiles.sbatch")
sbatch --parsable --chdir="$out_dir" --dependency="afterok:${array%%;*}" --export=ALL \
  "$here/merge.sbatch"
