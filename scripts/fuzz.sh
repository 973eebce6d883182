#!/usr/bin/env bash
# Runs each libFuzzer target (preset fuzz: scripts/setup.sh fuzz) for $1 seconds (default
# 60) from the committed seed corpus (tests/fuzz/corpus/TARGET), on a copy so the corpus in
# the repository stays as committed. A crash, a sanitizer report or an exception other than
# std::invalid_argument fails the script; the input is kept in build/fuzz/findings/.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
findings=build/fuzz/findings
mkdir -p "$findings"
for target in scene experiment mesh; do
  work=$(mktemp -d)
  cp tests/fuzz/corpus/$target/* "$work/"
  echo "fuzz: $target for ${seconds} s from $(ls "$work" | wc -l) seeds"
  build/fuzz/tests/fuzz/deformlab-fuzz-$target -max_total_time="$seconds" -max_len=4096 -rss_limit_mb=2048 \
    -timeout=10 -print_final_stats=1 -artifact_prefix="$findings/$target-" "$work" 2>&1 | tail -4
  rm -rf "$work"
done
