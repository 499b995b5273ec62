#!/usr/bin/env bash
# Builds the outside OctoMap-adapter program with nothing but g++ and pkg-config occseg-octomap,
# against the installed prefix, and runs it. Usage: adapters_pkg_config.sh PREFIX LIBDIR SRC WORK
set -euo pipefail
prefix=$1 libdir=$2 src=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
export PKG_CONFIG_PATH="$prefix/$libdir/pkgconfig"
[ "$(pkg-config --modversion occseg-octomap)" = "0.1.0" ] || { echo "occseg-octomap.pc: wrong or no version"; exit 1; }
flags=$(pkg-config --cflags --libs occseg-octomap)
echo "pkg-config --cflags --libs occseg-octomap: $flags"
case "$flags" in *"-I$prefix/include"*"-loccseg_octomap"*) ;; *) echo "flags do not point into $prefix"; exit 1 ;; esac
# (OCCSEG_CXX, OCCSEG_EXTRA_CFLAGS: a sanitizer build's compiler and flags; see pkg_config_build.sh)
# shellcheck disable=SC2086
"${OCCSEG_CXX:-g++}" -std=c++17 -Wall -Wextra "$src" -o "$work/octomap_app" $flags ${OCCSEG_EXTRA_CFLAGS:-} -Wl,-rpath,"$prefix/$libdir"
"$work/octomap_app" "$work/segments.ot" | tee "$work/output.txt"
grep -q "^grid 3 x 1 x 1, segments.ot: 3 leaves of 0.1 m$" "$work/output.txt"
deps=$(ldd "$work/octomap_app")
grep -q "liboccseg_octomap.so.0 => $prefix/$libdir/liboccseg_octomap.so.0" <<<"$deps"
echo "pkg-config occseg-octomap build: ok"
