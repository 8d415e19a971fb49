#!/usr/bin/env bash
# Screenshots of the built documentation with headless Chromium, to look at
# what a reader sees: the index, a gallery page with figures and one with an
# embedded animation.  Build the docs first:
#     python -m sphinx -W --keep-going -b html docs docs/_build/html
# Usage: bash docs/screenshot.sh [OUT_DIR]   (default docs/_screenshots)
# Needs Chromium (Debian: apt-get install chromium).
set -euo pipefail
cd "$(dirname "$0")/.."
html="$PWD/docs/_build/html"
out="${1:-docs/_screenshots}"
browser="$(command -v chromium || command -v chromium-browser || command -v google-chrome || true)"
if [ -z "$browser" ]; then
    echo "screenshot.sh: no Chromium found (Debian: apt-get install chromium)" >&2
    exit 2
fi
if [ ! -f "$html/index.html" ]; then
    echo "screenshot.sh: $html/index.html missing; build the docs first" >&2
    exit 2
fi
mkdir -p "$out"
profile="$(mktemp -d)"
trap 'rm -rf "$profile"' EXIT

# shot PAGE NAME HEIGHT: a 1280-pixel-wide window of HEIGHT pixels
shot() {
    # --no-sandbox: CI and containers run as root; the pages are our own files.
    # The virtual-time budget lets MathJax and the animation player run first.
    "$browser" --headless --no-sandbox --disable-gpu --disable-dev-shm-usage \
        --hide-scrollbars --user-data-dir="$profile" --window-size="1280,$3" \
        --virtual-time-budget=8000 --screenshot="$out/$2.png" \
        "file://$html/$1" >/dev/null 2>&1
    [ -s "$out/$2.png" ] || { echo "screenshot.sh: no screenshot of $1" >&2; exit 1; }
    echo "$out/$2.png"
}

shot index.html index 1100
shot auto_examples/index.html gallery 1500
shot auto_examples/plot_02_real_objects.html real_objects 3000
shot auto_examples/plot_06_poinsot_animation.html poinsot_animation 1600
shot generated/orbits.total_phase.html api_total_phase 1400
