#!/usr/bin/env bash
# Regenerates docs/figures/: the experiments of docs/experiments.md (simulated scenes, both
# presets, the baseline and the ideal labelling, scored against ground truth), the pictures
# like the paper's Figures 5-7, the 3D pictures of the scenes (<scene>-scene.png) and the pictures
# `occseg segment` draws of a real map (geb079-*.png, from ../shared/data). Builds first if
# needed. Takes a few minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${OCCSEG_BUILD_DIR:-build}
[ -x "$build/tools/occseg" ] || bash scripts/build.sh
out=docs/figures
mkdir -p "$out"
# The paper's construction (a stack of 128 planar scans), every scene.
"$build/tools/occseg" figures --out "$out" --mode planar
# Full 3D scans from 3D viewpoints, two scenes.
"$build/tools/occseg" figures --out "$out" --mode full3d --scene cone --scene table
# A real map: the OctoMap of building 079 (Freiburg), as `occseg segment` draws it.
data=../shared/data
if [ -f "$data/geb079.bt" ]; then
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' EXIT
  "$build/tools/occseg" segment "$data/geb079.bt" --out "$tmp" --quiet
  cp "$tmp/scene.png" "$out/geb079-scene.png"
  cp "$tmp/segmentation.png" "$out/geb079-slices.png"
else
  echo "make-figures: $data/geb079.bt not found; geb079-*.png not regenerated" >&2
fi
