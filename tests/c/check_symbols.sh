#!/usr/bin/env bash
# The dynamic symbol table of liboccseg.so holds exactly the functions occseg.h declares: no C++
# symbol of the static core or of libstdc++ leaks, and no declared function is missing.
# Usage: check_symbols.sh LIBRARY HEADER
set -euo pipefail
lib=$1 header=$2
exported=$(nm -D --defined-only "$lib" | awk '{print $3}' | sort)
# Every declaration starts a line with OCCSEG_API and names the function before its '('.
declared=$(grep -E '^OCCSEG_API ' "$header" | sed -E 's/\(.*//; s/.*[ *]//' | sort)
[ -n "$declared" ] || { echo "no OCCSEG_API declarations found in $header"; exit 1; }
leaked=$(grep -v '^occseg_' <<< "$exported" || true)
if [ -n "$leaked" ]; then
  echo "symbols outside occseg_* are exported:"; echo "$leaked" | head -20; exit 1
fi
if [ "$exported" != "$declared" ]; then
  echo "exported and declared functions differ (< exported only, > declared only):"
  diff <(echo "$exported") <(echo "$declared") || true
  exit 1
fi
soname=$(objdump -p "$lib" | awk '$1 == "SONAME" {print $2}')
[ "$soname" = "liboccseg.so.0" ] || { echo "SONAME is '$soname', expected liboccseg.so.0"; exit 1; }
echo "$(wc -l <<< "$exported") occseg_* functions exported, all declared in occseg.h; SONAME $soname"
