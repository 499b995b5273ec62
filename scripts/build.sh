#!/usr/bin/env bash
# Configures and builds occseg into build/ (Release, 2 parallel jobs), after installing missing
# Debian packages. Extra arguments go to cmake's configure step.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build build -j2
