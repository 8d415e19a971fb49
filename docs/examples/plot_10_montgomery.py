"""
Montgomery's formula against a direct integration of the attitude
=================================================================

Montgomery (R. Montgomery, "How much does the rigid body rotate? A Berry's
phase from the 18th century", Am. J. Phys. **59**, 394 (1991)) showed that
after one period :math:`T` of the angular velocity in the body, a free
rigid body has turned about its fixed angular momentum by

.. math::

    \\Delta\\alpha = \\frac{2ET}{M} - \\Omega ,

the dynamic phase :math:`2ET/M` less the solid angle :math:`\\Omega`
enclosed by the path of :math:`\\mathbf M` in the body (Mecholsky 2019,
Eq. 1).  Mecholsky's Eq. (20) evaluates :math:`\\Delta\\alpha` in closed
form; ``orbits`` evaluates :math:`\\Omega` from a closed form of its own.

Here we check both against the simplest thing one can do without any
formula: integrate Euler's equations (15a–c) together with the attitude
:math:`\\dot R = R[\\boldsymbol\\omega]_\\times` over one period, and read
off the angle :math:`R(T)R(0)^{\\mathsf T}` turns about :math:`\\mathbf M`.
The spin is the paper's demonstration: its T-handle (:math:`l_1 = 8`,
:math:`l_2 = 4`, :math:`w = 1`, normalised to :math:`|\\mathbf I| = 1`),
:math:`|\\boldsymbol\\omega_0| = 1`, :math:`\\theta = \\pi/2 - 0.15`,
:math:`\\phi = \\pi/2 - 0.2`.
"""

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

import orbits

body = orbits.Body(orbits.Body.preset("t-handle").normalized_moments, name="T-handle")
theta, phi = np.pi / 2 - 0.15, np.pi / 2 - 0.2
row = orbits.phases(body, theta, phi).iloc[0]

# %%
# The closed forms beside the paper's numbers
# -------------------------------------------
# The paper (Sec. II, "Demonstration of formula") gives E, M, T, the dynamic
# phase, Ω by a numerical area in Mathematica (coarse: 2.1253 against
# 2.12519, erratum 8 of the docs), and Δα by its Eq. (20).
published = {
    "energy": 0.264805,
    "momentum": 0.533252,
    "period": 23.8181,
    "dynamic_phase": 23.6555,
    "geometric_phase": 2.1253,
    "total_phase": 21.5303,
}
print(f"{'quantity':16s} {'Mecholsky 2019':>15s} {'orbits':>20s}")
for name, value in published.items():
    print(f"{name:16s} {value:15.6g} {row[name]:20.15g}")
print(f"Delta alpha mod 2 pi: paper 2.68074, orbits {row['total_phase'] % (2 * np.pi):.15g}")

# %%
# Integration of the attitude
# ---------------------------
# Twelve unknowns: ω in the body and the rotation matrix R (body → space).
# DOP853 at rtol 1e-12 over the closed-form period T.
moments = body.moments
omega0 = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])


def euler_and_attitude(_, y):
    w, rot = y[:3], y[3:].reshape(3, 3)
    i1, i2, i3 = moments
    dw = [
        (i2 - i3) * w[1] * w[2] / i1,
        (i3 - i1) * w[2] * w[0] / i2,
        (i1 - i2) * w[0] * w[1] / i3,
    ]
    cross = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
    return np.concatenate([dw, (rot @ cross).ravel()])


period = row["period"]
sol = solve_ivp(
    euler_and_attitude,
    (0.0, period),
    np.concatenate([omega0, np.eye(3).ravel()]),
    method="DOP853",
    rtol=1e-12,
    atol=1e-12,
    dense_output=True,
)
rot_t = sol.y[3:, -1].reshape(3, 3)
m_hat = moments * omega0 / np.linalg.norm(moments * omega0)  # M / |M| in space (R(0) = 1)
turn = rot_t  # R(T) R(0)^T with R(0) = 1
# the angle of the rotation about m_hat: from its trace and its axial vector
axial = np.array([turn[2, 1] - turn[1, 2], turn[0, 2] - turn[2, 0], turn[1, 0] - turn[0, 1]])
angle = np.arctan2(0.5 * axial @ m_hat, 0.5 * (np.trace(turn) - 1.0)) % (2 * np.pi)
off_axis = np.linalg.norm(turn @ m_hat - m_hat)
print(f"omega(T) - omega0: {np.abs(sol.y[:3, -1] - omega0).max():.1e} (closed-form period)")
print(f"R(T) R(0)^T leaves M fixed to {off_axis:.1e}")
print(f"rotation about M by integration: {angle:.12f} rad")
print(f"closed form Delta alpha mod 2 pi: {row['total_phase'] % (2 * np.pi):.12f} rad")
print(f"difference: {abs(angle - row['total_phase'] % (2 * np.pi)):.1e} rad")

# %%
# The dynamic phase by integration
# --------------------------------
# :math:`2ET/M` is the angle swept by ω projected on M, :math:`\int_0^T
# \boldsymbol\omega\cdot\hat{\mathbf M}\,dt` (the paper's Eq. 22); its
# quadrature on the integrated ω gives the paper's 23.6555, and the
# geometric phase follows as the difference of the two integrated angles
# (the dynamic one is unwound, the total one only known mod 2π).
t = np.linspace(0.0, period, 4001)
w_t = sol.sol(t)[:3]
rot_all = sol.sol(t)[3:].reshape(3, 3, -1)
w_space = np.einsum("ijk,jk->ik", rot_all, w_t)
dynamic = np.trapezoid(m_hat @ w_space, t)
turns = round((dynamic - angle) / (2 * np.pi))
print(f"dynamic phase: integrated {dynamic:.10f}, closed form {row['dynamic_phase']:.10f}")
print(
    f"geometric phase: 2ET/M - Delta alpha (integrated, {turns} whole turns) "
    f"{dynamic - angle - 2 * np.pi * turns:.10f}, closed form {row['geometric_phase']:.10f}"
)

# %%
# The three phases along the spin direction
# -----------------------------------------
# The paper's Fig. 5 for this body (φ = 0): the total phase is the
# difference of the dynamic and geometric phases at every θ.
thetas = np.linspace(0.02, np.pi / 2 - 0.02, 400)
table = orbits.phases(body, thetas)
fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
ax.plot(thetas, table["dynamic_phase"], ":", label="dynamic 2ET/M")
ax.plot(thetas, table["geometric_phase"], "-.", label="geometric Ω")
ax.plot(thetas, table["total_phase"], "-", label="total Δα = 2ET/M − Ω")
ax.axvline(body.critical_angle(), color="0.6", lw=0.8)
ax.set_ylim(-10, 60)
ax.set_xlabel("θ (rad)")
ax.set_ylabel("phase (rad)")
ax.set_title("Montgomery's formula on the paper's T-handle")
ax.legend()
plt.show()
