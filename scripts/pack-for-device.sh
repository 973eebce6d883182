#!/usr/bin/env bash
# Packs a build folder (default build/default) for a GPU machine as .dev/build.tar.xz: binaries
# (symbols stripped) and test lists, without object files or test logs (the folder itself is too
# large to travel). scripts/gpu-check.sh unpacks it there, at the same path. EXCLUDE: more
# patterns to leave out. With .gl/ holding the mesh and window libraries (37 MB), all the
# binaries (about 5 MB each, packed) do not fit one call's 64 MiB: pack and run a part at a time,
# e.g. EXCLUDE="deformlab_gl_tests deformlab_viewer_tests deformlab_unit_tests deformlab-bench" with
# PARTS=tests LABELS='match|cuda|interop', then the rest.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/default}
stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
excludes=(--exclude='*.o' --exclude='*.a' --exclude='CMakeFiles' --exclude='Testing')
for e in ${EXCLUDE:-}; do excludes+=(--exclude="$e"); done
tar -cf - "${excludes[@]}" "$build" | tar -xf - -C "$stage"
find "$stage" -type f -perm -u+x -exec sh -c 'file -b "$1" | grep -q ELF && strip "$1"' _ {} \;
mkdir -p .dev
tar -cf - -C "$stage" "$build" | xz -6 -T2 >.dev/build.tar.xz
ls -la .dev/build.tar.xz
