#!/usr/bin/env bash
# Sets up everything on a fresh Debian 12 machine and runs the main job: the demo, which
# simulates the paper's cone scene, segments it and writes everything to ./occseg-out/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
./build/tools/occseg demo "$@"
