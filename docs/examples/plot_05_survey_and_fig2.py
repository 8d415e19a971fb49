"""
A small survey and the paper's Fig. 2
=====================================

A survey runs the closed-orbit search over many bodies at once: every
body of a grid over the physical region of the ``I1–I2`` plane
(``|I| = 1``, ``I1 ≤ I2 ≤ I3``, triangle inequality).  It writes a
directory of Parquet parts with a manifest, resumable and checked, and
is read back as two tables: one row per body and one per closed orbit.
``orbits survey --resolution N --n-max K --out DIR`` does the same from
the command line, locally or on a dask.distributed cluster.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from orbits.figures import figure2
from orbits.survey import Survey, read_survey, survey_grid

# %%
# Run it
# ------
# A 150 × 150 grid (8670 of its points are physical bodies), closed orbits
# up to ``n = 6``.
out = Path(tempfile.mkdtemp()) / "survey"
report = Survey.grid(out, 150, n_max=6).run()
bodies, found = read_survey(out)
print(f"{len(bodies)} bodies, {len(found)} closed orbits")
print(bodies[["I1", "I2", "I3", "theta_crit", "min_total_phase", "orbits", "n_smallest"]].head())

# %%
# The paper's Fig. 2
# ------------------
# The survey's bodies table holds each body's smallest total phase over all
# spins, ``min_total_phase``; on the grid it is the map of Fig. 2.  The red
# curves bound the physical region (prolate ``I1 → 0``, oblate ``I2 = I3``,
# flat ``I3 = I1 + I2``); along the dashed curve the two limits θ → 0 and
# θ → π/2 of Δα are equal, and the minimum has a kink.  No body reaches
# below ``2π`` (erratum 7).
fig = figure2(survey_grid(out))
fig

# %%
# What else the tables say
# ------------------------
# A body has an orbit ``Δα = 2πn`` exactly when ``n`` lies above its
# minimum, so the smallest multiple grows towards the oblate corner, where
# the minimum total phase is largest.
fig, ax = plt.subplots(figsize=(6.4, 4.2), layout="constrained")
points = ax.scatter(bodies.I1, bodies.I2, c=bodies.n_smallest, s=2, cmap="viridis")
fig.colorbar(points, ax=ax, label="smallest n with a closed orbit Δα = 2πn")
ax.set_xlabel("I1 (|I| = 1)")
ax.set_ylabel("I2")
ax.set_aspect("equal")
ax.set_title("Survey: the smallest closed-orbit multiple of each body")

# %%
# The orbits table is a catalog of all the bodies together (the ``body``
# column is the body's row in the bodies table).  For instance the share
# of SAM and LAM orbits with each ``n``, and how many close after half a
# period:
counts = found.groupby(["n", "branch"]).size().unstack()
print(counts)
print(found.closes_after.value_counts())
print("largest |residual| / (2 pi n):", np.max(np.abs(found.residual) / (2 * np.pi * found.n)))
plt.show()
