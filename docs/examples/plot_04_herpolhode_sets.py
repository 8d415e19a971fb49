"""
Herpolhode sets
===============

The herpolhode is the path of the angular velocity's tip in the fixed
invariable plane (Poinsot).  After one period it has turned by ``Δα``
about the angular momentum, so it closes exactly for the orbits of the
catalog.  This page draws the set of a body's closed herpolhodes, shows
that those of odd multiples already close after half a period, and draws
a few fractional orbits ``2πp/q``.
"""

import matplotlib.pyplot as plt
import numpy as np

import orbits
from orbits.figures import contact_sheet

# sphinx_gallery_thumbnail_number = 2
body = orbits.Body.preset("fig6")
table = orbits.closed_orbits(body, n_max=7)

# %%
# The contact sheet
# -----------------
# All closed herpolhodes with ``n ≤ 7``, left to right in θ as in the
# paper's Fig. 6: SAM orbits with ``n`` rising towards θ_c, then LAM orbits
# with ``n`` falling.  ``orbits figures BODY --n-max N --out DIR`` writes the
# same sheet and one figure per orbit.
sheet = contact_sheet(body, table)

# %%
# Odd multiples close after half a period
# ---------------------------------------
# Over half a period the body-frame angular velocity is mirrored
# (``ω(t + T/2) = D ω(t)`` with ``D = diag(−1, −1, 1)`` on SAM) and the
# orientation picks up a turn by ``Δα/2 + π`` about the angular momentum.
# In the invariable plane the herpolhode's second half is its first half
# turned by ``π(n + 1)``: the same curve when ``n`` is odd.  Drawn over a
# full period, an odd-``n`` curve is traced twice.
fig, axes = plt.subplots(1, 2, figsize=(8.0, 4.2), layout="constrained")
for ax, n in zip(axes, (4, 5)):
    row = table[(table.branch == "SAM") & (table.n == n)].iloc[0]
    t, omega = orbits.herpolhode(body, dtheta=row.dtheta, periods=1, points=4001)
    half = len(t) // 2
    ax.plot(
        omega[: half + 1, 0],
        omega[: half + 1, 1],
        color="tab:purple",
        lw=2.5,
        label="first half period",
    )
    ax.plot(
        omega[half:, 0],
        omega[half:, 1],
        color="black",
        lw=0.8,
        ls="--",
        label="second half period",
    )
    ax.plot(*omega[0, :2], "o", color="black", label="start")
    ax.plot(*omega[half, :2], "x", color="black", ms=9, label="after T/2")
    ax.set_aspect("equal")
    ax.set_title(f"SAM, Δα = 2π·{n}: closes after {row.closes_after} T")
    ax.set_xlabel("ω_x (invariable plane)")
axes[0].set_ylabel("ω_y")
axes[1].legend(loc="lower left", fontsize="x-small")

# %%
# The same numerically: the angular velocity in space after half a period
# returns to its start for odd ``n`` (to rounding), not for even ``n``.
for n in range(2, 8):
    row = table[(table.branch == "SAM") & (table.n == n)].iloc[0]
    motion = orbits.Motion.from_spin(body, dtheta=row.dtheta)
    start, half = motion.omega_space([0.0, motion.period / 2])
    print(
        f"n = {n}: |omega_space(T/2) - omega_space(0)| = {np.linalg.norm(half - start):.1e}"
        f"   closes_after = {row.closes_after}"
    )

# %%
# Fractional orbits
# -----------------
# ``Δα = 2πp/q`` closes after ``q`` periods (``q/2`` when ``p`` and ``q``
# are both odd): star-like curves with ``q``-fold structure.
fractions = orbits.closed_orbits(body, n_max=4, q_max=5)
picks = [(7, 2), (10, 3), (11, 4), (17, 5)]
fig, axes = plt.subplots(1, len(picks), figsize=(10.0, 3.0), layout="constrained")
for ax, (p, q) in zip(axes, picks):
    row = fractions[(fractions.branch == "SAM") & (fractions.n == p) & (fractions.q == q)].iloc[0]
    t, omega = orbits.herpolhode(body, dtheta=row.dtheta, periods=q, points=600 * q + 1)
    ax.plot(omega[:, 0], omega[:, 1], color="tab:purple", lw=0.6)
    ax.plot(*omega[0, :2], "o", color="black", ms=3)
    ax.set_aspect("equal")
    ax.set_axis_off()
    ax.set_title(f"2π·{p}/{q}, {q} periods", fontsize="small")
plt.show()
