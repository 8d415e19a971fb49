"""
Quick tour
==========

A body, a spin, its phases, its exact motion and its closed orbits, in a
dozen lines.  Angles are in radians, ``|ω₀| = 1`` and times are in units of
``1/|ω₀|`` unless a body carries physical units.
"""

import matplotlib.pyplot as plt
import numpy as np

import orbits
from orbits.plotting import plot_herpolhode, plot_total_phase

# %%
# A body and its total phase
# --------------------------
# The paper's Fig. 6 body, moments normalised to ``|I| = 1``.  The
# critical angle θ_c separates the short-axis (SAM) and long-axis (LAM)
# modes.
body = orbits.Body.preset("fig6")
print(body)
print("theta_c =", body.critical_angle())
print(orbits.phases(body, [0.5, 1.2]).T)

# %%
# Near the separatrix the phase diverges like ``log(1/|θ − θ_c|)``.  Pass
# the offset ``dtheta`` there: θ itself would round to θ_c.
print(orbits.total_phase(body, dtheta=[-1e-3, -1e-30, -1e-300]))

# %%
# Closed orbits
# -------------
# The spins whose total phase is a whole number of turns, ``Δα = 2πn``:
# after one period the body is back where it started.
orbit_table = orbits.closed_orbits(body, n_max=6)
print(orbit_table[["branch", "n", "theta", "dtheta", "total_phase", "period"]])

fig, ax = plt.subplots(figsize=(6.4, 4.2), layout="constrained")
plot_total_phase(ax, body, orbit_table)
ax.set_title("Total phase of the Fig. 6 body; closed orbits marked")

# %%
# The exact motion
# ----------------
# :class:`orbits.Motion` evaluates the closed-form solution at any time:
# the angular velocity in the body, the Euler angles, the rotation matrix.
# After one period the orientation is a rotation by Δα about the angular
# momentum (here the z axis of the space frame).
motion = orbits.Motion.from_spin(body, 0.9)
R0, R1 = motion.rotation([0.0, motion.period])
turn = R1 @ R0.T
print("Delta alpha       =", motion.total_phase())
print("angle of R(T)R(0)^-1 about z =", np.arctan2(turn[1, 0], turn[0, 0]) % (2 * np.pi))
print("total phase mod 2 pi          =", motion.total_phase() % (2 * np.pi))

# %%
# The herpolhode of a closed orbit
# --------------------------------
# The tip of ω traced in the space frame closes after one period exactly
# when ``Δα = 2πn``.
row = orbit_table[(orbit_table.branch == "SAM") & (orbit_table.n == 4)].iloc[0]
fig, ax = plt.subplots(figsize=(4.2, 4.2), layout="constrained")
plot_herpolhode(ax, body, dtheta=row.dtheta)
ax.set_title(f"SAM, Δα = 2π·4, θ = {row.theta:.6f}")
plt.show()
