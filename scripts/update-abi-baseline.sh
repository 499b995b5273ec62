#!/usr/bin/env bash
# Regenerates the ABI baseline capi/abi/liboccseg.abi from a build of liboccseg.so. Run it only
# for an INTENTIONAL ABI change (new functions for a release, or a break that comes with a new
# SONAME), then commit the new baseline with the change; the ctest c_abi_baseline compares every
# build against it with abidiff. Usage: scripts/update-abi-baseline.sh [BUILD_DIR] (default build)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
cmake --build "$build" -j2 --target occseg
abidw --no-corpus-path --no-comp-dir-path --no-show-locs --exported-interfaces-only --drop-private-types \
      --type-id-style hash --headers-dir capi/include --headers-dir "$build/capi/include" \
      "$build/capi/liboccseg.so" | sed "s|path='$PWD/|path='|" > capi/abi/liboccseg.abi  # no host paths
echo "wrote capi/abi/liboccseg.abi ($(grep -c '<elf-symbol ' capi/abi/liboccseg.abi) functions)"
