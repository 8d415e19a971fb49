#!/usr/bin/env bash
# Regenerates the committed figures and animations; run from the repository root.
# After an intended change to a figure, also redraw the image-test baselines:
#   PYTHONPATH=. python tests/baseline/regenerate.py
set -euo pipefail
orbits figures --paper --formats png --out figures/paper
orbits figures --preset fig6 --n-max 10 --formats png --out figures/fig6
bash figures/animations.sh
