#!/bin/bash
# Renders pbrt-v3 scenes with acr and with pbrt-v3 on one crop at one spp and compares them
# (docs/pbrt-v3-compatibility.md, "The official pbrt-v3 scenes at hand").
# Usage: compare_with_pbrt_v3.sh PBRT ACR SPP OUTDIR SCENE.pbrt...
# Env: CROP (default "0.4 0.6 0.4 0.6"), THREADS (2), LIMIT (seconds per render, 120).
# Each scene is copied beside itself with its pixelsamples (and sppm's numiterations) set to
# SPP, so that its relative file names resolve; the copy is removed afterwards.
set -u
pbrt=$(realpath "$1"); acr=$(realpath "$2"); spp=$3; out=$(realpath -m "$4"); shift 4
crop=${CROP:-0.4 0.6 0.4 0.6}; threads=${THREADS:-2}; limit=${LIMIT:-120}
mkdir -p "$out"
for scene in "$@"; do
  dir=$(dirname "$scene"); name=$(basename "$scene" .pbrt)
  copy="$dir/$name-spp$spp.pbrt"
  sed -E "s/(\"integer (pixelsamples|numiterations)\"[[:space:]]*)\[?[[:space:]]*[0-9]+[[:space:]]*\]?/\1[$spp]/" \
    "$scene" > "$copy"
  (cd "$dir" && timeout "$limit" "$pbrt" --quiet --nthreads "$threads" --cropwindow $crop \
    --outfile "$out/$name-pbrt.exr" "$(basename "$copy")" > "$out/$name-pbrt.log" 2>&1)
  echo "$name: pbrt-v3 exit $?"
  timeout "$limit" "$acr" render "$copy" --spp "$spp" --seed 1 --threads "$threads" \
    --cropwindow "${crop// /,}" -o "$out/$name-acr.exr" --quiet > "$out/$name-acr.log" 2>&1
  echo "$name: acr exit $?"
  rm -f "$copy"
  if [ -f "$out/$name-acr.exr" ] && [ -f "$out/$name-pbrt.exr" ]; then
    echo "$name: $("$acr" diff "$out/$name-acr.exr" "$out/$name-pbrt.exr" 2>&1)"
  fi
done
