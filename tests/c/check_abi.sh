#!/usr/bin/env bash
# Compares liboccseg.so with the ABI baseline kept in the repository (capi/abi/liboccseg.abi).
# abidiff's exit code is a bit field: 1 error, 2 usage error, 4 ABI change, 8 incompatible ABI
# change. Only 0 and 4 pass: a compatible change (e.g. a new function) is reported but
# tolerated; to accept an intentional change run scripts/update-abi-baseline.sh.
# With --expect-break, checks instead that a baseline with a function the library lacks is
# reported as incompatible (so the check above can fail at all).
# Usage: check_abi.sh [--expect-break] BASELINE LIBRARY INCLUDE_DIR...
set -euo pipefail
expect_break=0
if [ "$1" = "--expect-break" ]; then expect_break=1; shift; fi
baseline=$1 lib=$2; shift 2
hd=(); for d in "$@"; do hd+=(--headers-dir2 "$d"); done
if ((expect_break)); then
  tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
  grep -q "'occseg_map_free'" "$baseline"
  sed "s/occseg_map_free/occseg_map_gone/g" "$baseline" > "$tmp/broken.abi"
  set +e; abidiff --drop-private-types "${hd[@]}" "$tmp/broken.abi" "$lib" > "$tmp/report"; rc=$?; set -e
  cat "$tmp/report"
  if (( rc & 8 )) && grep -q "occseg_map_gone" "$tmp/report"; then
    echo "abidiff flags a removed function as incompatible (exit $rc)"; exit 0
  fi
  echo "abidiff did not flag the removed function (exit $rc)"; exit 1
fi
set +e; abidiff --drop-private-types "${hd[@]}" "$baseline" "$lib"; rc=$?; set -e
case $rc in
  0) echo "ABI identical to $baseline" ;;
  4) echo "compatible ABI change against $baseline (tolerated; update the baseline when releasing)" ;;
  *) echo "abidiff exit $rc: ABI break or error against $baseline; if intended, run scripts/update-abi-baseline.sh"
     exit 1 ;;
esac
