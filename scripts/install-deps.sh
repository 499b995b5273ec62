#!/usr/bin/env bash
# Installs the Debian 12 packages occseg needs to build, test and benchmark, skipping what is there.
# Needs root (or sudo). Safe to run again.
set -euo pipefail
pkgs=(build-essential cmake pkg-config git
      libeigen3-dev libpng-dev zlib1g-dev nlohmann-json3-dev libcli11-dev
      libpcl-dev liboctomap-dev
      libgtest-dev libgmock-dev libcmocka-dev libbenchmark-dev
      abigail-tools valgrind clang libclang-rt-14-dev tmux
      python3-numpy python3-pytest python3-scipy)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "occseg: installing ${missing[*]}" >&2
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO=sudo
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi
