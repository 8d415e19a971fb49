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
  Bulirsch ``cel`` used for the closed-form phase.  For ``n < -1`` (always
  the case for a thin rod, ``I1 -> 0``, where ``-n ~ 1/I1``) the form
  ``F + (n/3) s^3 R_J`` cancels (its terms are ~ ``F`` while ``Pi ~
  1/sqrt(-n)``); there :func:`pi_far` uses the cancellation-free form
  derived from DLMF 19.7.9 (see there), whose leading term is
  ``atan2(W s, c dn) / W`` with ``W = M (I3-I1) / (I1 I3 D)``, the
  coefficient of ``Pi`` in ``phi`` itself.
* Times are first reduced by whole periods, ``t = k T + t'``:
  ``Pi(u + 4 K) = Pi(u) + 4 Pi(n)``, so ``omega(k T) = omega0`` and
  ``phi(k T) = k phi(T)`` do not depend on the rounding of ``D T`` against
  ``4 K`` (which ``dphi/du``, up to ``M / (I1 D)``, amplifies for a thin
  rod).
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
# below this characteristic Pi(n; .) is taken from pi_far (no cancellation)
_FAR_N = -1.0


@njit(cache=True, nogil=True)
def pi_far(s, c, dn, ratio, width):
    """``Pi(n; am | m)`` for ``n < 0``, ``|am| <= pi/2``, without cancellation.

    ``s, c, dn``: sine and cosine of ``am`` (``c >= 0``) and ``sqrt(1 - m
    s^2)``; ``ratio = m / N`` and ``width = W = sqrt((1 + N)(1 + m / N))``
    with ``N = -n > 0``.  Then

        Pi(-N; am | m) = atan2(W s, c dn) / W
                         + (m / (3 N)) s^3 R_J(c^2, dn^2, 1, 1 + (m / N) s^2),

    two terms of the sign of ``s``: no cancellation for any ``N > 0``.
    Derivation: DLMF 19.7.9 with ``alpha^2 = -N`` and ``omega^2 = m /
    alpha^2 = -m / N``, ``Pi(-N) + Pi(-m / N) = F + sqrt(C) R_C((C - 1)(C -
    m), (C + N)(C + m / N))`` (``C = 1 / s^2``); ``Pi(-m / N) = F - (m /
    3N) s^3 R_J(...)`` (DLMF 19.25.14) cancels ``F``, and the ``R_C``,
    scaled by ``s^4``, is ``R_C(x, y)`` with ``x = c^2 dn^2`` and ``y - x =
    s^2 (1 + N)(1 + m / N) = W^2 s^2`` exactly, i.e. ``atan(sqrt((y - x) /
    x)) / sqrt(y - x)`` (DLMF 19.2.18) ``= atan2(W s, c dn) / (W s)``.
    (Checked in mpmath at 60 digits to 1e-60 over ``N`` in 1e-3..1e40.)
    The form ``F + (n/3) s^3 R_J`` that it replaces for ``n < -1`` has
    terms ~ ``F`` while ``Pi ~ 1 / sqrt(N)``: a relative error ~ ``eps
    sqrt(N)``, which on a thin rod ``(e, 1, 1 + e)`` (``N ~ 1 / e^2``)
    reached 0.2 in ``phi(T)`` at ``e = 1e-15``.
    """
    q = 1.0 + ratio * s * s
    if abs(c) < _TINY_ROOT and dn < _TINY_ROOT:
        rj = carlson_rj_roots(abs(c), dn, q)
    else:
        rj = carlson_rj(c * c, dn * dn, 1.0, q)
    return math.atan2(width * s, c * dn) / width + ratio / 3.0 * s * s * s * rj


@njit(cache=True, nogil=True)
def pi_far_complete(kc, ratio, width):
    """Complete ``Pi(n | m)`` for ``n < 0`` as :func:`pi_far` at ``am = pi/2``.

    ``pi / (2 W) + (m / (3 N)) R_J(0, kc^2, 1, 1 + m / N)``.
    """
    q = 1.0 + ratio
    if kc < _TINY_ROOT:
        rj = carlson_rj_roots(0.0, kc, q)
    else:
        rj = carlson_rj(0.0, kc * kc, 1.0, q)
    return HALF_PI / width + ratio / 3.0 * rj


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
    SLOT_RATIO,
    SLOT_WIDTH,
) = range(26)
SLOT_MEANS = 26
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
    if n < _FAR_N:
        part = pi_far(s, c, dn, orbit[SLOT_RATIO], orbit[SLOT_WIDTH])
    else:
        # DLMF 19.25.14 with F(am(r)) = r (|n| <= 1: Pi >= F / 2, no
        # cancellation); near the saddle c and dn may both be below 1e-154,
        # whose squares leave the normal doubles
        p = 1.0 - n * s * s
        if abs(c) < _TINY_ROOT and dn < _TINY_ROOT:
            rj = carlson_rj_roots(abs(c), dn, p)
        else:
            rj = carlson_rj(c * c, dn * dn, 1.0, p)
        part = r + n / 3.0 * s * s * s * rj
    value = 2.0 * j * orbit[SLOT_PI_COMPLETE] + part
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
    if branch == BRANCH_SAM:
        # near I3 the squares of w1, w2 can fall below the normal doubles
        # (|w1|, |w2| < 1.5e-154 |w|): 2EI3 - M^2 from scaled components
        small, undo = scaled_gap(i1, d31, w1, i2, d32, w2)
        a1 = math.sqrt(small / (i1 * d31)) / undo
        a2 = math.sqrt(small / (i2 * d32)) / undo
        a3 = math.sqrt(gap_m1 / (i3 * d31))
        sign = 1.0 if w3 >= 0.0 else -1.0  # w3 ~ dn never vanishes
        amp1, amp2, amp3 = a1, sign * a2, sign * a3
        cos0 = w1 / amp1 if amp1 > 0.0 else 1.0
        sin0 = w2 / amp2 if a2 > 0.0 else 0.0
        n = -i3 * d21 / (i1 * d32)
    else:
        # near I1, M^2 - 2EI1 from scaled w2, w3 (as 2EI3 - M^2 on SAM)
        small, undo = scaled_gap(i2, d21, w2, i3, d31, w3)
        a1 = math.sqrt(gap_3m / (i1 * d31))
        a2 = math.sqrt(small / (i2 * d21)) / undo
        a3 = math.sqrt(small / (i3 * d31)) / undo
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
    m = elliptic_parameter(i1, i2, i3, branch, gap_m1, gap_3m, kc)
    if n < _FAR_N:
        # m / N and W = sqrt((1 + N)(1 + m / N)) of pi_far, as products:
        # m / N = I1 (2EI3 - M^2) / (I3 (M^2 - 2EI1)) on SAM, I1 (I3-I2) /
        # (I3 (I2-I1)) on LAM, and 1 + N = 1 - n = p of orbit_constants
        if branch == BRANCH_SAM:
            ratio = i1 * gap_3m / (i3 * gap_m1)
        else:
            ratio = i1 * d32 / (i3 * d21)
        width = math.sqrt(p) * math.sqrt(1.0 + ratio)
        orbit[SLOT_RATIO] = ratio
        orbit[SLOT_WIDTH] = width
        orbit[SLOT_PI_COMPLETE] = pi_far_complete(kc, ratio, width)
    else:
        orbit[SLOT_RATIO] = 0.0
        orbit[SLOT_WIDTH] = 0.0
        orbit[SLOT_PI_COMPLETE] = ellippi_complete_carlson(n, kc)
    orbit[SLOT_COEF] = momentum * d31 / (i1 * i3 * rate)
    orbit[SLOT_MOMENTUM] = momentum
    orbit[SLOT_PRECESSION] = momentum / i3
    orbit[SLOT_TWO_E] = two_e
    orbit[SLOT_PERIOD] = 4.0 * quarter / rate
    orbit[SLOT_M] = m
    orbit[SLOT_GAP_3M] = gap_3m
    # a steady spin about I3 (w1 = w2 = 0 exactly, not only their squares):
    # the Euler angles phi and psi share one axis
    orbit[SLOT_STILL] = 1.0 if (branch == BRANCH_SAM and a1 == 0.0 and a2 == 0.0) else 0.0
    orbit[SLOT_LEVELS] = levels
    quarters, tau0 = start_offset(sin0, cos0, kc)
    orbit[SLOT_START_QUARTERS] = quarters
    orbit[SLOT_TAU0] = tau0
    orbit[SLOT_PI_START] = pi_of_u(orbit, tau0)[0]
    return branch


@njit(cache=True, nogil=True)
def whole_periods(orbit, t):
    """``(k, w)``: ``t = k T + t'`` with ``k`` whole, ``|t'| <= T/2``, ``w = tau0 + D t'``.

    ``u(t) = u(t') + 4 k K`` exactly (``T = 4 K / D``), so ``sn, cn, dn``
    are those at ``w`` and ``Pi`` gains ``4 k Pi(n)``: the motion at whole
    periods does not depend on how ``D T`` rounds against ``4 K``.
    """
    period = orbit[SLOT_PERIOD]
    k = math.floor(t / period + 0.5)
    rest = t - k * period if k != 0.0 else t
    return k, orbit[SLOT_TAU0] + orbit[SLOT_RATE] * rest


# omega's components below this (relative to |omega| ~ 1, as the kernels see
# it) have squares near or below the smallest normal double (2.2e-308)
_SMALL_COMPONENT = 2.0**-300
_UNDO = 2.0**600


@njit(cache=True, nogil=True)
def scaled_gap(ia, da, wa, ib, db, wb):
    """``(g, f)`` with ``ia da wa^2 + ib db wb^2 = (g / f^2)`` and g of normal squares.

    For ``2EI3 - M^2`` (or ``M^2 - 2EI1``) of a spin within ~1e-154 of I3
    (I1): the squares of its small components are subnormal (a few bits,
    or 0), so the sum is formed from the components times ``f = 2**600``
    (exact), and ``sqrt(g) / f`` keeps every digit of an amplitude.
    """
    if max(abs(wa), abs(wb)) < _SMALL_COMPONENT:
        wa *= _UNDO
        wb *= _UNDO
        undo = _UNDO
    else:
        undo = 1.0
    return ia * da * wa * wa + ib * db * wb * wb, undo


@njit(cache=True, nogil=True)
def state_at(orbit, t):
    """``w1, w2, w3, phi, theta, psi`` at time ``t`` (body-frame omega, Euler angles).

    ``phi`` is continuous (unwrapped) with ``phi(0) = 0``; ``psi`` is
    continuous too: on SAM it winds by -2 pi sign(w3) per period, on LAM it
    stays in one half-plane.  ``t`` is first reduced by whole periods
    (:func:`whole_periods`).
    """
    k, w = whole_periods(orbit, t)
    pi_u, sn, cn, dn, j = pi_of_u(orbit, w)
    gained = (pi_u - orbit[SLOT_PI_START]) + 4.0 * k * orbit[SLOT_PI_COMPLETE]
    return _state(orbit, t, gained, sn, cn, dn, j + 2.0 * k)


@njit(cache=True, nogil=True)
def state_from_pieces(orbit, t, pi_u, sn, cn, dn, j):
    """:func:`state_at` from ``P(u)``, ``sn, cn, dn`` of ``u`` and its half-period index."""
    return _state(orbit, t, pi_u - orbit[SLOT_PI_START], sn, cn, dn, j)


@njit(cache=True, nogil=True)
def _state(orbit, t, gained, sn, cn, dn, j):
    """:func:`state_at` from ``P(u) - P(u0)``, ``sn, cn, dn`` and the half-period index."""
    i1 = orbit[SLOT_I1]
    i2 = orbit[SLOT_I2]
    i3 = orbit[SLOT_I3]
    elapsed = orbit[SLOT_COEF] * gained
    phi = orbit[SLOT_PRECESSION] * t + elapsed
    amp2 = orbit[SLOT_A2]
    w2 = amp2 * sn
    if orbit[SLOT_BRANCH] == BRANCH_SAM:
        w1 = orbit[SLOT_A1] * cn
        w3 = orbit[SLOT_A3] * dn
        if orbit[SLOT_STILL] != 0.0:
            # a plain spin about I3: R = Rz(phi + psi) at theta = 0 (w3 > 0)
            # and Rz(phi - psi) Rx(pi) at theta = pi (w3 < 0, L along -I3);
            # either way the body turns at M/I3 about L: phi +- psi = M t / I3
            psi = -elapsed if w3 >= 0.0 else elapsed
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
    k, w = whole_periods(orbit, t)
    pi_u, sn, cn, dn, _ = pi_of_u(orbit, w)
    gained = (pi_u - orbit[SLOT_PI_START]) + 4.0 * k * orbit[SLOT_PI_COMPLETE]
    return _omega_space(orbit, t, gained, sn, cn, dn)


@njit(cache=True, nogil=True)
def omega_space_from_pieces(orbit, t, pi_u, sn, cn, dn):
    """:func:`omega_space_at` from ``P(u)`` and ``sn, cn, dn`` of ``u``."""
    return _omega_space(orbit, t, pi_u - orbit[SLOT_PI_START], sn, cn, dn)


@njit(cache=True, nogil=True)
def _omega_space(orbit, t, gained, sn, cn, dn):
    """:func:`omega_space_at` from ``P(u) - P(u0)`` and ``sn, cn, dn`` of ``u``."""
    i1 = orbit[SLOT_I1]
    i2 = orbit[SLOT_I2]
    phi = orbit[SLOT_PRECESSION] * t + orbit[SLOT_COEF] * gained
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
    if mu_sq > 1e-280:
        inv_mu = 1.0 / math.sqrt(mu_sq)
        x_node = (i2 - i1) * w1 * w2 * inv_mu
        y_node = w3 * (orbit[SLOT_GAP_3M] / momentum) * inv_mu
    else:
        # a spin within ~1e-140 of I3 (mu is small on SAM only): w1 w2 and
        # 2EI3 - M^2 = I1 (I3 - I1) a1^2 would fall below the normal
        # doubles (and 1/mu overflow for mu below 5.6e-309), so each is
        # formed as a product of normal factors, w1 (w2 / mu) and
        # a1 (a1 / mu)
        mu = math.hypot(m1, m2)
        if mu == 0.0:  # a steady spin about I3: omega along M
            return 0.0, 0.0, height
        amp1 = orbit[SLOT_A1]
        x_node = (i2 - i1) * w1 * (w2 / mu)
        y_node = w3 * (i1 * (orbit[SLOT_I3] - i1) * amp1 / momentum) * (amp1 / mu)
    sf, cf = sincos(phi)
    return cf * x_node - sf * y_node, sf * x_node + cf * y_node, height


@njit(cache=True, nogil=True)
def phase_after_period(orbit):
    """``Delta alpha`` from the motion: ``phi(T) - 2 pi`` (SAM) or ``phi(T)``.

    ``T = 4 K / D`` with K from the AGM table; phi from Carlson's Pi.  By
    :func:`whole_periods` this is ``M T / I3 + 4 (M (I3-I1) / (I1 I3 D))
    Pi(n)`` (eqn:fullphi over one period), free of the rounding of ``D T``.
    """
    phi = state_at(orbit, orbit[SLOT_PERIOD])[3]
    return phi - TWO_PI if orbit[SLOT_BRANCH] == BRANCH_SAM else phi
