#!/usr/bin/env bash
# Builds and runs the README example with nothing but a C compiler and pkg-config, against the
# installed prefix, as the README tells a user to.  Usage: pkg_config_build.sh PREFIX LIBDIR SRC WORK
set -euo pipefail
prefix=$1 libdir=$2 src=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
export PKG_CONFIG_PATH="$prefix/$libdir/pkgconfig"
version=$(pkg-config --modversion occseg)
[ "$version" = "0.1.0" ] || { echo "pkg-config --modversion occseg: '$version', expected 0.1.0"; exit 1; }
flags=$(pkg-config --cflags --libs occseg)
echo "pkg-config --cflags --libs occseg: $flags"
case "$flags" in *"-I$prefix/include"*) ;; *) echo "cflags do not point into $prefix"; exit 1 ;; esac
# OCCSEG_EXTRA_CFLAGS: the sanitizer flags in a sanitizer build (a sanitized library needs them);
# OCCSEG_CC: the build's own C compiler there (its sanitizer runtime is the library's).
# shellcheck disable=SC2086
"${OCCSEG_CC:-cc}" -std=c99 -Wall -Wextra -pedantic -Werror "$src" -o "$work/example" $flags ${OCCSEG_EXTRA_CFLAGS:-}
LD_LIBRARY_PATH="$prefix/$libdir" "$work/example" > "$work/output.txt"
cat "$work/output.txt"
grep -q "^segment 1: occupied, 512 voxels, mop 0.90, bbox (12, 12, 12)-(19, 19, 19)$" "$work/output.txt"
# The binary really uses the installed library.
# (Captured first: with pipefail, `ldd | grep -q` fails when grep exits before ldd has written
# everything and ldd dies of SIGPIPE, which made this test flaky.)
deps=$(LD_LIBRARY_PATH="$prefix/$libdir" ldd "$work/example")
grep -q "liboccseg.so.0 => $prefix/$libdir/liboccseg.so.0" <<<"$deps"
echo "pkg-config build: ok"
