"""Exact torque-free motion of the asymmetric top (numba kernels).

An orbit is described by a flat float64 array (``ORBIT_SIZE`` entries,
slots named ``SLOT_*``) filled once by :func:`orbit_setup`; the per-time
kernels then only evaluate elliptic functions.

Formulas (Mecholsky 2019, appendix; Landau & Lifshitz, Mechanics, Sec. 37):

* eqn:Omegas, SAM (``M^2 > 2 E I2``), ``tau = D (t + t0)``::

      w1 = a1 cn(tau),  w2 = a2 sn(tau),  w3 = a3 dn(tau)
      a1^2 = (2EI3 - M^2) / (I1 (I3-I1)),  a2^2 = (2EI3 - M^2) / (I2 (I3-I2)),
      a3^2 = (M^2 - 2EI1) / (I3 (I3-I1))

  LAM: indices 1 <-> 3 swapped (``w1 ~ dn``, ``w3 ~ cn``).  Euler's
  equations fix the signs: the product of the three amplitude signs is +1.
* eqn:eulerangles: ``cos(theta) = I3 w3 / M``, ``tan(psi) = I1 w1 / (I2 w2)``.
* eqn:fullphi: ``dphi/dt = M/I3 + M (I3-I1)/(I1 I3) / (1 - n sn^2(tau))``
  with ``n = -I3 (I2-I1) / (I1 (I3-I2))`` on SAM and
  ``n = -I3 (M^2-2EI1) / (I1 (2EI3-M^2))`` on LAM (the reciprocal-modulus
  form of the paper's second case), so

      phi(t) = M t / I3 + M (I3-I1) / (I1 I3 D) [Pi(n; am tau) - Pi(n; am tau_0)]

  with ``Pi(n; phi + j pi) = 2 j Pi(n) + Pi(n; phi)``.  The incomplete and
  complete Pi come from Carlson's R_J (DLMF 19.25.14), independent of the
  Bulirsch ``cel`` used for the closed-form phase.
* Orientation ``R = Rz(phi) Rx(theta) Rz(psi)`` (z-x'-z'', Goldstein/Landau)
  maps body components to space components; the space z axis is along M
  and ``phi(0) = 0``.
"""

import math

from numba import njit

from .elliptic import (
    AGM_LEVELS,
    agm_table,
    carlson_rj,
    carlson_rj_roots,
    ellipf_sincos,
    ellippi_complete_carlson,
    jacobi_quarters,
    quarter_reduce,
)
from .phase import BRANCH_SAM, BRANCH_SEPARATRIX, elliptic_parameter, orbit_constants
from .trig import sincos

HALF_PI = 0.5 * math.pi
TWO_PI = 2.0 * math.pi
# below this |cn| and dn the R_J of phi(t) is taken from them, not their squares
_TINY_ROOT = 1.0e-140

(
    SLOT_BRANCH,
    SLOT_I1,
    SLOT_I2,
    SLOT_I3,
    SLOT_A1,
    SLOT_A2,
    SLOT_A3,
    SLOT_KC,
    SLOT_RATE,
    SLOT_TAU0,
    SLOT_QUARTER,
    SLOT_N,
    SLOT_PI_COMPLETE,
    SLOT_PI_START,
    SLOT_COEF,
    SLOT_MOMENTUM,
    SLOT_PRECESSION,
    SLOT_TWO_E,
    SLOT_PERIOD,
    SLOT_M,
    SLOT_STILL,
    SLOT_LEVELS,
    SLOT_GAP_3M,
    SLOT_START_QUARTERS,
) = range(24)
SLOT_MEANS = 24
SLOT_GEOMETRIC = SLOT_MEANS + AGM_LEVELS
ORBIT_SIZE = SLOT_GEOMETRIC + AGM_LEVELS


@njit(cache=True, nogil=True)
def pi_of_u(orbit, w):
    """``Pi(n; am(u) | m)`` continued through every half period, with sn, cn, dn.

    ``u = q K + w``: ``w`` is the argument's offset from the start's whole
    number ``q`` of quarter periods (``SLOT_START_QUARTERS``), so that the
    start itself, ``w = tau0``, is represented at full relative precision
    (see :func:`start_offset`).  Also returns the half-period index ``j``
    of ``am(u) = j pi + am(r)``.
    """
    levels = int(orbit[SLOT_LEVELS])
    means = orbit[SLOT_MEANS : SLOT_MEANS + AGM_LEVELS]
    geometric = orbit[SLOT_GEOMETRIC : SLOT_GEOMETRIC + AGM_LEVELS]
    sn, cn, dn, j, r = jacobi_quarters(
        w, orbit[SLOT_START_QUARTERS], orbit[SLOT_KC], levels, means, geometric
    )
    parity = 1.0 - 2.0 * (j % 2.0 != 0.0)
    s = parity * sn  # sin and cos of am(r), |am(r)| <= pi/2
    c = parity * cn
    n = orbit[SLOT_N]
    # DLMF 19.25.14 with F(am(r)) = r; near the saddle c and dn may both be
    # below 1e-154, whose squares leave the normal doubles
    p = 1.0 - n * s * s
    if abs(c) < _TINY_ROOT and dn < _TINY_ROOT:
        rj = carlson_rj_roots(abs(c), dn, p)
    else:
        rj = carlson_rj(c * c, dn * dn, 1.0, p)
    value = 2.0 * j * orbit[SLOT_PI_COMPLETE] + r + n / 3.0 * s * s * s * rj
    return value, sn, cn, dn, j


@njit(cache=True, nogil=True)
def half_period_index(orbit, w):
    """The half-period index ``j`` of ``u = q K + w`` (as :func:`pi_of_u` gives it)."""
    return quarter_reduce(w, orbit[SLOT_START_QUARTERS], orbit[SLOT_QUARTER])[2]


@njit(cache=True, nogil=True)
def start_offset(sin0, cos0, kc):
    """The start ``u0 = q K + x`` with ``(sn u0, cn u0)`` along ``(sin0, cos0)``.

    Returns ``q`` (an integer in ``-2..2``, as a float) and ``x``, ``|x| <=
    K/2``, with ``u0 = F(am0 | m)`` for the amplitude ``am0 = atan2(sin0,
    cos0)`` in ``[-pi, pi]``.  ``x`` is formed without any subtraction of
    nearly equal numbers and without forming ``am0`` itself, from the
    normalised ``(sin, cos)`` through Carlson's ``R_F``
    (:func:`orbits.core.elliptic.ellipf_sincos`):

    * ``F(am0) <= K/2`` (``|cos am0| >= sqrt(kc) |sin am0|``, ``cos >= 0``):
      ``q = 0``, ``x = F(am0)``;
    * near ``+-pi`` likewise with ``F(pi - y) = 2K - F(y)``: ``q = +-2``,
      ``x = -sin(am0) R_F(cos^2, cos^2 + kc^2 sin^2, 1)``;
    * near ``+-pi/2`` (a spin near the unstable I2 axis, or any start once
      ``kc`` is small) the complementary amplitude ``psi`` with ``tan(am0)
      tan(psi) = 1/kc``, i.e. ``(sin psi, cos psi)`` along ``(cos am0, kc
      |sin am0|)``: ``F(am0) = +-(K - F(psi))`` (``cn(K - v) = kc sd(v)``,
      DLMF 22.4.iii), so ``q = +-1``, ``x = -+F(psi)``.

    The split is where ``F(am0) = F(psi)``, i.e. ``tan^2 am0 = 1/kc``, so
    ``|x| <= K/2`` in every case.  The motion is evaluated at ``q K + (x +
    D t)`` with the quarter-period shifts of
    :func:`orbits.core.elliptic.jacobi_quarters`, so at ``t = 0`` each
    component of omega is recovered to a few ulps, even where it is far
    below the others (before, ``u0`` was one double near ``K`` and its
    rounding, ``eps K``, was amplified by up to ``1/kc``).
    """
    scale = math.hypot(sin0, cos0)
    s = sin0 / scale
    c = cos0 / scale
    edge = abs(s) * math.sqrt(kc)
    if c > 0.0 and c >= edge:
        return 0.0, ellipf_sincos(s, c, kc)
    if c < 0.0 and -c >= edge:
        return (2.0 if s >= 0.0 else -2.0), -ellipf_sincos(s, -c, kc)
    if s > 0.0:
        return 1.0, -ellipf_sincos(c, kc * s, kc)
    return -1.0, ellipf_sincos(c, -kc * s, kc)


@njit(cache=True, nogil=True)
def orbit_setup(i1, i2, i3, w1, w2, w3, scale, offset, closing, orbit):
    """Fill ``orbit`` with the constants of the motion through omega0.

    Parameters
    ----------
    i1, i2, i3 : float
        Principal moments, ascending.
    w1, w2, w3 : float
        omega0 in the principal frame (any magnitude).
    scale, offset, closing : float
        ``M^2 - 2 E I2 = -scale * offset * closing``, from
        :func:`orbits.core.phase.spin_gap` or ``vector_gap``.
    orbit : ndarray, shape (ORBIT_SIZE,)

    Returns
    -------
    int
        The branch code (0 on the separatrix, where nothing is filled).
    """
    branch, two_e, m_sq, gap_m1, gap_3m, kc, q, p, b = orbit_constants(
        i1, i2, i3, w1, w2, w3, scale, offset, closing
    )
    orbit[SLOT_BRANCH] = branch
    if branch == BRANCH_SEPARATRIX:
        return branch
    d21 = i2 - i1
    d31 = i3 - i1
    d32 = i3 - i2
    a1 = math.sqrt(gap_3m / (i1 * d31))
    a3 = math.sqrt(gap_m1 / (i3 * d31))
    if branch == BRANCH_SAM:
        a2 = math.sqrt(gap_3m / (i2 * d32))
        sign = 1.0 if w3 >= 0.0 else -1.0  # w3 ~ dn never vanishes
        amp1, amp2, amp3 = a1, sign * a2, sign * a3
        cos0 = w1 / amp1 if amp1 > 0.0 else 1.0
        sin0 = w2 / amp2 if a2 > 0.0 else 0.0
        n = -i3 * d21 / (i1 * d32)
    else:
        a2 = math.sqrt(gap_m1 / (i2 * d21))
        sign = 1.0 if w1 >= 0.0 else -1.0  # w1 ~ dn never vanishes
        amp1, amp2, amp3 = sign * a1, sign * a2, a3
        cos0 = w3 / amp3 if amp3 > 0.0 else 1.0
        sin0 = w2 / amp2 if a2 > 0.0 else 0.0
        n = -i3 * gap_m1 / (i1 * gap_3m)
    levels = agm_table(
        kc,
        orbit[SLOT_MEANS : SLOT_MEANS + AGM_LEVELS],
        orbit[SLOT_GEOMETRIC : SLOT_GEOMETRIC + AGM_LEVELS],
    )
    quarter = HALF_PI / orbit[SLOT_MEANS + levels]
    rate = math.sqrt(q / (i1 * i2 * i3))
    momentum = math.sqrt(m_sq)
    orbit[SLOT_I1] = i1
    orbit[SLOT_I2] = i2
    orbit[SLOT_I3] = i3
    orbit[SLOT_A1] = amp1
    orbit[SLOT_A2] = amp2
    orbit[SLOT_A3] = amp3
    orbit[SLOT_KC] = kc
    orbit[SLOT_RATE] = rate
    orbit[SLOT_QUARTER] = quarter
    orbit[SLOT_N] = n
    orbit[SLOT_PI_COMPLETE] = ellippi_complete_carlson(n, kc)
    orbit[SLOT_COEF] = momentum * d31 / (i1 * i3 * rate)
    orbit[SLOT_MOMENTUM] = momentum
    orbit[SLOT_PRECESSION] = momentum / i3
    orbit[SLOT_TWO_E] = two_e
    orbit[SLOT_PERIOD] = 4.0 * quarter / rate
    orbit[SLOT_M] = elliptic_parameter(i1, i2, i3, branch, gap_m1, gap_3m)
    orbit[SLOT_GAP_3M] = gap_3m
    # a steady spin about I3: the Euler angles phi and psi share one axis
    orbit[SLOT_STILL] = 1.0 if (branch == BRANCH_SAM and gap_3m == 0.0) else 0.0
    orbit[SLOT_LEVELS] = levels
    quarters, tau0 = start_offset(sin0, cos0, kc)
    orbit[SLOT_START_QUARTERS] = quarters
    orbit[SLOT_TAU0] = tau0
    orbit[SLOT_PI_START] = pi_of_u(orbit, tau0)[0]
    return branch


@njit(cache=True, nogil=True)
def state_at(orbit, t):
    """``w1, w2, w3, phi, theta, psi`` at time ``t`` (body-frame omega, Euler angles).

    ``phi`` is continuous (unwrapped) with ``phi(0) = 0``; ``psi`` is
    continuous too: on SAM it winds by -2 pi sign(w3) per period, on LAM it
    stays in one half-plane.
    """
    pi_u, sn, cn, dn, j = pi_of_u(orbit, orbit[SLOT_TAU0] + orbit[SLOT_RATE] * t)
    return state_from_pieces(orbit, t, pi_u, sn, cn, dn, j)


@njit(cache=True, nogil=True)
def state_from_pieces(orbit, t, pi_u, sn, cn, dn, j):
    """:func:`state_at` from ``P(u)``, ``sn, cn, dn`` of ``u`` and its half-period index."""
    i1 = orbit[SLOT_I1]
    i2 = orbit[SLOT_I2]
    i3 = orbit[SLOT_I3]
    elapsed = orbit[SLOT_COEF] * (pi_u - orbit[SLOT_PI_START])
    phi = orbit[SLOT_PRECESSION] * t + elapsed
    amp2 = orbit[SLOT_A2]
    w2 = amp2 * sn
    if orbit[SLOT_BRANCH] == BRANCH_SAM:
        w1 = orbit[SLOT_A1] * cn
        w3 = orbit[SLOT_A3] * dn
        if orbit[SLOT_STILL] != 0.0:
            psi = -elapsed  # phi + psi = M t / I3, a plain spin
        else:
            # chi = atan2(I2 w2, I1 w1) follows +-am; unwrap it against am
            # (sin, cos of am(r), |am(r)| <= pi/2, are (-1)^j sn, (-1)^j cn)
            parity = 1.0 - 2.0 * (j % 2.0 != 0.0)
            winding = 1.0 if amp2 >= 0.0 else -1.0
            am = j * math.pi + math.atan2(parity * sn, parity * cn)
            chi = math.atan2(i2 * w2, i1 * w1)
            delta = chi - winding * am
            delta -= TWO_PI * math.floor(delta / TWO_PI + 0.5)
            psi = HALF_PI - (winding * am + delta)
    else:
        w1 = orbit[SLOT_A1] * dn
        w3 = orbit[SLOT_A3] * cn
        psi = math.atan2(i1 * w1, i2 * w2)
    theta = math.atan2(math.hypot(i1 * w1, i2 * w2), i3 * w3)
    return w1, w2, w3, phi, theta, psi


@njit(cache=True, nogil=True)
def rotation_from_euler(phi, theta, psi, out):
    """``R = Rz(phi) Rx(theta) Rz(psi)`` into ``out`` (3x3)."""
    sf, cf = sincos(phi)
    st, ct = sincos(theta)
    sp, cp = sincos(psi)
    out[0, 0] = cf * cp - sf * ct * sp
    out[0, 1] = -cf * sp - sf * ct * cp
    out[0, 2] = sf * st
    out[1, 0] = sf * cp + cf * ct * sp
    out[1, 1] = -sf * sp + cf * ct * cp
    out[1, 2] = -cf * st
    out[2, 0] = st * sp
    out[2, 1] = st * cp
    out[2, 2] = ct


@njit(cache=True, nogil=True)
def omega_space_at(orbit, t):
    """Space-frame angular velocity at ``t`` (the herpolhode point).

    With ``R = Rz(phi) Rx(theta) Rz(psi)`` and ``sin(psi), cos(psi)`` from the
    body-frame momentum, ``R omega`` lies in the invariable plane at height
    ``2E/M``; its part in that plane is ``Rz(phi)`` of
    ``((I2 - I1) w1 w2, w3 (2EI3 - M^2) / M) / (M sin(theta))``.
    """
    pi_u, sn, cn, dn, _ = pi_of_u(orbit, orbit[SLOT_TAU0] + orbit[SLOT_RATE] * t)
    return omega_space_from_pieces(orbit, t, pi_u, sn, cn, dn)


@njit(cache=True, nogil=True)
def omega_space_from_pieces(orbit, t, pi_u, sn, cn, dn):
    """:func:`omega_space_at` from ``P(u)`` and ``sn, cn, dn`` of ``u``."""
    i1 = orbit[SLOT_I1]
    i2 = orbit[SLOT_I2]
    phi = orbit[SLOT_PRECESSION] * t + orbit[SLOT_COEF] * (pi_u - orbit[SLOT_PI_START])
    w2 = orbit[SLOT_A2] * sn
    if orbit[SLOT_BRANCH] == BRANCH_SAM:
        w1 = orbit[SLOT_A1] * cn
        w3 = orbit[SLOT_A3] * dn
    else:
        w1 = orbit[SLOT_A1] * dn
        w3 = orbit[SLOT_A3] * cn
    momentum = orbit[SLOT_MOMENTUM]
    height = orbit[SLOT_TWO_E] / momentum
    # x + i y = exp(i phi) (x' + i y') with (x', y') = R_x(theta) R_z(psi) omega:
    # x' = (I2 - I1) w1 w2 / mu and y' = w3 (2EI3 - M^2) / (M mu), where
    # mu = M sin(theta) = |(M1, M2)| (eqn:eulerangles; 2EI3 - M^2 is an
    # invariant taken from the orbit).  Only products: no cancellation.
    # (the kernels see |I| ~ 1 and |omega| ~ 1: the squares cannot overflow;
    # hypot where they could underflow, e.g. a rod spun about its axis)
    m1 = i1 * w1
    m2 = i2 * w2
    mu_sq = m1 * m1 + m2 * m2
    mu = math.sqrt(mu_sq) if mu_sq > 1e-280 else math.hypot(m1, m2)
    if mu == 0.0:  # a steady spin about I3: omega along M
        return 0.0, 0.0, height
    inv_mu = 1.0 / mu
    x_node = (i2 - i1) * w1 * w2 * inv_mu
    y_node = w3 * (orbit[SLOT_GAP_3M] / momentum) * inv_mu
    sf, cf = sincos(phi)
    return cf * x_node - sf * y_node, sf * x_node + cf * y_node, height


@njit(cache=True, nogil=True)
def phase_after_period(orbit):
    """``Delta alpha`` from the motion: ``phi(T) - 2 pi`` (SAM) or ``phi(T)``.

    ``T = 4 K / D`` with K from the AGM table; phi from Carlson's Pi.
    """
    phi = state_at(orbit, orbit[SLOT_PERIOD])[3]
    return phi - TWO_PI if orbit[SLOT_BRANCH] == BRANCH_SAM else phi
