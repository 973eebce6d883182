#!/usr/bin/env bash
# Packs a build folder (default build/default) for a GPU machine as .dev/build.tgz: binaries
# (symbols stripped) and test lists, without object files or test logs (the folder itself is too
# large to travel). scripts/gpu-check.sh unpacks it there, at the same path. EXCLUDE: more
# patterns to leave out (e.g. "bench" when only the tests run there).
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
tar -czf .dev/build.tgz -C "$stage" "$build"
ls -la .dev/build.tgz
