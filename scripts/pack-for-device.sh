#!/usr/bin/env bash
# Packs a build folder (default build/default) for a GPU machine in two archives:
#   .dev/base.tar.xz      the tree without object files, test logs or programs (test lists,
#                         shaders, data)
#   .dev/programs.tar.xz  every program, symbols stripped, in one solid xz stream whose
#                         dictionary spans them all: they share most of their code, so the
#                         archive is a few MB where the programs are 170
# e.g. carry .gl, .dev/base.tar.xz and .dev/programs.tar.xz, and run `scripts/gpu-check.sh`:
# it unpacks what .dev/ holds there, at the same paths.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/default}
stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
tar -cf - --exclude='*.o' --exclude='*.a' --exclude='CMakeFiles' --exclude='Testing' "$build" | tar -xf - -C "$stage"
rm -rf .dev
mkdir -p "$stage/programs" .dev
while IFS= read -r f; do
  file -b "$f" | grep -q ELF || continue
  strip "$f"
  mkdir -p "$stage/programs/$(dirname "${f#"$stage"/}")"
  mv "$f" "$stage/programs/${f#"$stage"/}"
done < <(find "$stage/$build" -type f -perm -u+x)
tar -cf - -C "$stage/programs" . | xz -9e --threads=1 >.dev/programs.tar.xz
tar -cf - -C "$stage" "$build" | xz -6 -T2 >.dev/base.tar.xz
ls -la .dev
