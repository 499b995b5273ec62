#!/usr/bin/env bash
# Sets up everything on a fresh Debian 12 machine and runs every test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
cd build
ctest -j2 --output-on-failure --timeout 600
