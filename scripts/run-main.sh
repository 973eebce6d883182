#!/usr/bin/env bash
# The main job: set up, build, and run the paper's drag experiment on the best pipeline
# this machine has. Extra arguments go to `deformlab run` (e.g. --out DIR).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh default
exec build/default/app/deformlab run --out runs/paper-drag "$@"
