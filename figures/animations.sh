#!/usr/bin/env bash
# Regenerates the committed Poinsot animations (small GIFs); run from the repository root.
# Deterministic: the same versions of orbits, matplotlib and Pillow give the same bytes.
set -euo pipefail
out=figures/animations
small=(--frames 48 --fps 10 --dpi 72)
# the Dzhanibekov / tennis-racket flip of the paper's T-handle near its intermediate axis
orbits animate --preset t-handle --flip "${small[@]}" --out "$out/t_handle_flip.gif"
# a closed orbit of the catalog: Fig. 6's body, 2 pi * 3 on SAM, back at its start after T
orbits animate --preset fig6 --n 3 --branch SAM "${small[@]}" --out "$out/fig6_n3_SAM.gif"
# a real object: a phone (71 x 147 x 7.8 mm, 170 g) tossed at 2 rev/s close to its intermediate axis
orbits animate --box 0.071 0.147 0.0078 --mass 0.17 --name phone --flip 0.1 --speed 2 --units Hz \
    "${small[@]}" \
    --out "$out/phone_flip.gif"
