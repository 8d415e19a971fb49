#!/usr/bin/env bash
# Regenerates the committed figures; run from the repository root.
set -euo pipefail
orbits figures --paper --formats png --out figures/paper
orbits figures --preset fig6 --n-max 10 --formats png --out figures/fig6
