"""Compiled integration of Euler's equations with quaternion kinematics.

An independent check of the closed forms: nothing here uses elliptic
functions.  The state is ``y = (w1, w2, w3, q0, q1, q2, q3)``:

* Euler's equations (eqn:Euler): ``I1 w1' = (I2 - I3) w2 w3`` and cyclic;
* the orientation quaternion ``q`` (body -> space) obeys
  ``q' = q (x) (0, w) / 2`` (so ``R' = R [w]x``).

The integrator is Dormand & Prince's explicit Runge-Kutta 8(5,3) (Hairer,
Norsett & Wanner, *Solving ODEs I*, Sec. II.10), the method of
``scipy.integrate.solve_ivp(method="DOP853")``, with the same error norm
and step control; its Butcher tableau is taken from SciPy's published
coefficients.  It is compiled so that ``orbits verify`` can integrate tens
of thousands of orbits; tests check it against ``solve_ivp`` itself.

Events ("the period is over") are located without dense output: once a
step brackets the crossing, the step length from the last accepted point
is iterated (Illinois regula falsi) until the event function vanishes.
"""

import math

import numpy as np
from numba import njit
from scipy.integrate._ivp import dop853_coefficients as _tableau

N_STAGES = _tableau.N_STAGES  # 12
TABLEAU_A = np.ascontiguousarray(_tableau.A[:N_STAGES, :N_STAGES])
TABLEAU_B = np.ascontiguousarray(_tableau.B)
TABLEAU_C = np.ascontiguousarray(_tableau.C[:N_STAGES])
TABLEAU_E3 = np.ascontiguousarray(_tableau.E3)  # 13 entries
TABLEAU_E5 = np.ascontiguousarray(_tableau.E5)

SAFETY = 0.9
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0
ERROR_EXPONENT = -1.0 / 8.0
STATE_SIZE = 7


@njit(cache=True, nogil=True)
def euler_rhs(inertia, y, dy):
    """Right-hand side: Euler's equations and quaternion kinematics."""
    i1 = inertia[0]
    i2 = inertia[1]
    i3 = inertia[2]
    w1 = y[0]
    w2 = y[1]
    w3 = y[2]
    dy[0] = (i2 - i3) * w2 * w3 / i1
    dy[1] = (i3 - i1) * w3 * w1 / i2
    dy[2] = (i1 - i2) * w1 * w2 / i3
    q0 = y[3]
    q1 = y[4]
    q2 = y[5]
    q3 = y[6]
    dy[3] = 0.5 * (-q1 * w1 - q2 * w2 - q3 * w3)
    dy[4] = 0.5 * (q0 * w1 + q2 * w3 - q3 * w2)
    dy[5] = 0.5 * (q0 * w2 + q3 * w1 - q1 * w3)
    dy[6] = 0.5 * (q0 * w3 + q1 * w2 - q2 * w1)


@njit(cache=True, nogil=True)
def dop853_step(inertia, y, f0, h, stages, y_new, f_new, work):
    """One DOP853 step of length ``h`` from ``(y, f0 = f(y))``.

    Fills ``stages`` (13, 7; the last row is ``f(y_new)``), ``y_new`` and
    ``f_new``.
    """
    n = y.shape[0]
    for i in range(n):
        stages[0, i] = f0[i]
    for s in range(1, N_STAGES):
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += TABLEAU_A[s, j] * stages[j, i]
            work[i] = y[i] + h * acc
        euler_rhs(inertia, work, stages[s])
    for i in range(n):
        acc = 0.0
        for j in range(N_STAGES):
            acc += TABLEAU_B[j] * stages[j, i]
        y_new[i] = y[i] + h * acc
    euler_rhs(inertia, y_new, f_new)
    for i in range(n):
        stages[N_STAGES, i] = f_new[i]


@njit(cache=True, nogil=True)
def error_norm(stages, h, y, y_new, rtol, atol):
    """SciPy's DOP853 error norm (the 5th- and 3rd-order estimators)."""
    n = y.shape[0]
    err5 = 0.0
    err3 = 0.0
    for i in range(n):
        scale = atol + max(abs(y[i]), abs(y_new[i])) * rtol
        e5 = 0.0
        e3 = 0.0
        for j in range(N_STAGES + 1):
            e5 += TABLEAU_E5[j] * stages[j, i]
            e3 += TABLEAU_E3[j] * stages[j, i]
        err5 += (e5 / scale) ** 2
        err3 += (e3 / scale) ** 2
    if err5 == 0.0 and err3 == 0.0:
        return 0.0
    return abs(h) * err5 / math.sqrt((err5 + 0.01 * err3) * n)


@njit(cache=True, nogil=True)
def _initial_step(inertia, y, f0, rtol, atol, work, f1):
    """Hairer's starting step (Solving ODEs I, Sec. II.4), order 8."""
    n = y.shape[0]
    d0 = 0.0
    d1 = 0.0
    for i in range(n):
        scale = atol + abs(y[i]) * rtol
        d0 += (y[i] / scale) ** 2
        d1 += (f0[i] / scale) ** 2
    d0 = math.sqrt(d0 / n)
    d1 = math.sqrt(d1 / n)
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    if not (h0 > 0.0 and math.isfinite(h0)):
        h0 = 1e-6
    for i in range(n):
        work[i] = y[i] + h0 * f0[i]
    euler_rhs(inertia, work, f1)
    d2 = 0.0
    for i in range(n):
        scale = atol + abs(y[i]) * rtol
        d2 += ((f1[i] - f0[i]) / scale) ** 2
    d2 = math.sqrt(d2 / n) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    h = min(100.0 * h0, h1)
    return h if (h > 0.0 and math.isfinite(h)) else 1e-6


@njit(cache=True, nogil=True)
def euler_phi(y):
    """Euler angle phi of the orientation quaternion in ``y[3:7]``.

    ``R = Rz(phi) Rx(theta) Rz(psi)`` has ``R02 = sin phi sin theta`` and
    ``R12 = -cos phi sin theta``; in quaternion components
    ``phi = atan2(xz + wy, wx - yz)`` (space z along M).
    """
    w = y[3]
    x = y[4]
    yy = y[5]
    z = y[6]
    return math.atan2(x * z + w * yy, w * x - yy * z)


# with track_phi: a step's phi turn is kept at most PHI_STEP_LIMIT, aiming at
# PHI_STEP (radians), so that its change is read unwrapped without doubt
PHI_STEP = 0.25 * math.pi
PHI_STEP_LIMIT = 0.5 * math.pi


@njit(cache=True, nogil=True)
def phi_rate(inertia, y):
    """``|dphi/dt| = M (I1 w1^2 + I2 w2^2) / (I1^2 w1^2 + I2^2 w2^2)`` at state ``y``.

    The Euler angle phi of ``R = Rz(phi) Rx(theta) Rz(psi)`` with space z
    along M (Landau & Lifshitz, Sec. 37); 0 for a spin along I3, where
    phi is not defined.
    """
    a = inertia[0] * y[0]
    b = inertia[1] * y[1]
    c = inertia[2] * y[2]
    across = a * a + b * b
    if across == 0.0:
        return 0.0
    momentum = math.sqrt(across + c * c)
    return momentum * (inertia[0] * y[0] * y[0] + inertia[1] * y[1] * y[1]) / across


@njit(cache=True, nogil=True)
def integrate_to_event(
    inertia,
    y0,
    component,
    target,
    direction,
    count,
    rtol,
    atol,
    t_max,
    y_out,
    max_steps,
    max_step=np.inf,
    track_phi=False,
):
    """Integrate until ``y[component] - target`` crosses zero ``count`` times
    in ``direction`` (+1 or -1); the start itself does not count.

    Parameters
    ----------
    inertia : ndarray (3,)
    y0 : ndarray (7,)
        Initial state.
    component, target, direction, count
        The event: ``g = y[component] - target`` passing from the
        ``-direction`` side to the ``+direction`` side.
    rtol, atol : float
        Tolerances, as in ``solve_ivp``.
    t_max : float
        Give up after this time (returns -1).
    y_out : ndarray (7,)
        Receives the state at the event.
    max_steps : int
    max_step : float
        Largest step allowed.
    track_phi : bool
        Also follow the Euler angle phi continuously (unwrapped) and return
        its change.  Each step is then short enough that phi turns by at
        most pi/2 in it (its rate, :func:`phi_rate`, times the step, at both
        ends of the step and at the event): short steps only where phi
        turns fast (near ``w2 = 0`` on a rod's orbit), not all along, since
        millions of forced short steps drifted the state by their rounding
        (6e-7 rad of Delta alpha on a 1e-6 rod).

    Returns
    -------
    t_event, phi_change : float
        Time of the ``count``-th event (-1.0 if not reached) and, with
        ``track_phi``, the change of phi up to it (else 0).
    """
    n = y0.shape[0]
    y = y0.copy()
    f = np.empty(n)
    euler_rhs(inertia, y, f)
    y_new = np.empty(n)
    f_new = np.empty(n)
    stages = np.empty((N_STAGES + 1, n))
    work = np.empty(n)
    y_try = np.empty(n)
    f_try = np.empty(n)
    h = min(_initial_step(inertia, y, f, rtol, atol, work, f_new), max_step)
    t = 0.0
    g_old = 0.0
    seen = 0
    phi_total = 0.0
    phi_last = euler_phi(y) if track_phi else 0.0
    for _ in range(max_steps):
        if t > t_max:
            return -1.0, 0.0
        if track_phi:
            rate = phi_rate(inertia, y)
            if rate * h > PHI_STEP:
                h = PHI_STEP / rate
        while True:
            dop853_step(inertia, y, f, h, stages, y_new, f_new, work)
            err = error_norm(stages, h, y, y_new, rtol, atol)
            if err < 1.0:
                if track_phi:
                    rate = phi_rate(inertia, y_new)
                    if rate * h > PHI_STEP_LIMIT:  # phi turned too fast in it: shorter
                        h = PHI_STEP / rate
                        continue
                factor = (
                    MAX_FACTOR if err == 0.0 else min(MAX_FACTOR, SAFETY * err**ERROR_EXPONENT)
                )
                break
            h *= max(MIN_FACTOR, SAFETY * err**ERROR_EXPONENT)
        g_new = y_new[component] - target
        if direction * g_old < 0.0 and direction * g_new >= 0.0:
            if seen + 1 == count:
                h_event = _locate(
                    inertia,
                    y,
                    f,
                    h,
                    g_old,
                    g_new,
                    component,
                    target,
                    stages,
                    y_try,
                    f_try,
                    work,
                    y_out,
                )
                if track_phi:
                    rate = phi_rate(inertia, y_out)
                    if rate * h_event > PHI_STEP_LIMIT:
                        # phi turns fastest at the event (w2 = 0 on a rod's
                        # orbit): step up to it in shorter steps
                        h = PHI_STEP / rate
                        continue
                    phi_total += _wrapped(euler_phi(y_out) - phi_last)
                return t + h_event, phi_total
            seen += 1
        t += h
        for i in range(n):
            y[i] = y_new[i]
            f[i] = f_new[i]
        if track_phi:
            phi_now = euler_phi(y)
            phi_total += _wrapped(phi_now - phi_last)
            phi_last = phi_now
        g_old = g_new
        h = min(h * factor, max_step)
    return -1.0, 0.0


@njit(cache=True, nogil=True)
def _wrapped(angle):
    """``angle`` reduced to (-pi, pi]."""
    return angle - 2.0 * math.pi * math.floor(angle / (2.0 * math.pi) + 0.5)


@njit(cache=True, nogil=True)
def _locate(inertia, y, f, h, g_lo, g_hi, component, target, stages, y_try, f_try, work, y_out):
    """Step length in (0, h] at which the event function vanishes.

    Illinois regula falsi on the step length: every trial is a full DOP853
    step from the last accepted point (shorter than the accepted step, so
    at least as accurate).
    """
    lo = 0.0
    hi = h
    side = 0
    h_star = h
    for _ in range(100):
        h_star = hi - g_hi * (hi - lo) / (g_hi - g_lo)
        if not (lo < h_star < hi):
            h_star = 0.5 * (lo + hi)
        dop853_step(inertia, y, f, h_star, stages, y_try, f_try, work)
        g = y_try[component] - target
        if g == 0.0 or hi - lo <= 4e-16 * h:
            break
        if (g > 0.0) == (g_hi > 0.0):
            hi = h_star
            g_hi = g
            if side == 1:
                g_lo *= 0.5
            side = 1
        else:
            lo = h_star
            g_lo = g
            if side == -1:
                g_hi *= 0.5
            side = -1
    for i in range(y.shape[0]):
        y_out[i] = y_try[i]
    return h_star
