#!/usr/bin/env bash
# Packs a build folder (default build/default) for a GPU machine as .dev/build.tgz: binaries and
# test lists without object files (the folder itself is too large to travel). scripts/gpu-check.sh
# unpacks it there, at the same path.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/default}
mkdir -p .dev
tar -czf .dev/build.tgz --exclude='*.o' --exclude='*.a' --exclude='CMakeFiles' "$build"
ls -la .dev/build.tgz
