"""
The tumbling asteroid 4179 Toutatis
===================================

Toutatis, a 4.6 km near-Earth asteroid, does not spin about one axis: it
tumbles in a *long-axis mode* (LAM), rotating about its long axis while
that axis precesses about the fixed angular momentum.  Radar and the
Chang'e-2 flyby gave its two periods:

* Hudson & Ostro (1995, Science 270, 84): rotation about the long axis
  :math:`P_\\psi` = 5.41 d, mean precession of the long axis
  :math:`P_\\phi` = 7.35 d;
* Zhao et al. (2015, MNRAS, arXiv:1504.02024): 5.38 d and 7.40 d,
  ± 0.03 d in Zhao, Hu & Ji (2016, IAU Symp. 318, 156).

Takahashi, Busch & Scheeres (2013, AJ 146, 95) fitted Toutatis' spin
state and moments of inertia to the radar observations of 1992–2008.
Their Table 2 is used below *as quoted in the Toutatis test of
Principia's Euler solver* (mockingbirdnest/Principia,
``physics/euler_solver_test.cpp``):

* principal moments 1, 3.0836, 3.235 (long axis smallest);
* at 1992-11-09T17:49:47 UTC: angular velocity (−98.5, 14.5, 33.7) deg/d
  along their x, y, z; ZXZ Euler angles (147.5°, 63.9°, 241.5°); angular
  momentum toward ICRS latitude −54.75°, longitude 180.2°;
* at 1992-12-02T21:40:00 UTC, 23.16 d later: (−97.0, −35.6, 7.2) deg/d;
  Euler angles (122.2°, 86.5°, 107.0°).

Which moment goes with which of their axes is checked first, from the
numbers alone.  Then the exact motion (``orbits.Motion``) gives the LAM
periods beside the observed ones and carries the spin to the later date,
beside Takahashi et al.'s values and a direct integration of Euler's
equations.
"""

import itertools

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from orbits import Body, Motion

DEG = np.pi / 180.0  # deg/d -> rad/d: times below are in days
moments = np.array([1.0, 3.0836, 3.235])
toutatis = Body(moments, name="4179 Toutatis (Takahashi et al. 2013)")
omega_epoch = np.array([-98.5, 14.5, 33.7])  # deg/d, Takahashi's x, y, z
omega_later = np.array([-97.0, -35.6, 7.2])  # deg/d, 1992-12-02T21:40 UTC
elapsed = 23.16  # d, from 1992-11-09T17:49:47 to 1992-12-02T21:40:00 UTC
published = {"Hudson & Ostro 1995": (5.41, 7.35), "Zhao et al. 2015": (5.38, 7.40)}

# %%
# Which moment belongs to which axis
# ----------------------------------
# Each row puts Takahashi et al.'s x, y, z components along the principal
# axes I1 < I2 < I3 in one of the six orders and gives the branch and the
# periods of the resulting motion.  "x y z" (their x the long axis,
# moment 1; y with 3.0836; z with 3.235) reproduces the observed periods;
# "x z y" misses them by 1–3 %, and the other four are far off.  In
# particular "z x y" (their x along I2, y along I3, z along I1), which
# Principia's comment on the axes might suggest, gives 12.0 d and 3.7 d.
# Principia's code pairs their x component with the moment 1; the comment
# concerns the order of the body axes of the Euler angles, in which the
# long axis comes third, as checked next.

print("their axes along I1, I2, I3: branch, P_psi (d), P_phi (d)")
for order in itertools.permutations(range(3)):
    omega = np.empty(3)
    omega[list(order)] = omega_epoch  # Takahashi's axis k along I_(order[k]+1)
    trial = Motion.from_omega(toutatis, omega * DEG, axes="principal")
    periods = trial.tumbling_periods()
    label = " ".join("xyz"[order.index(k)] for k in range(3))
    print(f"  {label}: {trial.branch}  {periods.rotation:6.3f}  {periods.precession:6.3f}")

# %%
# The same assignment is what makes the Euler angles and the direction of
# the angular momentum agree: with the body axes of the ZXZ angles taken
# as (y, z, x), the epoch attitude carries the body's angular momentum
# :math:`I\\omega` to within a fraction of a degree of the published
# direction (two independent numbers of Table 2).
to_euler_axes = np.array([[0, 1, 0], [0, 0, 1], [1, 0, 0]])  # (x,y,z) -> (y,z,x)
attitude_epoch = Rotation.from_euler("ZXZ", [147.5, 63.9, 241.5], degrees=True).as_matrix()
lat, lon = np.radians(-54.75), np.radians(180.2)
momentum_icrs = np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])
momentum_body = to_euler_axes @ (moments * omega_epoch)
carried = attitude_epoch @ momentum_body / np.linalg.norm(momentum_body)
print(
    "angle between R(epoch) I omega and the published L direction: "
    f"{np.degrees(np.arccos(carried @ momentum_icrs)):.2f} deg"
)

# %%
# Periods
# -------
# The exact motion from the epoch spin, in days: its branch, ``D =
# M^2/2E`` (LAM: below I2), the rotation period :math:`P_\\psi = T` (the
# period of ω in the body) and the mean precession period :math:`P_\\phi`
# of the long axis about L (``Motion.tumbling_periods``), beside the
# observed periods.
motion = Motion.from_omega(toutatis, omega_epoch * DEG, axes="principal")
periods = motion.tumbling_periods()
print(
    f"{toutatis.name}: branch {motion.branch}, D = {motion.D:.5f} (I2 = {moments[1]}), "
    f"axis {periods.axis}"
)
print(f"{'':22s} {'P_psi (d)':>9s} {'P_phi (d)':>9s} {'dP_psi':>8s} {'dP_phi':>8s}")
print(f"{'orbits (Takahashi)':22s} {periods.rotation:9.4f} {periods.precession:9.4f}")
for source, (p_psi, p_phi) in published.items():
    print(
        f"{source:22s} {p_psi:9.2f} {p_phi:9.2f} "
        f"{periods.rotation / p_psi - 1:+8.2%} {periods.precession / p_phi - 1:+8.2%}"
    )
print(f"mean rotation about L, 2 pi T / Delta alpha: {periods.about_momentum:.4f} d")

# %%
# Takahashi et al.'s moments and epoch spin reproduce Zhao et al.'s
# periods to their last digit, and Hudson & Ostro's to 0.6 % and 0.7 %.
#
# A uniform ellipsoid with Hudson & Ostro's dimensions (1.92, 2.40, 4.60
# km) has markedly different moment ratios; the same spin would tumble
# with other periods, so the periods do constrain the mass distribution
# once the spin is known.
ellipsoid = Body.from_semi_axes(4.60 / 2, 2.40 / 2, 1.92 / 2, name="uniform ellipsoid")
uniform = Motion.from_omega(ellipsoid, omega_epoch * DEG, axes="principal").tumbling_periods()
print(
    f"uniform ellipsoid: I/I1 = {(ellipsoid.moments / ellipsoid.moments[0]).round(4)}, "
    f"same spin: P_psi = {uniform.rotation:.3f} d, P_phi = {uniform.precession:.3f} d"
)

# %%
# 23.16 days later
# ----------------
# The exact motion at 1992-12-02T21:40 UTC, a DOP853 integration of
# Euler's equations (rtol 1e-12) that knows nothing of the closed form,
# and Takahashi et al.'s value, in deg/d along their x, y, z.
i1, i2, i3 = moments


def euler(_, w):
    return [
        (i2 - i3) * w[1] * w[2] / i1,
        (i3 - i1) * w[2] * w[0] / i2,
        (i1 - i2) * w[0] * w[1] / i3,
    ]


span = 60.0  # days shown in the figure
integration = solve_ivp(
    euler,
    (0.0, span),
    omega_epoch * DEG,
    method="DOP853",
    rtol=1e-12,
    atol=1e-14,
    dense_output=True,
)
exact_later = motion.omega(elapsed) / DEG
integrated_later = integration.sol(elapsed) / DEG
print(f"{'at +23.16 d (deg/d)':24s} {'x':>9s} {'y':>9s} {'z':>9s}")
for label, value in (
    ("orbits (exact)", exact_later),
    ("integration (DOP853)", integrated_later),
    ("Takahashi et al. 2013", omega_later),
):
    print(f"{label:24s} {value[0]:9.4f} {value[1]:9.4f} {value[2]:9.4f}")
print(f"|exact - integration| = {np.abs(exact_later - integrated_later).max():.1e} deg/d")
print(f"|exact - Takahashi|   = {np.linalg.norm(exact_later - omega_later):.2f} deg/d")

# %%
# The closed form and the integration agree to the integrator's accuracy.
# Takahashi et al.'s later spin differs from the torque-free prediction by
# a few deg/d, more than the rounding of their table (0.1 deg/d): the
# two conserved quantities of torque-free motion, ``|L|`` and ``2E``, differ
# by 3–4 % between their two states (below), and the direction of L
# given by their later spin and Euler angles lies 15° from the published
# one (0.16° at the epoch), so no torque-free motion of this body joins
# the two states exactly.  (Their fit is not of torque-free motion
# alone: it models the tidal torques on Toutatis.)  The attitude follows
# the same pattern: carried forward from the epoch angles, the exact
# motion gives the Euler angles below, beside theirs.
later = moments * omega_later
print(
    "Takahashi's later / epoch state: |L| ratio "
    f"{np.linalg.norm(later) / np.linalg.norm(moments * omega_epoch):.4f}, "
    f"2E ratio {later @ omega_later / ((moments * omega_epoch) @ omega_epoch):.4f}"
)
attitude_later = Rotation.from_euler("ZXZ", [122.2, 86.5, 107.0], degrees=True).as_matrix()
direction = attitude_later @ to_euler_axes @ later / np.linalg.norm(later)
print(
    "their later state's L direction is "
    f"{np.degrees(np.arccos(direction @ momentum_icrs)):.1f} deg from the published one"
)
# principal -> ICRS at t: R_epoch (principal -> ICRS at 0) R_L(0)^T R_L(t),
# R_L the closed form's body -> (z along L) orientation
principal_to_icrs = attitude_epoch @ to_euler_axes
carried = principal_to_icrs @ motion.rotation(0.0).T @ motion.rotation(elapsed)
angles = Rotation.from_matrix(carried @ to_euler_axes.T).as_euler("ZXZ", degrees=True) % 360
print(f"Euler angles ZXZ at +23.16 d: orbits {angles.round(1)}, Takahashi [122.2  86.5 107. ]")

# %%
# ω over 60 days
# --------------
# The three components of ω along Takahashi et al.'s axes: lines from the
# closed form, open markers from the integration (every 1.5 days), filled
# diamonds Takahashi et al.'s two published states.
t = np.linspace(0.0, span, 1201)
exact = motion.omega(t) / DEG
marks = np.arange(0.0, span + 1e-9, 1.5)
integrated = integration.sol(marks).T / DEG
fig, ax = plt.subplots(figsize=(7.5, 4.2), layout="constrained")
for k, (name, colour) in enumerate(zip("xyz", ("C0", "C1", "C2"))):
    ax.plot(t, exact[:, k], color=colour, lw=1.2, label=f"$\\omega_{name}$ (exact)")
    ax.plot(marks, integrated[:, k], "o", mfc="none", color=colour, ms=4)
    ax.plot([0.0, elapsed], [omega_epoch[k], omega_later[k]], "D", color=colour, mec="k", ms=6)
ax.plot([], [], "o", mfc="none", color="0.3", ms=4, label="integration (DOP853)")
ax.plot([], [], "D", color="0.6", mec="k", ms=6, label="Takahashi et al. 2013")
ax.axhline(0.0, color="0.8", lw=0.6)
ax.set_xlabel("time since 1992-11-09T17:49:47 UTC (days)")
ax.set_ylabel("angular velocity (deg/day)")
ax.set_title("4179 Toutatis: body-frame angular velocity (moments 1 : 3.0836 : 3.235)")
ax.legend(loc="center", bbox_to_anchor=(0.5, 0.3), fontsize=8, ncols=3)
plt.show()
