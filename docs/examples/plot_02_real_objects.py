"""
Real objects: a phone, a T-handle, a tennis racket, a molecule, an asteroid
===========================================================================

Any rigid body with three different principal moments is an asymmetric
top.  Here are five, built from their shapes, masses or spectra, with
their moments in SI units (kg m²), so that every time printed is in
seconds (or hours for the asteroid).

For each body we ask the question of the *tennis-racket theorem*: thrown
spinning about its intermediate axis, tipped off it by a small angle, how
long until it flips over?  The spin near the intermediate axis lies close
to the separatrix; the body turns over twice per period ``T`` of its
angular velocity in the body, so once every ``T/2``.
"""

import warnings

import matplotlib.pyplot as plt
import numpy as np

import orbits
from orbits import Body, Motion
from orbits.animate import flip_motion
from orbits.plotting import plot_body_space

# %%
# Five bodies
# -----------
# **A phone**: a uniform box 146 × 71 × 8 mm of 170 g
# (``I_x = m (b² + c²)/12`` and cyclically).
phone = Body.box(0.146, 0.071, 0.008, mass=0.170, name="phone")

# %%
# **The paper's T-handle** (cross piece 8, shaft 4, square section 1, unit
# mass; eqn:IsforT), the body of the "dancing T-handle" filmed on the ISS.
t_handle = Body.preset("t-handle")

# %%
# **A tennis racket** as a set of point masses (a crude model, in m and
# kg): a handle of 100 g along y, 0.30 m long, and an oval hoop of 180 g,
# semi-axes 0.13 m (x) and 0.16 m (y), centred 0.46 m up.
handle_y = np.linspace(0.0, 0.30, 11)
handle = np.column_stack([np.zeros_like(handle_y), handle_y, np.zeros_like(handle_y)])
angle = np.linspace(0.0, 2.0 * np.pi, 36, endpoint=False)
hoop = np.column_stack([0.13 * np.cos(angle), 0.46 + 0.16 * np.sin(angle), np.zeros_like(angle)])
masses = np.concatenate(
    [np.full(len(handle), 0.100 / len(handle)), np.full(len(hoop), 0.180 / len(hoop))]
)
racket = Body.from_point_masses(masses, np.vstack([handle, hoop]), name="tennis racket")

# %%
# **A molecule**, formaldehyde H₂CO, from its ground-state rotational
# constants (MHz; Johns & McKellar 1973).  A planar molecule should have
# ``I_C = I_A + I_B``; measured constants give a small positive *inertial
# defect* (vibration-rotation coupling).  ``defect="flatten"`` puts the body
# on the flat edge of the physical region and says by how much it moved it
# (the default refuses).
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    formaldehyde = Body.from_rotational_constants(
        281970.5, 38833.99, 34004.24, unit="MHz", defect="flatten", name="formaldehyde"
    )
print(caught[0].message)

# %%
# **The tumbling asteroid (99942) Apophis**, with the moment ratios that
# Pravec et al. (2014, Icarus 233, 48) fitted to its light curves:
# ``I_a/I_c = 0.61``, ``I_b/I_c = 0.965``.
apophis = Body((0.61, 0.965, 1.0), name="Apophis")

bodies = [phone, t_handle, racket, formaldehyde, apophis]
print(f"{'body':14s} {'I1, I2, I3 (as given)':>30s}   {'|I| = 1':>20s}   theta_c")
for body in bodies:
    given = ", ".join(f"{v:.3g}" for v in body.moments)
    unit = ", ".join(f"{v:.4f}" for v in body.normalized_moments)
    print(f"{body.name:14s} {given:>30s}   {unit:>20s}   {body.critical_angle():.4f}")

# %%
# Where they sit in body space
# ----------------------------
# The paper's Fig. 2 map of the physical moments (``|I| = 1``, ``I1 < I2 <
# I3``), coloured by the smallest total phase any spin of that body can
# have.  The phone and the formaldehyde molecule are nearly flat
# (``I3 ≈ I1 + I2``); Apophis is close to the prolate edge (``I2 ≈ I3``).
fig, ax = plt.subplots(figsize=(7.0, 5.6), layout="constrained")
plot_body_space(ax, resolution=120)
markers = "os^Dv"
# label offsets (points): three of the bodies are close together
offsets = [(8, -10), (8, 4), (8, -2), (-30, 10), (-24, -16)]
for body, marker, offset in zip(bodies, markers, offsets):
    i1, i2, _ = body.normalized_moments
    ax.plot(i1, i2, marker, color="white", markeredgecolor="black", markersize=8)
    ax.annotate(
        body.name,
        (i1, i2),
        xytext=offset,
        textcoords="offset points",
        color="white",
        fontsize="small",
        fontweight="bold",
    )
ax.set_title("Five real bodies in the body space of Fig. 2")

# %%
# How long until it flips?
# ------------------------
# Spin each body at 2 turns per second about its intermediate axis, tipped
# by 0.05 rad towards the other two (:func:`orbits.animate.flip_motion`).
# The time between flips grows only like ``log(1/offset)``.  (Apophis and
# the molecule spin far slower or faster in reality; this is the same
# throw for every body.)
speed = 2 * 2 * np.pi  # rad/s
print(f"{'body':14s} {'T (s)':>9s} {'flip every (s)':>15s}")
for body in bodies:
    motion = flip_motion(body, offset=0.05, speed=speed)
    print(f"{body.name:14s} {motion.period:9.3f} {motion.period / 2:15.3f}")

# %%
# The phone's flip, seen in its angular velocity: the component along the
# intermediate axis (the phone's long edge is I1, its short edge I2)
# reverses every half period while the other two pulse.
motion = flip_motion(phone, offset=0.05, speed=speed)
t = np.linspace(0.0, 2.0 * motion.period, 1500)
omega = motion.omega(t)
fig, ax = plt.subplots(figsize=(7.0, 3.4), layout="constrained")
for k, (name, style) in enumerate(
    [("ω₁ (long axis)", "-"), ("ω₂ (intermediate)", "--"), ("ω₃ (normal to the screen)", "-.")]
):
    ax.plot(t, omega[:, k], style, label=name)
for j in range(1, 4):
    ax.axvline(j * motion.period / 2, color="0.7", linewidth=0.8)
ax.set_xlabel("time (s)")
ax.set_ylabel("ω in the body (rad/s)")
ax.set_title(
    f"A phone thrown at 2 rev/s about its intermediate axis: "
    f"a flip every {motion.period / 2:.2f} s"
)
ax.legend(fontsize="small", loc="lower right")

# %%
# Apophis from its light-curve periods
# ------------------------------------
# Observers give a tumbling asteroid's two periods: the precession ``P_φ``
# of its axis about the angular momentum and the rotation ``P_ψ`` about
# its own axis.  Their ratio fixes the spin (one per branch); ``P_ψ`` then
# fixes its rate.  Pravec et al. (2014) give ``P_φ = 27.38 h``,
# ``P_ψ = 263 h`` and a strongest light-curve period ``P_1 = 30.56 h`` on
# the short-axis mode (SAM).  :func:`orbits.spins_with_periods` takes the
# periods in any one unit and answers in it (the command line:
# ``orbits phase --moments 0.61 0.965 1 --periods 263 27.38 --time-unit h``).
spins = orbits.spins_with_periods(apophis, 263.0, 27.38)  # hours in, hours out
sam = spins[spins["branch"] == "SAM"].iloc[0]
print(f"theta = {sam['theta']:.6f} rad (theta_c = {apophis.critical_angle():.6f})")
print(
    f"P_phi = {sam['P_phi']:.2f} h, P_psi = {sam['P_psi']:.1f} h, "
    f"P_1 = 2 pi T / Delta alpha = {sam['P_about_L']:.2f} h (observed 30.56 h)"
)
print(f"E/E0 = 2 E I3 / M^2 = {sam['E_over_E0']:.4f} (observed 1.024 +- 0.013)")
print(spins[["branch", "P_psi", "P_phi", "P_about_L", "E_over_E0"]])
# the row's spin (principal axes, rad/h) is a Motion whose period is P_psi
motion = Motion.from_omega(apophis, sam[["w1", "w2", "w3"]].to_numpy(dtype=float))
print(f"Motion from (w1, w2, w3): T = {motion.period:.6f} h")
plt.show()
