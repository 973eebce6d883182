#!/usr/bin/env bash
# Set up, build, and run the whole test suite. GPU tests skip where there is no GPU.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh default
ctest --preset default -j2
