#!/usr/bin/env bash
# CI: on a one-node SLURM cluster started here, renders an example scene as a job array of
# four bands plus a merge job, and checks the merged image equals the single-process render
# exactly (MSE 0). usage: ci-check.sh ACR_BINARY
set -euo pipefail
acr=$(realpath "${1:?usage: ci-check.sh ACR_BINARY}")
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
work=$(mktemp -d)
"$here/one-node-cluster.sh"
scene="$root/scenes/cornell-box.pbrt"
args=(--spp 4 --filter gaussian --sampler halton)
merge_job=$(ACR="$acr" "$here/submit.sh" "$scene" "$work/merged.exr" 4 "${args[@]}")
echo "merge job $merge_job"
for _ in $(seq 1 600); do
  squeue -h -j "$merge_job" 2>/dev/null | grep -q . || break
  sleep 1
done
if [ ! -s "$work/merged.exr" ]; then
  echo "no merged image; job logs:" >&2
  tail -n 20 "$work"/tiles-merged/*.log >&2 || true
  exit 1
fi
"$acr" render "$scene" -o "$work/single.exr" --quiet "${args[@]}"
report=$("$acr" diff "$work/merged.exr" "$work/single.exr" --json)
echo "merged vs single process: $report"
echo "$report" | grep -q '"mse":0.0' || { echo "the merged frame differs" >&2; exit 1; }
rm -rf "$work"
echo "SLURM job array: merged frame equals the single-process render"
