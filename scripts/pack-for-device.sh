#!/usr/bin/env bash
# Packs a build folder (default build/default) for a GPU machine, one archive a part, so that a
# call carries only what it runs (.gl/ and every program together exceed one call's 64 MiB):
#   .dev/base.tar.xz       the tree without object files, test logs or programs (test lists,
#                          shaders, data)
#   .dev/<program>.tar.xz  each program, its symbols stripped (about 5 MB each)
# e.g. carry .gl, .dev/base.tar.xz and .dev/deformlab_cuda_tests.tar.xz, and run
# `PARTS=tests LABELS=cuda scripts/gpu-check.sh`: it unpacks what .dev/ holds there, at the same
# paths, and refuses to start when a chosen test's program is missing (the gl, viewer and cli
# tests run deformlab itself, so carry .dev/deformlab.tar.xz with those labels).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/default}
stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
tar -cf - --exclude='*.o' --exclude='*.a' --exclude='CMakeFiles' --exclude='Testing' "$build" | tar -xf - -C "$stage"
mkdir -p .dev
programs=()
while IFS= read -r f; do
  file -b "$f" | grep -q ELF || continue
  strip "$f"
  programs+=("${f#"$stage"/}")
done < <(find "$stage" -type f -perm -u+x)
for p in "${programs[@]}"; do
  tar -cf - -C "$stage" "$p" | xz -6 -T2 >".dev/$(basename "$p").tar.xz"
  rm "$stage/$p"
done
tar -cf - -C "$stage" "$build" | xz -6 -T2 >.dev/base.tar.xz
ls -la .dev
