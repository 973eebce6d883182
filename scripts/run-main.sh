#!/usr/bin/env bash
# The main job: set up, build, run the paper's drag experiment on the best pipeline this
# machine has (runs/paper-drag/), then the quick sweep of every pipeline here with its
# report (runs/quick/report.md). Extra arguments go to `deformlab run`.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh default
build/default/app/deformlab run --out runs/paper-drag "$@"
build/default/app/deformlab experiment quick --out runs/quick
