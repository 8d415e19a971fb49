#!/usr/bin/env bash
# Regenerates the committed catalogs; run from the repository root.
# tests/test_catalog.py runs these same commands and compares the results.
set -euo pipefail
orbits catalog --preset fig6 --n-max 30 --verify --out catalogs/fig6_n30.csv
orbits catalog --preset fig6 --n-max 30 --q-max 5 --verify --out catalogs/fig6_n30_q5.csv
orbits catalog --preset t-handle --n-max 30 --verify --out catalogs/t-handle_n30.csv
orbits catalog --preset t-handle --n-max 30 --q-max 5 --verify --out catalogs/t-handle_n30_q5.csv
