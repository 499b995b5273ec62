#!/usr/bin/env bash
# Regenerates docs/figures/: the experiments of docs/experiments.md (simulated scenes, both
# presets, the baseline and the ideal labelling, scored against ground truth) and the pictures
# like the paper's Figures 5-7. Builds first if needed. Takes about a minute on 2 cores.
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
