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
# curves bound the physical region: prolate ``I2 = I3`` (top), oblate
# ``I1 = I2`` (right) and flat ``I3 = I1 + I2`` (lower left).  Along the
# dashed curve the two limits θ → 0 and θ → π/2 of Δα are equal, and the
# minimum has a kink.  No body reaches
# below ``2π`` (erratum 7).
fig2 = figure2(survey_grid(out))

# %%
# What else the tables say
# ------------------------
# A body has an orbit ``Δα = 2πn`` exactly when ``2πn`` lies above its
# minimum total phase, so the smallest multiple grows towards the sphere
# corner ``I1 = I2 = I3`` (right), where the minimum is largest.
# ``n_smallest`` is −1 for a body with no closed orbit up to ``n_max``.
none = bodies.n_smallest < 0
fig, ax = plt.subplots(figsize=(6.4, 4.2), layout="constrained")
ax.scatter(bodies.I1[none], bodies.I2[none], s=2, color="0.75", label="none with n ≤ 6")
cmap = plt.get_cmap("viridis", 5)
points = ax.scatter(
    bodies.I1[~none],
    bodies.I2[~none],
    c=bodies.n_smallest[~none],
    s=2,
    cmap=cmap,
    vmin=1.5,
    vmax=6.5,
)
fig.colorbar(points, ax=ax, ticks=range(2, 7), label="smallest n with Δα = 2πn")
ax.set_xlabel("I1 (|I| = 1)")
ax.set_ylabel("I2")
ax.set_aspect("equal")
ax.legend(loc="lower right", markerscale=4, fontsize="small")
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
