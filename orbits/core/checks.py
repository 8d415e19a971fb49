"""Batch kernel running the three independent checks of the total phase.

For each initial condition (body, omega0):

* ``rotation``: Euler's equations with quaternion kinematics, integrated
  (compiled DOP853, :mod:`orbits.core.ode`) from the identity orientation
  until omega returns to omega0 ``periods`` times; the final rotation must
  be a rotation about M.  Returns the period found, the rotation angle about
  M mod 2 pi and the size of the rotation's part *not* about M.
* ``montgomery``: 2ET/M - Omega by quadrature along the polhode
  (:func:`montgomery_phase`, here; no elliptic functions).
* ``motion``: phi(T) of the exact motion (:mod:`orbits.core.motion`,
  Carlson's Pi), independent of Bulirsch's ``cel``.
"""

import math

import numpy as np
from numba import njit, prange

from . import motion as _motion
from . import phase as _phase
from .launch import parallel_kernel
from .ode import STATE_SIZE, euler_rhs, integrate_to_event

TWO_PI = 2.0 * math.pi
HALF_PI = 0.5 * math.pi

# ---------------------------------------------------------------- Montgomery
#
# Montgomery's Delta alpha = 2ET/M - Omega with the period T and the solid
# angle Omega by quadrature along the polhode, from the two invariants
# alone (no elliptic functions).  The angular momentum in the body is
# M (sin v cos u, sin v sin u, cos v) about the axis the polhode circles
# (I3 on SAM, u from I1; I1 on LAM, u from I2); the energy fixes v(u).
# The variable of integration is x, the azimuth's distance from the I2
# side of the polhode, where every difficulty lies: x = pi/2 - u on SAM,
# x = u on LAM.  With s = sin x, c = cos x:
#
#     G(x) = p s^2 + q c^2,   N(x) = a s^2 + b c^2,
#     dt/dx = 1 / sqrt(G N),  cos v = sqrt(N / (M^2 G)),
#     sin^2 v = c0 / (M^2 G),
#
# SAM: p = 1/I1 - 1/I3, q = 1/I2 - 1/I3, a = (M^2 - 2EI1)/I1,
#      b = (M^2 - 2EI2)/I2, c0 = (2EI3 - M^2)/I3;
# LAM: p = 1/I1 - 1/I3, q = 1/I1 - 1/I2, a = (2EI3 - M^2)/I3,
#      b = (2EI2 - M^2)/I2, c0 = (M^2 - 2EI1)/I1;
#
# every coefficient is a product of non-negative factors (the differences
# of reciprocals formed as (Ij - Ii)/(Ii Ij), the separatrix gap
# M^2 - 2EI2 from its factored form), so none cancels.  T = 4 int_0^{pi/2}
# dt/dx dx and the cap's solid angle 4 int_0^{pi/2} (1 - cos v) dx, with
# 1 - cos v = sin^2 v / (1 + cos v); Omega = +cap on SAM, -cap on LAM
# (right-hand rule).
#
# The integrands change on the scales sqrt(b/a) (the separatrix distance:
# down to ~1e-150 rad for |dtheta| = 1e-300) and sqrt(q/p) (the thin-rod
# corner, where I3 - I2 or I2 - I1 is small beside I1) near x = 0: the
# first panels are graded geometrically down to below both, and sqrt(G),
# sqrt(N) are formed with hypot, so nothing is squared into underflow and x
# itself (not pi/2 - x) carries the small distances.  Parameterised by u
# instead, cos u near u = pi/2 has an absolute error of 1e-16, which is all
# of the orbit's information there once the scale is below ~1e-8 (the
# earlier quadrature lost 5e-8 relative at the rod (1e-9, 1, 1 + 1e-9) and
# every digit at |dtheta| < 1e-14).

_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(20)
GAUSS_NODES = np.ascontiguousarray(_NODES)
GAUSS_WEIGHTS = np.ascontiguousarray(_WEIGHTS)
# graded panels: x_j = (pi/2) 2^-j down to below both scales, at most this many
_MAX_GRADED = 1100
_STACK = _MAX_GRADED + 256
# panel evaluations (20 points each) before the quadrature gives up (NaN):
# a bound on the time of any call whatever its tolerance (~0.5 s)
MONTGOMERY_MAX_PANELS = 600_000
# the tolerance range that montgomery_phase accepts (orbits.checks.montgomery
# refuses others before calling it): below 1e-15 the panels' rounding is
# larger than the tolerance and the budget runs out
MONTGOMERY_RTOL_MIN = 1e-15
MONTGOMERY_RTOL_MAX = 1e-3


@njit(cache=True, nogil=True)
def _montgomery_integrands(x, root_p, root_q, root_a, root_b, root_c0, momentum):
    """``(dt/dx, 1 - cos v)`` at ``x`` (see the comment above)."""
    s = math.sin(x)
    c = math.cos(x)
    root_g = math.hypot(root_p * s, root_q * c)
    root_n = math.hypot(root_a * s, root_b * c)
    cos_v = root_n / (momentum * root_g)
    sin_v = root_c0 / (momentum * root_g)
    return 1.0 / (root_g * root_n), sin_v * sin_v / (1.0 + cos_v)


@njit(cache=True, nogil=True)
def _montgomery_panel(lo, hi, root_p, root_q, root_a, root_b, root_c0, momentum):
    half = 0.5 * (hi - lo)
    mid = 0.5 * (lo + hi)
    time = 0.0
    area = 0.0
    for k in range(GAUSS_NODES.shape[0]):
        dt, dcap = _montgomery_integrands(
            mid + half * GAUSS_NODES[k], root_p, root_q, root_a, root_b, root_c0, momentum
        )
        time += GAUSS_WEIGHTS[k] * dt
        area += GAUSS_WEIGHTS[k] * dcap
    return half * time, half * area


@njit(cache=True, nogil=True)
def _add(total, compensation, value):
    """Neumaier's compensated sum: ``(total, compensation) += value``."""
    t = total + value
    if abs(total) >= abs(value):
        compensation += (total - t) + value
    else:
        compensation += (value - t) + total
    return t, compensation


@njit(cache=True, nogil=True)
def period_and_cap(i1, i2, i3, w1, w2, w3, scale, offset, closing, rtol):
    """Period T and the cap's solid angle by quadrature along the polhode.

    Parameters
    ----------
    i1, i2, i3 : float
        Principal moments, ascending (any scale).
    w1, w2, w3 : float
        The spin (any magnitude).
    scale, offset, closing : float
        ``M^2 - 2 E I2 = -scale * offset * closing`` (factored as in
        :func:`orbits.core.phase.spin_gap`: ``offset`` carries the sign and
        the separatrix distance, the others are positive).
    rtol : float
        Relative tolerance of the adaptive Gauss-Legendre quadrature
        (20 points a panel; a panel is split until its halves agree with
        it to ``rtol`` of the totals).

    Returns
    -------
    period, cap, branch : float
        ``branch`` +1 (SAM) or -1 (LAM); ``period`` and ``cap`` NaN on the
        separatrix (``offset == 0``) or when the quadrature needed more
        than :data:`MONTGOMERY_MAX_PANELS` panels.
    """
    if offset == 0.0 or not (scale > 0.0 and closing > 0.0):
        return np.nan, np.nan, 0.0
    sam = offset < 0.0
    s1 = w1 * w1
    s2 = w2 * w2
    s3 = w3 * w3
    m_sq = i1 * i1 * s1 + i2 * i2 * s2 + i3 * i3 * s3
    momentum = math.sqrt(m_sq)
    gap_m1 = i2 * (i2 - i1) * s2 + i3 * (i3 - i1) * s3  # M^2 - 2 E I1
    gap_3m = i1 * (i3 - i1) * s1 + i2 * (i3 - i2) * s2  # 2 E I3 - M^2
    # |M^2 - 2 E I2| / I2 as a product of square roots: no underflow
    root_b = math.sqrt(scale) * math.sqrt(abs(offset)) * math.sqrt(closing) / math.sqrt(i2)
    root_p = math.sqrt((i3 - i1) / (i1 * i3))
    if sam:
        root_q = math.sqrt((i3 - i2) / (i2 * i3))
        root_a = math.sqrt(gap_m1 / i1)
        root_c0 = math.sqrt(gap_3m / i3)
    else:
        root_q = math.sqrt((i2 - i1) / (i1 * i2))
        root_a = math.sqrt(gap_3m / i3)
        root_c0 = math.sqrt(gap_m1 / i1)
    # the smaller of the two scales near x = 0, and the graded panels
    finest = min(root_b / root_a, root_q / root_p)
    lo_stack = np.empty(_STACK)
    hi_stack = np.empty(_STACK)
    depth = 0
    edge = HALF_PI
    estimate_t = 0.0
    estimate_c = 0.0
    while depth < _MAX_GRADED - 1 and edge > 0.25 * finest:
        lower = 0.5 * edge
        lo_stack[depth] = lower
        hi_stack[depth] = edge
        depth += 1
        edge = lower
    lo_stack[depth] = 0.0
    hi_stack[depth] = edge
    depth += 1
    for k in range(depth):
        t_k, c_k = _montgomery_panel(
            lo_stack[k], hi_stack[k], root_p, root_q, root_a, root_b, root_c0, momentum
        )
        estimate_t += t_k
        estimate_c += c_k
    scale_t = abs(estimate_t)
    scale_c = max(abs(estimate_c), 1e-300)
    total_t = 0.0
    comp_t = 0.0
    total_c = 0.0
    comp_c = 0.0
    panels = depth
    while depth > 0:
        depth -= 1
        a = lo_stack[depth]
        b = hi_stack[depth]
        t_ab, c_ab = _montgomery_panel(a, b, root_p, root_q, root_a, root_b, root_c0, momentum)
        mid = 0.5 * (a + b)
        t_l, c_l = _montgomery_panel(a, mid, root_p, root_q, root_a, root_b, root_c0, momentum)
        t_r, c_r = _montgomery_panel(mid, b, root_p, root_q, root_a, root_b, root_c0, momentum)
        panels += 3
        if panels > MONTGOMERY_MAX_PANELS:
            return np.nan, np.nan, (1.0 if sam else -1.0)
        converged = (
            abs(t_l + t_r - t_ab) <= rtol * scale_t and abs(c_l + c_r - c_ab) <= rtol * scale_c
        )
        # a panel narrower than ~1e-13 of its position cannot be split usefully
        if converged or depth + 2 > _STACK or b - a <= 1e-13 * b:
            total_t, comp_t = _add(total_t, comp_t, t_l)
            total_t, comp_t = _add(total_t, comp_t, t_r)
            total_c, comp_c = _add(total_c, comp_c, c_l)
            total_c, comp_c = _add(total_c, comp_c, c_r)
        else:
            lo_stack[depth] = a
            hi_stack[depth] = mid
            lo_stack[depth + 1] = mid
            hi_stack[depth + 1] = b
            depth += 2
    return 4.0 * (total_t + comp_t), 4.0 * (total_c + comp_c), (1.0 if sam else -1.0)


@njit(cache=True, nogil=True)
def montgomery_phase(i1, i2, i3, w1, w2, w3, scale, offset, closing, rtol):
    """``Delta alpha = 2ET/M - Omega`` with T and Omega by quadrature.

    Arguments as :func:`period_and_cap`.  Returns ``(total, dynamic,
    omega_signed, period, branch)``; NaN where :func:`period_and_cap` gives
    NaN.
    """
    two_e = i1 * w1 * w1 + i2 * w2 * w2 + i3 * w3 * w3
    momentum = math.sqrt(i1 * i1 * w1 * w1 + i2 * i2 * w2 * w2 + i3 * i3 * w3 * w3)
    period, cap, branch = period_and_cap(i1, i2, i3, w1, w2, w3, scale, offset, closing, rtol)
    signed = branch * cap  # right-hand rule: + on SAM, - on LAM
    dynamic = two_e * period / momentum
    return dynamic - signed, dynamic, signed, period, branch


@njit(cache=True, nogil=True)
def return_event(i1, i2, i3, w1, w2, w3):
    """How to see omega return to omega0: ``(component, direction)``.

    The crossing of one component of omega through its initial value: the
    ``sn`` or the ``cn`` component (never the ``dn`` one, which returns twice
    per period), whichever moves faster at the start; ``direction`` is the
    sign of its initial rate, 0 for a steady spin.
    """
    f0 = np.empty(STATE_SIZE)
    euler_rhs(np.array([i1, i2, i3]), np.array([w1, w2, w3, 1.0, 0.0, 0.0, 0.0]), f0)
    two_e = i1 * w1 * w1 + i2 * w2 * w2 + i3 * w3 * w3
    m_sq = i1 * i1 * w1 * w1 + i2 * i2 * w2 * w2 + i3 * i3 * w3 * w3
    cn_index = 0 if m_sq > two_e * i2 else 2
    component = 1 if abs(f0[1]) >= abs(f0[cn_index]) else cn_index
    rate = f0[component]
    return component, (1.0 if rate > 0.0 else (-1.0 if rate < 0.0 else 0.0))


@njit(cache=True, nogil=True)
def rotation_about_momentum(q, i1, i2, i3, w1, w2, w3):
    """Split a rotation (quaternion ``q``, from the identity) about M^ = I w / |I w|.

    Returns ``(angle, off_axis)``: the rotation angle about M in [0, 2 pi),
    and ``2 |q_vec x M^|``, the size (radians) of the part not about M.
    """
    norm_q = math.sqrt(q[0] ** 2 + q[1] ** 2 + q[2] ** 2 + q[3] ** 2)
    momentum = math.sqrt((i1 * w1) ** 2 + (i2 * w2) ** 2 + (i3 * w3) ** 2)
    m1 = i1 * w1 / momentum
    m2 = i2 * w2 / momentum
    m3 = i3 * w3 / momentum
    v1 = q[1] / norm_q
    v2 = q[2] / norm_q
    v3 = q[3] / norm_q
    along = v1 * m1 + v2 * m2 + v3 * m3
    p1 = v1 - along * m1
    p2 = v2 - along * m2
    p3 = v3 - along * m3
    angle = 2.0 * math.atan2(along, q[0] / norm_q)
    angle -= TWO_PI * math.floor(angle / TWO_PI)
    return angle, 2.0 * math.sqrt(p1 * p1 + p2 * p2 + p3 * p3)


# the period reported by :func:`rotation_after_periods` (and ``ode_period``
# of :func:`check_batch`) when the step budget ran out before the last return
STEP_BUDGET_EXHAUSTED = -1.0
# the step budget of the ODE check in :func:`check_batch`
ODE_MAX_STEPS = 10_000_000
# ``ode_period`` of :func:`check_batch` for a row not integrated because one
# period needs more steps than ODE_MAX_STEPS (:func:`ode_steps_at_least`)
STEP_BUDGET_PREDICTED = -2.0
# A lower bound on the compiled DOP853's steps per unit of T * sqrt(2E/I3)
# (the period times the least |omega| on the orbit) at rtol <= 1e-12 and
# atol <= 1e-14, a tenth of the least rate measured: 2.60 steps (bodies
# (1, 1.001, 1.002) and (1, 1.0001, 1.0002), tending to 2.60 as the body
# nears the sphere) and 2.7 to 250 on (1, 2, 3), (0.3, 0.7, 0.9), thin rods,
# nearly prolate and oblate bodies, at theta = 0.02 ... 1.55: no step
# turned the body by more than 1/2.6 = 0.38 rad (the local error of a
# rotation by h |omega| grows as (h |omega|)^9; tests/test_checks.py counts
# the steps against this bound).
ODE_STEPS_PER_TURN_AT_LEAST = 0.26
# the tolerances the bound was measured at (tighter ones take more steps)
ODE_PREDICTION_RTOL = 1e-12
ODE_PREDICTION_ATOL = 1e-14


@njit(cache=True, nogil=True)
def ode_steps_at_least(i1, i2, i3, w1, w2, w3, period):
    """A lower bound on the DOP853 steps of one period, from the period.

    Parameters
    ----------
    i1, i2, i3 : float
        Principal moments, ascending (any scale).
    w1, w2, w3 : float
        The spin (any magnitude), rad per unit time.
    period : float
        The orbit's period, in the same unit of time.

    Returns
    -------
    float
        ``ODE_STEPS_PER_TURN_AT_LEAST * period * sqrt(2E/I3)``: steps (a
        count, dimensionless) the compiled DOP853 takes at least at rtol
        1e-12, atol 1e-14 (|omega| >= sqrt(2E/I3) all along the orbit);
        0 where ``period`` is not finite and positive.
    """
    if not (period > 0.0 and math.isfinite(period)):
        return 0.0
    two_e = i1 * w1 * w1 + i2 * w2 * w2 + i3 * w3 * w3
    return ODE_STEPS_PER_TURN_AT_LEAST * period * math.sqrt(two_e / i3)


@njit(cache=True, nogil=True)
def _integrate_periods(i1, i2, i3, w1, w2, w3, periods, rtol, atol, max_steps, y_end):
    """Integrate from the identity orientation until omega has returned
    ``periods`` times (:func:`return_event`); returns the time (-1 if not
    reached, NaN for a steady spin) with the final state in ``y_end``.
    """
    component, direction = return_event(i1, i2, i3, w1, w2, w3)
    if direction == 0.0:
        return np.nan
    y0 = np.array([w1, w2, w3, 1.0, 0.0, 0.0, 0.0])
    t_end, _ = integrate_to_event(
        np.array([i1, i2, i3]),
        y0,
        component,
        y0[component],
        direction,
        periods,
        rtol,
        atol,
        1e15,
        y_end,
        max_steps,
    )
    return t_end


@njit(cache=True, nogil=True)
def rotation_after_periods(i1, i2, i3, w1, w2, w3, periods, rtol, atol, max_steps):
    """Integrate ``periods`` periods; return ``(period, angle, off_axis)``.

    The period is the time between returns of omega to omega0 (see
    :func:`return_event`); ``angle`` and ``off_axis`` as in
    :func:`rotation_about_momentum`.  When the ``max_steps`` steps end
    before the last return (a period too long for the budget: a nearly
    symmetric body, or a spin very near the separatrix) the period is
    :data:`STEP_BUDGET_EXHAUSTED` (-1) and the rest NaN; all NaN when
    omega does not move (a steady spin about an axis: no return).
    """
    y_end = np.empty(STATE_SIZE)
    t_end = _integrate_periods(i1, i2, i3, w1, w2, w3, periods, rtol, atol, max_steps, y_end)
    if t_end == STEP_BUDGET_EXHAUSTED:
        return STEP_BUDGET_EXHAUSTED, np.nan, np.nan
    if not t_end >= 0.0:
        return np.nan, np.nan, np.nan
    angle, off_axis = rotation_about_momentum(y_end[3:], i1, i2, i3, w1, w2, w3)
    return t_end / periods, angle, off_axis


@njit(cache=True, nogil=True)
def phase_by_quarter(i1, i2, i3, gap_m1, gap_3m, scale, offset, closing, rtol):
    """``Delta alpha`` from one quarter period integrated from the saddle side.

    Parameters
    ----------
    i1, i2, i3 : float
        Principal moments, ascending.
    gap_m1, gap_3m : float
        ``M^2 - 2 E I1`` and ``2 E I3 - M^2`` of the orbit.
    scale, offset, closing : float
        ``M^2 - 2 E I2 = -scale * offset * closing`` (factored, so that it is
        known to full relative precision however small).

    Returns
    -------
    delta_alpha, quarter_time : float

    Notes
    -----
    The orbit's point of closest approach to the unstable spin about I2 is
    where ``w1 = 0`` (SAM) or ``w3 = 0`` (LAM); from the two invariants,
    there ``w2^2 = (2EI3 - M^2)/(I2 (I3-I2))`` and the small component is
    ``w3^2 = (M^2 - 2EI2)/(I3 (I3-I2))`` (SAM), or ``w2^2 = (M^2 -
    2EI1)/(I2 (I2-I1))`` and ``w1^2 = (2EI2 - M^2)/(I1 (I2-I1))`` (LAM).
    Started there, with an error control that is relative in every
    component, the integration keeps the separatrix distance to full
    precision however small it is -- unlike a start anywhere else, where
    a double omega0 cannot resolve it.  The integration runs until
    ``w2 = 0`` (a quarter period) while following the Euler angle phi.

    Euler's equations are reversible under ``(w_k, t) -> (-w_k, -t)`` for
    each k, so the four quarters of a period are mirror images, and
    ``dphi/dt = M (I1 w1^2 + I2 w2^2) / (I1^2 w1^2 + I2^2 w2^2)`` takes the
    same values on each: ``phi(T) = 4 phi(T/4)``, and
    ``Delta alpha = phi(T) - 2 pi`` (SAM) or ``phi(T)`` (LAM)
    (eqn:alphaproto).
    """
    d21 = i2 - i1
    d32 = i3 - i2
    magnitude = abs(offset)
    sam = offset < 0.0
    if sam:
        w1 = 0.0
        w2 = math.sqrt(gap_3m / (i2 * d32))
        w3 = math.sqrt(scale / (i3 * d32)) * math.sqrt(magnitude) * math.sqrt(closing)
    else:
        w1 = math.sqrt(scale / (i1 * d21)) * math.sqrt(magnitude) * math.sqrt(closing)
        w2 = math.sqrt(gap_m1 / (i2 * d21))
        w3 = 0.0
    m1 = i1 * w1
    m2 = i2 * w2
    m3 = i3 * w3
    # orientation with space z along M and phi = 0: R = Rx(theta) Rz(psi)
    half_theta = 0.5 * math.atan2(math.sqrt(m1 * m1 + m2 * m2), m3)
    half_psi = 0.5 * math.atan2(m1, m2)
    y0 = np.array(
        [
            w1,
            w2,
            w3,
            math.cos(half_theta) * math.cos(half_psi),
            math.sin(half_theta) * math.cos(half_psi),
            -math.sin(half_theta) * math.sin(half_psi),
            math.cos(half_theta) * math.sin(half_psi),
        ]
    )
    inertia = np.array([i1, i2, i3])
    y_end = np.empty(STATE_SIZE)
    # error control relative in every component: the absolute floor sits
    # well below the small components' own scale
    small = max(abs(w1), abs(w3))
    atol = rtol * 1e-3 * small if small > 0.0 else rtol * 1e-3
    # steps as short as phi's turn needs where it turns fast (near w2 = 0,
    # at up to M/I1), not everywhere (integrate_to_event's track_phi)
    t_quarter, phi_quarter = integrate_to_event(
        inertia, y0, 1, 0.0, -1.0, 1, rtol, atol, 1e15, y_end, 100_000_000, np.inf, True
    )
    if t_quarter < 0.0:
        return np.nan, np.nan
    total = 4.0 * phi_quarter
    if sam:
        total -= TWO_PI
    return total, t_quarter


@njit(cache=True, nogil=True)
def rotation_angle_after_periods(i1, i2, i3, w1, w2, w3, periods, rtol, atol, max_steps):
    """Angle of the rotation ``R(q T) R(0)^-1`` (full integration), in [0, pi]."""
    y_end = np.empty(STATE_SIZE)
    t_end = _integrate_periods(i1, i2, i3, w1, w2, w3, periods, rtol, atol, max_steps, y_end)
    if not t_end >= 0.0:
        return np.nan
    vector = math.sqrt(y_end[4] ** 2 + y_end[5] ** 2 + y_end[6] ** 2)
    return 2.0 * math.atan2(vector, abs(y_end[3]))


CHECK_COLUMNS = (
    "closed_form",
    "closed_form_theta",
    "motion",
    "montgomery",
    "solid_angle",
    "montgomery_period",
    "ode_period",
    "ode_angle",
    "ode_off_axis",
    "period",
    "branch",
    "w1",
    "w2",
    "w3",
    "relative_gap",
    "gap_slope",
)
# the relative change of the gap by which gap_slope is differenced
GAP_SLOPE_STEP = 1e-6


@parallel_kernel(cache=True, nogil=True)
def check_batch(moments, theta, phi, ode_rtol, ode_atol, quad_rtol, out):
    """The closed form and all three checks for each row.

    The closed form (``closed_form``) and the three checks evaluate the
    orbit through the double-precision vector omega0 built from ``theta,
    phi``, whose distance from the separatrix is computed exactly
    (:func:`orbits.core.phase.vector_gap`), so near the separatrix they
    compare the same orbit; how the double omega0 differs from the exact
    ``theta`` is a matter of the input's conditioning, not of the formulas.
    ``closed_form_theta`` is the closed form of the orbit of ``theta``
    itself (the factored gap of :func:`orbits.core.phase.spin_from_angle`),
    the orbit that ``orbits.total_phase`` and ``orbits.phases`` evaluate:
    the reference their values are compared with.

    ``moments`` (n, 3) sorted ascending; ``theta``, ``phi`` (n,) the unit
    initial spin.  ``out`` (n, 16) follows :data:`CHECK_COLUMNS`: the
    closed-form total phase (Bulirsch ``cel``) of omega0 and of ``theta``,
    the exact-motion ``phi(T)`` phase, Montgomery's total phase, solid angle
    and period, the ODE period, rotation angle mod 2 pi and off-axis size,
    the closed-form period, the branch (+1 SAM, -1 LAM, 0 where ``theta``
    has no closed form: on the separatrix, or within the rounding error of
    ``theta_c``), omega0, the orbit's relative distance from the separatrix
    ``g = |M^2 - 2 E I2| / (I3 (I3 - I2) w3^2 + I1 (I2 - I1) w1^2)`` (the
    gap over the two terms it is the difference of, which a rounding of
    the spin moves by ``eps`` each) and ``|d Delta alpha / d ln g|`` (the
    closed form at ``g (1 +- GAP_SLOPE_STEP)``, a central difference): a
    rounding of the state moves the phase by that times ``eps / g``
    (check (a)'s conditioning next to the separatrix).  Every
    column but ``branch`` is NaN on the rows of branch 0; a row whose
    integration ran out of steps has ``ode_period`` equal to :data:`STEP_BUDGET_EXHAUSTED` (see
    :func:`rotation_after_periods`), and one not integrated because both
    periods (closed form and quadrature) need more than
    :data:`ODE_MAX_STEPS` steps (:func:`ode_steps_at_least`, applied at
    ``ode_rtol <= 1e-12`` and ``ode_atol <= 1e-14``) has
    :data:`STEP_BUDGET_PREDICTED`.  Every entry of ``out`` is written.
    """
    for k in prange(moments.shape[0]):
        i1 = moments[k, 0]
        i2 = moments[k, 1]
        i3 = moments[k, 2]
        code, _, _, _, w1, w2, w3, scale, offset, closing = _phase.spin_from_angle(
            _phase.body_constants(i1, i2, i3, phi[k]), theta[k], False
        )
        if code != _phase.STATUS_OK:
            for j in range(out.shape[1]):
                out[k, j] = np.nan
            out[k, 10] = 0.0
            continue
        out[k, 1] = _phase.total_from_spin(i1, i2, i3, w1, w2, w3, scale, offset, closing)
        # every evaluation below follows the orbit through the double
        # vector (w1, w2, w3); its separatrix gap is computed exactly
        v_scale, v_offset, v_closing = _phase.vector_gap(i1, i2, i3, w1, w2, w3)
        out[k, 0] = _phase.total_from_spin(i1, i2, i3, w1, w2, w3, v_scale, v_offset, v_closing)
        orbit = np.empty(_motion.ORBIT_SIZE)
        branch = _motion.orbit_setup(i1, i2, i3, w1, w2, w3, v_scale, v_offset, v_closing, orbit)
        out[k, 2] = _motion.phase_after_period(orbit)
        total, _, solid, period, _ = montgomery_phase(
            i1, i2, i3, w1, w2, w3, v_scale, v_offset, v_closing, quad_rtol
        )
        out[k, 3] = total
        out[k, 4] = solid
        out[k, 5] = period
        # a period that needs more than ODE_MAX_STEPS steps by both
        # independent periods (closed form and quadrature; a NaN period
        # bounds nothing) is not integrated: the integration would end in
        # STEP_BUDGET_EXHAUSTED after 4 to 7 s of steps (a nearly
        # symmetric body)
        fewest = min(
            ode_steps_at_least(i1, i2, i3, w1, w2, w3, orbit[_motion.SLOT_PERIOD]),
            ode_steps_at_least(i1, i2, i3, w1, w2, w3, period),
        )
        if (
            ode_rtol <= ODE_PREDICTION_RTOL
            and ode_atol <= ODE_PREDICTION_ATOL
            and fewest > ODE_MAX_STEPS
        ):
            ode_period, angle, off_axis = STEP_BUDGET_PREDICTED, np.nan, np.nan
        else:
            ode_period, angle, off_axis = rotation_after_periods(
                i1, i2, i3, w1, w2, w3, 1, ode_rtol, ode_atol, ODE_MAX_STEPS
            )
        out[k, 6] = ode_period
        out[k, 7] = angle
        out[k, 8] = off_axis
        out[k, 9] = orbit[_motion.SLOT_PERIOD]
        out[k, 10] = branch
        out[k, 11] = w1
        out[k, 12] = w2
        out[k, 13] = w3
        # the gap relative to its two terms, which a rounding of the spin
        # moves by eps each (I1 <= I2 <= I3: both are >= 0)
        terms = i3 * (i3 - i2) * w3 * w3 + i1 * (i2 - i1) * w1 * w1
        out[k, 14] = abs(v_scale * v_offset * v_closing) / terms
        up = _phase.total_from_spin(
            i1, i2, i3, w1, w2, w3, v_scale, v_offset * (1.0 + GAP_SLOPE_STEP), v_closing
        )
        down = _phase.total_from_spin(
            i1, i2, i3, w1, w2, w3, v_scale, v_offset * (1.0 - GAP_SLOPE_STEP), v_closing
        )
        out[k, 15] = abs(up - down) / (2.0 * GAP_SLOPE_STEP)


# Full integration from a double omega0 keeps ~1e-10 only while the orbit
# stays this far from the separatrix; closer, start from the saddle side.
FULL_INTEGRATION_FROM = 1e-3


@parallel_kernel(cache=True, nogil=True)
def closure_batch(moments, dtheta, periods, rtol, out):
    """Angle by which each orbit fails to close after ``periods[k]`` periods.

    ``moments`` (n, 3) sorted; ``dtheta`` (n,) offsets from the critical
    angle (phi = 0).  Orbits with ``|dtheta| >= FULL_INTEGRATION_FROM`` are
    integrated over all their periods from omega0 and ``out`` is the angle
    of ``R(qT) R(0)^-1``; closer to the separatrix the period's phase comes
    from :func:`phase_by_quarter` and ``out`` is ``|q Delta alpha|`` reduced
    to [0, pi].
    """
    for k in prange(moments.shape[0]):
        i1 = moments[k, 0]
        i2 = moments[k, 1]
        i3 = moments[k, 2]
        code, _, _, _, w1, w2, w3, scale, offset, closing = _phase.spin_from_angle(
            _phase.body_constants(i1, i2, i3, 0.0), dtheta[k], True
        )
        if code != _phase.STATUS_OK:
            out[k] = np.nan
            continue
        if abs(dtheta[k]) >= FULL_INTEGRATION_FROM:
            out[k] = rotation_angle_after_periods(
                i1, i2, i3, w1, w2, w3, periods[k], rtol, 1e-14, 100_000_000
            )
        else:
            gap_m1, gap_3m = _phase.orbit_constants(
                i1, i2, i3, w1, w2, w3, scale, offset, closing
            )[3:5]
            total, _ = phase_by_quarter(i1, i2, i3, gap_m1, gap_3m, scale, offset, closing, rtol)
            turned = periods[k] * total
            turned -= TWO_PI * math.floor(turned / TWO_PI + 0.5)
            out[k] = abs(turned)
