#!/usr/bin/env bash
# Prints the SHA-256 of the labels occseg gives on the test and benchmark maps, both presets, one
# and two threads: a refactoring that must not change behaviour keeps this list identical.
# usage: scripts/label-hashes.sh [BUILD_DIR] > hashes.txt   (BUILD_DIR defaults to build)
set -euo pipefail
cd "$(dirname "$0")/.."
build=$(realpath "${1:-build}")
data=$(realpath ../shared/data)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
tool="$build/tools/occseg"
"$build/bench/occseg_bench_segment" make scene 320 320 128 "$work/scene.npy"
"$build/bench/occseg_bench_segment" make noisy 320 320 128 "$work/noisy.npy"
"$build/bench/occseg_bench_segment" make scene 100 70 45 "$work/odd.npy"
for s in cone cube cylinder table; do
  "$tool" simulate --scene "$s" --out "$work/sim-$s" >/dev/null
done
maps=("$work/scene.npy" "$work/noisy.npy" "$work/odd.npy" "$work"/sim-*/map.npy
      "$data/geb079.bt" "$data/spherical_scan.graph" "$data/table_scene_mug_stereo_textured.pcd"
      "$data/office1.pcd")
for m in "${maps[@]}"; do
  for preset in default paper; do
    for t in 1 2; do
      "$tool" segment "$m" --preset "$preset" --threads "$t" --out "$work/out" --outputs labels.npy --quiet
      printf '%s %s %s %s\n' "$(sha256sum < "$work/out/labels.npy" | cut -c1-16)" \
        "$(sed "s#^$work/##; s#^$data/#data/#" <<<"$m")" "$preset" "$t"
    done
  done
done
