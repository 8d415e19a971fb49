"""Batch kernel running the three independent checks of the total phase.

For each initial condition (body, omega0):

* ``rotation``: Euler's equations with quaternion kinematics, integrated
  (compiled DOP853, :mod:`orbits.core.ode`) from the identity orientation
  until omega returns to omega0 ``periods`` times; the final rotation must
  be a rotation about M.  Returns the period found, the rotation angle about
  M mod 2 pi and the size of the rotation's part *not* about M.
* ``montgomery``: 2ET/M - Omega by quadrature (:mod:`orbits.core.quadrature`).
* ``motion``: phi(T) of the exact motion (:mod:`orbits.core.motion`,
  Carlson's Pi), independent of Bulirsch's ``cel``.
"""

import math

import numpy as np
from numba import njit, prange

from . import motion as _motion
from . import phase as _phase
from .exact import separatrix_gap_exact
from .ode import STATE_SIZE, euler_rhs, integrate_to_event
from .quadrature import montgomery_phase

TWO_PI = 2.0 * math.pi


@njit(cache=True, nogil=True)
def rotation_after_periods(i1, i2, i3, w1, w2, w3, periods, rtol, atol, max_steps):
    """Integrate ``periods`` periods; return ``(period, angle, off_axis)``.

    The period is the time between returns of omega to omega0, found as
    the crossings of one component of omega through its initial value (the
    ``sn`` or ``cn`` component, never the ``dn`` one, which returns twice
    per period).  ``angle`` is the rotation about M, in [0, 2 pi);
    ``off_axis`` is ``2 |q_vec x M^|``, the size (radians) of the part of the
    final rotation that is not about M.  All NaN if no return was found.
    """
    inertia = np.array([i1, i2, i3])
    y0 = np.array([w1, w2, w3, 1.0, 0.0, 0.0, 0.0])
    f0 = np.empty(STATE_SIZE)
    euler_rhs(inertia, y0, f0)
    two_e = i1 * w1 * w1 + i2 * w2 * w2 + i3 * w3 * w3
    m_sq = i1 * i1 * w1 * w1 + i2 * i2 * w2 * w2 + i3 * i3 * w3 * w3
    cn_index = 0 if m_sq > two_e * i2 else 2
    component = 1 if abs(f0[1]) >= abs(f0[cn_index]) else cn_index
    direction = 1.0 if f0[component] > 0.0 else -1.0
    if f0[component] == 0.0:
        return np.nan, np.nan, np.nan
    y_end = np.empty(STATE_SIZE)
    t_end = integrate_to_event(inertia, y0, component, y0[component], direction,
                               periods, rtol, atol, 1e12, y_end, max_steps)
    if t_end < 0.0:
        return np.nan, np.nan, np.nan
    norm_q = math.sqrt(y_end[3] ** 2 + y_end[4] ** 2 + y_end[5] ** 2 + y_end[6] ** 2)
    momentum = math.sqrt(m_sq)
    m1 = i1 * w1 / momentum
    m2 = i2 * w2 / momentum
    m3 = i3 * w3 / momentum
    q0 = y_end[3] / norm_q
    v1 = y_end[4] / norm_q
    v2 = y_end[5] / norm_q
    v3 = y_end[6] / norm_q
    along = v1 * m1 + v2 * m2 + v3 * m3
    p1 = v1 - along * m1
    p2 = v2 - along * m2
    p3 = v3 - along * m3
    angle = 2.0 * math.atan2(along, q0)
    angle -= TWO_PI * math.floor(angle / TWO_PI)
    return t_end / periods, angle, 2.0 * math.sqrt(p1 * p1 + p2 * p2 + p3 * p3)


CHECK_COLUMNS = ("closed_form", "motion", "montgomery", "solid_angle",
                 "montgomery_period", "ode_period", "ode_angle", "ode_off_axis",
                 "period", "branch")


@njit(cache=True, nogil=True, parallel=True)
def check_batch(moments, theta, phi, ode_rtol, ode_atol, quad_rtol, out):
    """The closed form and all three checks for each row.

    All four evaluate the orbit through the double-precision vector
    omega0 built from ``theta, phi``, whose distance from the separatrix is
    computed exactly (so near the separatrix they compare the same orbit;
    how the double omega0 differs from the exact ``theta`` is a matter of
    the input's conditioning, not of the formulas).

    ``moments`` (n, 3) sorted ascending; ``theta``, ``phi`` (n,) the unit
    initial spin.  ``out`` (n, 10) follows :data:`CHECK_COLUMNS`: the
    closed-form total phase (Bulirsch ``cel``), the exact-motion
    ``phi(T)`` phase, Montgomery's total phase, solid angle and period, the
    ODE period, rotation angle mod 2 pi and off-axis size, the closed-form
    period and the branch.  Rows on the separatrix get NaN.
    """
    for k in prange(moments.shape[0]):
        i1 = moments[k, 0]
        i2 = moments[k, 1]
        i3 = moments[k, 2]
        cphi, sphi, theta_c, co_theta_c, root_a, root_b, root_ab = \
            _phase.body_constants(i1, i2, i3, phi[k])
        th, dth, co_th, code = _phase.angle_triplet(theta[k], False, theta_c,
                                                    co_theta_c)
        if code != _phase.STATUS_OK:
            for j in range(out.shape[1]):
                out[k, j] = np.nan
            continue
        w1, w2, w3, scale, offset, closing = _phase.spin_gap(
            cphi, sphi, root_a, root_b, root_ab, th, dth, co_th)
        # every evaluation below follows the orbit through the double
        # vector (w1, w2, w3); its separatrix gap is computed exactly
        gap = separatrix_gap_exact(i1, i2, i3, w1, w3)
        out[k, 0] = _phase.total_from_spin(i1, i2, i3, w1, w2, w3, 1.0, -gap, 1.0)
        orbit = np.empty(_motion.ORBIT_SIZE)
        branch = _motion.orbit_setup(i1, i2, i3, w1, w2, w3, 1.0, -gap, 1.0, orbit)
        out[k, 1] = _motion.phase_after_period(orbit)
        total, dynamic, solid, period, quad_branch = montgomery_phase(
            i1, i2, i3, w1, w2, w3, gap, quad_rtol)
        out[k, 2] = total
        out[k, 3] = solid
        out[k, 4] = period
        ode_period, angle, off_axis = rotation_after_periods(
            i1, i2, i3, w1, w2, w3, 1, ode_rtol, ode_atol, 10_000_000)
        out[k, 5] = ode_period
        out[k, 6] = angle
        out[k, 7] = off_axis
        out[k, 8] = orbit[_motion.SLOT_PERIOD]
        out[k, 9] = branch
