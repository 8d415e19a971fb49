"""Elliptic integrals and Jacobi elliptic functions as numba kernels.

Every routine here takes the *complementary* modulus ``kc = sqrt(1 - m)``
(or ``kc**2``) instead of the parameter ``m``.  Near the separatrix of the
rigid top ``1 - m`` is the small, physically meaningful quantity; callers
compute it in factored form and pass it in, so nothing here ever forms
``1 - m`` by subtraction.

Algorithms (implemented from the published descriptions):

* ``cel`` -- R. Bulirsch, "Numerical calculation of elliptic integrals and
  elliptic functions. III", Numer. Math. 13, 305-315 (1969): the general
  complete integral

  .. math:: \\mathrm{cel}(k_c, p, a, b) = \\int_0^{\\pi/2}
            \\frac{a\\cos^2\\varphi + b\\sin^2\\varphi}
                 {(\\cos^2\\varphi + p\\sin^2\\varphi)
                  \\sqrt{\\cos^2\\varphi + k_c^2\\sin^2\\varphi}}\\,d\\varphi

  evaluated by a quadratically convergent Landen/AGM-type iteration.
  ``K(m) = cel(kc, 1, 1, 1)`` and ``Pi(n|m) = cel(kc, 1-n, 1, 1)``.
* ``carlson_rf``, ``carlson_rj``, ``carlson_rc`` -- B. C. Carlson, "Numerical
  computation of real or complex elliptic integrals", Numer. Algorithms 10,
  13-26 (1995); DLMF 19.36.1-19.36.2.
* ``jacobi_amplitude`` -- descending Landen transformation (arithmetic-
  geometric mean), Abramowitz & Stegun 16.4; DLMF 22.20(ii).
"""

import math

import numpy as np
from numba import njit

HALF_PI = 0.5 * math.pi

# cel: relative AGM gap at which to stop.  The iteration converges
# quadratically, so a gap of 1e-9 leaves a relative error near 1e-18.
_CEL_GAP = 1.0e-9
# Carlson duplication: stop when 4**-m * Q < |A|; with r = 1e-16 the
# truncated Taylor series of DLMF 19.36.1-2 has error below 1e-16.
_CARLSON_R = 1.0e-16
_AGM_GAP = 1.0e-17
# Carlson duplication: a cap on the steps.  The stopping test ends the loop
# after ~10 steps for arguments of similar size; R_J with p far above x, y, z
# needs about log4(p / max(x, y, z)) steps (p_m falls by 4 per step and
# lambda_m does not involve p): 482 at the documented ratio 1e290.
_CARLSON_STEPS = 1100
# R_J: arguments rescaled when the largest lies outside [2^-200, 2^200]
_SCALE_HIGH = 2.0**200
_SCALE_LOW = 2.0**-200
# below this d_k the R_J term e_k is formed factor by factor (d_k^2 underflows)
_SMALL_D = 1.0e-100
# below this |r| the Jacobi functions come from their Maclaurin series
_SERIES_ARGUMENT = 2.0**-27
_MAX_AGM = 40


@njit(cache=True, nogil=True)
def cel(kc, p, a, b):
    """Bulirsch's general complete elliptic integral ``cel(kc, p, a, b)``.

    Parameters
    ----------
    kc : float
        Complementary modulus, ``kc**2 = 1 - m``; must be nonzero.
    p : float
        Must be positive (all uses in ``orbits`` are; the Cauchy
        principal-value case ``p < 0`` is not needed here).
    a, b : float
        Coefficients of ``cos**2`` and ``sin**2`` in the numerator.

    Returns
    -------
    float
        The integral; NaN when ``kc == 0`` (logarithmic divergence) or
        ``p <= 0``.  Checked against mpmath within 8 ulps for ``1e-150 <=
        kc <= 1``, ``1e-100 <= p <= 1e100`` and ``a, b > 0`` (with ``a`` and
        ``b`` of opposite signs the integral can cancel, and only its
        absolute error is small).

    Notes
    -----
    Bulirsch (1969), Numer. Math. 13, 305.  Each pass applies the Landen
    transformation that maps ``(kc, p, a, b)`` to an equivalent integral
    with ``kc -> 2 sqrt(kc) / (1 + kc)``; the integral is invariant, and
    once the AGM pair has met the integrand is elementary.
    """
    if kc == 0.0 or not (p > 0.0):
        return np.nan
    kc = abs(kc)
    gm = 1.0  # running arithmetic mean of the AGM pair (1, kc)
    e = kc  # product of the pair, kc * gm
    root_p = math.sqrt(p)
    b = b / root_p
    for _ in range(_MAX_AGM):
        inv_root_p = 1.0 / root_p
        f = a
        a = a + b * inv_root_p
        g = e * inv_root_p
        b = 2.0 * (b + f * g)
        root_p = g + root_p
        previous = gm
        gm = kc + gm
        if abs(previous - kc) <= previous * _CEL_GAP:
            break
        kc = 2.0 * math.sqrt(e)
        e = kc * gm
    return HALF_PI * (b + a * gm) / (gm * (gm + root_p))


@njit(cache=True, nogil=True)
def cel_pair(kc, p, a1, b1, a2, b2):
    """Two ``cel`` integrals sharing ``kc`` and ``p`` in one AGM loop.

    ``cel`` is linear in ``(a, b)`` and the iteration for ``kc`` and ``p``
    does not depend on them, so both integrals ride the same loop.  Used to
    get ``K`` (``a = 1, b = p``) together with ``I1 K + (I3 - I1) Pi``.
    """
    if kc == 0.0 or not (p > 0.0):
        return np.nan, np.nan
    kc = abs(kc)
    gm = 1.0
    e = kc
    root_p = math.sqrt(p)
    b1 = b1 / root_p
    b2 = b2 / root_p
    for _ in range(_MAX_AGM):
        inv_root_p = 1.0 / root_p
        f1 = a1
        f2 = a2
        a1 = a1 + b1 * inv_root_p
        a2 = a2 + b2 * inv_root_p
        g = e * inv_root_p
        b1 = 2.0 * (b1 + f1 * g)
        b2 = 2.0 * (b2 + f2 * g)
        root_p = g + root_p
        previous = gm
        gm = kc + gm
        if abs(previous - kc) <= previous * _CEL_GAP:
            break
        kc = 2.0 * math.sqrt(e)
        e = kc * gm
    scale = HALF_PI / (gm * (gm + root_p))
    return (b1 + a1 * gm) * scale, (b2 + a2 * gm) * scale


@njit(cache=True, nogil=True)
def ellipk_kc(kc):
    """Complete elliptic integral of the first kind, ``K(m)``, from ``kc``.

    ``K = pi / (2 AGM(1, kc))`` (DLMF 19.8.5).
    """
    a = 1.0
    g = abs(kc)
    if g == 0.0:
        return np.inf
    for _ in range(_MAX_AGM):
        if abs(a - g) <= _AGM_GAP * a:
            break
        a, g = 0.5 * (a + g), math.sqrt(a * g)
    return math.pi / (a + g)


@njit(cache=True, nogil=True)
def carlson_rc(x, y):
    """Carlson's degenerate integral ``R_C(x, y)`` for ``x >= 0, y > 0``.

    Closed forms, DLMF 19.2.17-19.2.18 (with a series near ``x = y``).
    Checked against mpmath within 8 ulps for ``x = 0`` or ``x`` and ``y``
    anywhere in [1e-300, 1e300].
    """
    if x == y:
        return 1.0 / math.sqrt(x)
    if y > x:
        d = y - x
        t = math.sqrt(d / x) if x > 0.0 else np.inf
        if t < 1.0e-4:
            # atan(t)/t series avoids 0/0 when x ~ y
            t2 = t * t
            return (1.0 - t2 / 3.0 + t2 * t2 / 5.0) / math.sqrt(x)
        return math.atan(t) / math.sqrt(d)
    d = x - y
    t = math.sqrt(d / x)
    if t < 1.0e-4:
        t2 = t * t
        return (1.0 + t2 / 3.0 + t2 * t2 / 5.0) / math.sqrt(x)
    if t < 0.5:
        return math.atanh(t) / math.sqrt(d)
    # atanh(t) = ln((sqrt x + sqrt d) / sqrt y): no cancellation as t -> 1
    return math.log((math.sqrt(x) + math.sqrt(d)) / math.sqrt(y)) / math.sqrt(d)


@njit(cache=True, nogil=True)
def _rc_unit(e, one_plus_e):
    """``R_C(1, 1 + e)`` for ``e > -1``, from ``e`` and ``1 + e`` (both given).

    In the R_J duplication sum ``e`` is often tiny; forming ``1 + e`` first
    would throw away its digits, so the series ``sum (-e)^k / (2k + 1)`` is
    used near 0.  Near ``e = -1`` (``p`` far below ``x, y, z``) the caller
    passes ``1 + e`` formed without cancellation: ``atanh(t) / t`` with
    ``t = sqrt(-e)`` is ``log((1 + t)^2 / (1 + e)) / (2 t)``.
    """
    if abs(e) < 1.0e-3:
        return 1.0 + e * (
            -1.0 / 3.0
            + e * (1.0 / 5.0 + e * (-1.0 / 7.0 + e * (1.0 / 9.0 + e * (-1.0 / 11.0 + e / 13.0))))
        )
    if e > 0.0:
        t = math.sqrt(e)
        return math.atan(t) / t
    t = math.sqrt(-e)
    if t < 0.5:
        return math.atanh(t) / t
    return 0.5 * math.log((1.0 + t) * (1.0 + t) / one_plus_e) / t


@njit(cache=True, nogil=True)
def carlson_rf(x, y, z):
    """Carlson's symmetric integral ``R_F(x, y, z)``, at most one argument 0.

    Duplication theorem with the fifth-order series of DLMF 19.36.1
    (Carlson 1995, Algorithm 1).

    Domain (checked against mpmath in the tests, within 8 ulps): ``x, y,
    z >= 0``, at most one of them 0, each nonzero argument a normal double
    between 1e-290 and 1e290 times the largest, and the largest below
    1e150.
    """
    x0 = x
    y0 = y
    a0 = (x + y + z) / 3.0
    q = max(abs(a0 - x), abs(a0 - y), abs(a0 - z)) / _CARLSON_R ** (1.0 / 6.0)
    a = a0
    scale = 1.0  # 4**-m
    for _ in range(_CARLSON_STEPS):
        if scale * q < abs(a):
            break
        sx = math.sqrt(x)
        sy = math.sqrt(y)
        sz = math.sqrt(z)
        lam = sx * sy + sx * sz + sy * sz
        x = 0.25 * (x + lam)
        y = 0.25 * (y + lam)
        z = 0.25 * (z + lam)
        a = 0.25 * (a + lam)
        scale *= 0.25
    big_x = (a0 - x0) / a * scale
    big_y = (a0 - y0) / a * scale
    big_z = -(big_x + big_y)
    e2 = big_x * big_y - big_z * big_z
    e3 = big_x * big_y * big_z
    series = 1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0
    return series / math.sqrt(a)


@njit(cache=True, nogil=True)
def _gap_fraction(sp, sx):
    """``1 - |r|`` for ``r = (sp - sx) / (sp + sx)``, without cancellation."""
    if sp < sx:
        return 2.0 * sp / (sp + sx)
    return 2.0 * sx / (sp + sx)


@njit(cache=True, nogil=True)
def carlson_rj(x, y, z, p):
    """Carlson's symmetric integral ``R_J(x, y, z, p)`` for ``p > 0``.

    Duplication theorem with the series of DLMF 19.36.2 (Carlson 1995,
    Algorithm 2): ``R_J = 4^-m A_m^-3/2 (series) + 6 sum_k 4^-k R_C(1, 1 +
    e_k) / d_k``, with ``d_k = (sp + sx)(sp + sy)(sp + sz)`` and ``e_k =
    4^-3k (p-x)(p-y)(p-z) / d_k^2 = r_x r_y r_z``, ``r_x = (sp - sx) / (sp +
    sx)`` (square roots of the k-th arguments).

    Domain (checked in the tests within 16 ulps against mpmath, at 40
    digits more than the arguments' ratios span, and against the rows of
    Boost.Math's ``ellint_rj_data`` with ``p > 0``): ``x, y, z >= 0``, at
    most one of them 0, ``p > 0``, each nonzero argument a normal double
    between 1e-290 and 1e290 times the largest, the largest below 1e150,
    and ``R_J`` itself a normal double (the arguments are first scaled by
    a power of 4 so that the largest is near 1, which is exact, and ``R_J``
    is homogeneous of degree -3/2).  Extreme ratios
    (``p`` far below ``x, y, z``) make ``e_k`` approach -1, where ``R_C``
    has a logarithmic singularity; ``1 + e_k`` is then formed as ``1 -
    |r_x r_y r_z|`` from the non-negative ``1 - |r|`` of each factor,
    ``1 - (1 - a)(1 - b)(1 - c) = a + (1 - a)(b + (1 - b) c)``, never by
    cancellation.  Where ``d_k^2`` would underflow, ``e_k`` is formed as
    the product of the three ratios.  The loop ends on Carlson's test
    ``4^-m Q < |A_m|``; with ``p`` far above ``x, y, z`` that takes about
    ``log4(p / max(x, y, z))`` steps (482 at a ratio 1e290; the old cap of
    60 steps returned a wrong value beyond a ratio of ~1e36).
    """
    largest = max(x, y, z, p)
    shift = 0
    if largest > _SCALE_HIGH or largest < _SCALE_LOW:
        # an even power of two, so that every square root scales exactly
        shift = -2 * (math.frexp(largest)[1] // 2)
        x = math.ldexp(x, shift)
        y = math.ldexp(y, shift)
        z = math.ldexp(z, shift)
        p = math.ldexp(p, shift)
    x0 = x
    y0 = y
    z0 = z
    dx = p - x
    dy = p - y
    dz = p - z
    delta = dx * dy * dz
    a0 = (x + y + z + p + p) / 5.0
    q = max(abs(a0 - x), abs(a0 - y), abs(a0 - z), abs(a0 - p)) / _CARLSON_R ** (1.0 / 6.0)
    a = a0
    scale = 1.0  # 4**-m
    total = 0.0
    for _ in range(_CARLSON_STEPS):
        if scale * q < abs(a):
            break
        sx = math.sqrt(x)
        sy = math.sqrt(y)
        sz = math.sqrt(z)
        sp = math.sqrt(p)
        lam = sx * sy + sx * sz + sy * sz
        px = sp + sx
        py = sp + sy
        pz = sp + sz
        d = px * py * pz
        small = d < _SMALL_D
        if small:  # d^2 (and d) may underflow: factor by factor, each ratio in [-1, 1]
            e = (scale * dx / (px * px)) * (scale * dy / (py * py)) * (scale * dz / (pz * pz))
        else:
            e = delta * scale * scale * scale / (d * d)
        if e > -0.5:
            one_plus_e = 1.0 + e
        else:
            fx = _gap_fraction(sp, sx)
            fy = _gap_fraction(sp, sy)
            fz = _gap_fraction(sp, sz)
            one_plus_e = fx + (1.0 - fx) * (fy + (1.0 - fy) * fz)
        if small:
            total += scale * _rc_unit(e, one_plus_e) / px / py / pz
        else:
            total += scale * _rc_unit(e, one_plus_e) / d
        x = 0.25 * (x + lam)
        y = 0.25 * (y + lam)
        z = 0.25 * (z + lam)
        p = 0.25 * (p + lam)
        a = 0.25 * (a + lam)
        scale *= 0.25
    big_x = (a0 - x0) / a * scale
    big_y = (a0 - y0) / a * scale
    big_z = (a0 - z0) / a * scale
    big_p = -(big_x + big_y + big_z) / 2.0
    e2 = big_x * big_y + big_x * big_z + big_y * big_z - 3.0 * big_p * big_p
    e3 = big_x * big_y * big_z + 2.0 * e2 * big_p + 4.0 * big_p**3
    e4 = (2.0 * big_x * big_y * big_z + e2 * big_p + 3.0 * big_p**3) * big_p
    e5 = big_x * big_y * big_z * big_p * big_p
    series = (
        1.0
        - 3.0 * e2 / 14.0
        + e3 / 6.0
        + 9.0 * e2 * e2 / 88.0
        - 3.0 * e4 / 22.0
        - 9.0 * e2 * e3 / 52.0
        + 3.0 * e5 / 26.0
    )
    value = scale / a * series / math.sqrt(a) + 6.0 * total
    if shift != 0:
        # R_J(4^k v) = 8^-k R_J(v), with shift = 2k
        value = math.ldexp(value, 3 * shift // 2)
    return value


@njit(cache=True, nogil=True)
def carlson_rj_roots(sx, sy, p):
    """``R_J(sx^2, sy^2, 1, p)`` from ``sx, sy >= 0`` (not both 0), ``p >= 1``.

    Near the separatrix saddle of the motion, ``sx = |cn|`` and ``sy = dn``
    can both be below 1e-154, where their squares leave the normal doubles
    (and ``R_J`` of two zeros diverges).  The first duplication step of
    :func:`carlson_rj` needs only the square roots: ``lambda = sx sy + sx +
    sy``, ``d = (sp + sx)(sp + sy)(sp + 1)``, ``e = r_x r_y r_1`` with
    ``r = (sp - s)/(sp + s) >= 0``, and ``R_J(x, y, 1, p) = R_J(x_1, y_1,
    z_1, p_1) / 4 + 6 R_C(1, 1 + e) / d`` with ``x_1 = (x + lambda)/4`` etc.
    (DLMF 19.26.17-19.26.20), whose arguments are at least ``lambda/4``.
    """
    sp = math.sqrt(p)
    lam = sx * sy + sx + sy
    e = ((sp - sx) / (sp + sx)) * ((sp - sy) / (sp + sy)) * ((sp - 1.0) / (sp + 1.0))
    d = (sp + sx) * (sp + sy) * (sp + 1.0)
    rest = carlson_rj(
        0.25 * (sx * sx + lam), 0.25 * (sy * sy + lam), 0.25 * (1.0 + lam), 0.25 * (p + lam)
    )
    return 0.25 * rest + 6.0 * _rc_unit(e, 1.0 + e) / d


@njit(cache=True, nogil=True)
def ellippi_complete_carlson(n, kc):
    """Complete ``Pi(n|m)`` from Carlson's forms, for ``n < 1``.

    ``Pi = R_F(0, kc^2, 1) + (n/3) R_J(0, kc^2, 1, 1 - n)`` (DLMF 19.25.2).
    Independent of ``cel``; the exact-motion layer uses it so that the
    check of ``phi(T)`` against the closed form compares two algorithms.
    Valid for every ``kc`` down to the smallest normal double (below
    1e-140 the first duplication step is taken from ``kc`` itself).
    """
    k2 = kc * kc
    if kc < 1.0e-140:
        # kc^2 may leave the normal doubles: one duplication step by hand
        # (lambda = kc for the roots 0, kc, 1), see carlson_rj_roots
        first = carlson_rf(0.25 * kc, 0.25 * (k2 + kc), 0.25 * (1.0 + kc))
        return first + n / 3.0 * carlson_rj_roots(0.0, kc, 1.0 - n)
    return carlson_rf(0.0, k2, 1.0) + n / 3.0 * carlson_rj(0.0, k2, 1.0, 1.0 - n)


@njit(cache=True, nogil=True)
def ellipf_kc(phi, kc):
    """Incomplete ``F(phi|m)`` for any real ``phi``, from ``kc``.

    Reduced to ``|phi| <= pi/2`` with ``F(phi + j pi) = 2 j K + F(phi)``,
    then ``F = s R_F(c^2, c^2 + kc^2 s^2, 1)`` (DLMF 19.25.5), written so
    that ``1 - m s^2`` is never formed by subtraction.
    """
    j = math.floor(phi / math.pi + 0.5)
    r = phi - j * math.pi
    s = math.sin(r)
    c = math.cos(r)
    value = s * carlson_rf(c * c, c * c + kc * kc * s * s, 1.0)
    if j != 0.0:
        value += 2.0 * j * ellipk_kc(kc)
    return value


@njit(cache=True, nogil=True)
def ellipf_sincos(s, c, kc):
    """``F(am | m)`` for ``am = atan2(s, c)`` in ``[-pi/2, pi/2]`` (``c >= 0``).

    ``(s, c)`` is any positive multiple of ``(sin am, cos am)``; it is
    normalised here, and ``F = sin(am) R_F(cos^2 am, cos^2 am + kc^2
    sin^2 am, 1)`` (DLMF 19.25.5 with ``1 - m sin^2 = cos^2 + kc^2 sin^2``).
    Every argument is a product or a sum of non-negative terms, and ``R_F``
    has relative condition number at most 1/2 in each argument, so ``F``
    keeps a few ulps of relative accuracy for every ``kc`` and every ``am``,
    with no amplitude ever formed by ``atan2`` (which rounds the angle
    near ``pi/2``, where ``dF/d am = 1/dn`` can be ``1/kc``).
    """
    scale = math.hypot(s, c)
    s = s / scale
    c = c / scale
    c2 = c * c
    return s * carlson_rf(c2, c2 + (kc * s) * (kc * s), 1.0)


@njit(cache=True, nogil=True)
def quarter_reduce(w, quarters, quarter):
    """Reduce ``u = quarters K + w`` to a quarter period and to a half period.

    Parameters
    ----------
    w : float
        The argument's offset from ``quarters K``.
    quarters : float
        An integer (held in a double).
    quarter : float
        ``K``.

    Returns
    -------
    total, rq, j, r : float
        ``u = total K + rq`` with ``|rq| <= K/2`` (``rq = w`` exactly when
        ``|w| < K/2``), and ``u = 2 j K + r`` with ``|r| <= K``.
    """
    shift = math.floor(w / quarter + 0.5)
    rq = w - shift * quarter if shift != 0.0 else w
    total = quarters + shift
    half = 0.5 * total
    j = math.floor(half)
    if j == half:
        return total, rq, j, rq
    if rq >= 0.0:
        return total, rq, j + 1.0, rq - quarter
    return total, rq, j, rq + quarter


@njit(cache=True, nogil=True)
def jacobi_quarters(w, quarters, kc, levels, means, geometric):
    """``sn, cn, dn`` of ``u = quarters K + w`` with ``w`` kept at full precision.

    Returns ``sn, cn, dn, j, r`` as :func:`jacobi_from_table` does (``u =
    2 j K + r``, ``|r| <= K``).  The functions are evaluated at ``rq``,
    ``|rq| <= K/2`` (:func:`quarter_reduce`), and carried to ``u`` by the
    quarter-period shifts (DLMF 22.4.3): ``sn(v + K) = cd(v)``,
    ``cn(v + K) = -kc sd(v)``, ``dn(v + K) = kc nd(v)``, and ``(sn, cn, dn)
    (v + 2K) = (-sn, -cn, dn)(v)``.  Only products: where ``u`` lies near
    an odd multiple of ``K`` (a spin near the unstable axis, ``cn`` and
    ``dn`` tiny) each function keeps the relative accuracy of ``w``, which
    ``jacobi_from_table(quarters K + w)`` would lose to the rounding of
    ``u`` (an absolute ``eps K``).  ``dn(rq) >= sqrt(kc)`` here, so nothing
    divides by a small number.
    """
    quarter = HALF_PI / means[levels]
    total, rq, j, r = quarter_reduce(w, quarters, quarter)
    s, c, d, _, _ = jacobi_from_table(rq, levels, means, geometric)
    phase = total - 4.0 * math.floor(0.25 * total)
    if phase == 0.0:
        return s, c, d, j, r
    if phase == 2.0:
        return -s, -c, d, j, r
    inv = 1.0 / d
    if phase == 1.0:
        return c * inv, -kc * s * inv, kc * inv, j, r
    return -c * inv, kc * s * inv, kc * inv, j, r


AGM_LEVELS = _MAX_AGM + 1


@njit(cache=True, nogil=True)
def agm_table(kc, means, geometric):
    """AGM sequence of ``(1, kc)`` for the Jacobi functions; returns its length.

    Fills ``means[n] = a_n`` and ``geometric[n] = b_n`` (A&S 16.4.1,
    ``a_0 = 1``, ``b_0 = kc``) and returns ``N``, the first index at which
    ``c_N = (a_{N-1} - b_{N-1})/2`` is negligible; ``K(m) = pi / (2 a_N)``.
    ``c_n`` is carried by the stable recurrence ``c_{n+1} = c_n^2 / (4
    a_{n+1})`` for the stopping test.  Arrays need :data:`AGM_LEVELS` entries.
    """
    a = 1.0
    b = kc
    gap = math.sqrt((1.0 - kc) * (1.0 + kc))
    means[0] = a
    geometric[0] = b
    n = 0
    while n < _MAX_AGM and abs(gap) > _AGM_GAP * a:
        a, b = 0.5 * (a + b), math.sqrt(a * b)
        gap = gap * gap / (4.0 * a)
        n += 1
        means[n] = a
        geometric[n] = b
    return n


@njit(cache=True, nogil=True)
def jacobi_from_table(u, levels, means, geometric):
    """``sn, cn, dn`` of ``u`` and its half-period reduction, from :func:`agm_table`.

    Returns
    -------
    sn, cn, dn, j, r : float
        The three functions at ``u``; the half-period index ``j`` and the
        reduced argument ``r = u - 2 j K`` in ``[-K, K]``
        (``am(u) = j pi + am(r)``, and ``sn(r) = (-1)^j sn(u)``).

    Notes
    -----
    ``u`` is first reduced by the half period ``2K`` so that long time
    grids keep full accuracy.  At the bottom of the AGM the functions are
    trigonometric in ``v = a_N r``; the descending Gauss transformation is
    then undone level by level on the ratio ``cn/sn`` and on ``dn``, with
    rational operations only (R. Bulirsch, Numer. Math. 7, 78 (1965)):
    per level ``t <- t c, c <- c dn, dn <- (b_l + t) / (a_l + t), t <- c / a_l``.
    """
    a_last = means[levels]
    quarter = HALF_PI / a_last  # K(m)
    j = math.floor(u / (2.0 * quarter) + 0.5)
    r = u - 2.0 * j * quarter
    sign = 1.0 - 2.0 * (j % 2.0 != 0.0)
    if abs(r) < _SERIES_ARGUMENT:
        # Maclaurin series (DLMF 22.10.1-22.10.3); the next terms are
        # O(r^4) relative.  The ratio cn/sn of the descent below would
        # overflow for |r| below ~1e-154 (a start with sn ~ 1e-200).
        kc = geometric[0]
        m = (1.0 - kc) * (1.0 + kc)
        r2 = r * r
        return (
            sign * r * (1.0 - (1.0 + m) * r2 / 6.0),
            sign * (1.0 - 0.5 * r2),
            1.0 - 0.5 * m * r2,
            j,
            r,
        )
    v = a_last * r
    s = math.sin(v)
    c = math.cos(v)
    dn = 1.0
    if s != 0.0:
        ratio = c / s
        cot = a_last * ratio
        for level in range(levels - 1, -1, -1):
            mean = means[level]
            ratio *= cot
            cot *= dn
            dn = (geometric[level] + ratio) / (mean + ratio)
            ratio = cot / mean
        s = math.copysign(1.0 / math.sqrt(cot * cot + 1.0), s)
        c = cot * s
    return sign * s, sign * c, dn, j, r


@njit(cache=True, nogil=True)
def jacobi_amplitude(u, kc):
    """Jacobi amplitude and ``sn, cn, dn`` of real ``u`` with modulus ``kc``.

    Returns ``am, sn, cn, dn, j, r`` with ``am`` continuous in ``u``
    (``am = j pi + atan2(sn(r), cn(r))``); convenience form of
    :func:`agm_table` + :func:`jacobi_from_table` for one argument.
    """
    means = np.empty(AGM_LEVELS)
    geometric = np.empty(AGM_LEVELS)
    levels = agm_table(kc, means, geometric)
    sn, cn, dn, j, r = jacobi_from_table(u, levels, means, geometric)
    parity = 1.0 - 2.0 * (j % 2.0 != 0.0)
    return j * math.pi + math.atan2(parity * sn, parity * cn), sn, cn, dn, j, r


@njit(cache=True, nogil=True)
def cel_passes(kc):
    """Passes that :func:`cel`'s loop makes for the modulus ``kc`` (``> 0``).

    The loop stops on the AGM pair of ``(1, kc)`` alone, whatever ``p, a,
    b``.  One AGM step maps the ratio ``r = b/a`` of the pair to ``2 sqrt(r)
    / (1 + r)``, an increasing function on ``(0, 1]``; by induction the gap
    after any number of steps is decreasing in ``kc``.  So the count for
    the smallest ``kc`` of a batch is enough for every member of it: this
    is what makes :func:`cel_lanes` exact to the same tolerance as ``cel``.
    """
    kc = abs(kc)
    gm = 1.0
    e = kc
    for n in range(1, _MAX_AGM + 1):
        previous = gm
        gm = kc + gm
        if abs(previous - kc) <= previous * _CEL_GAP:
            return n
        kc = 2.0 * math.sqrt(e)
        e = kc * gm
    return _MAX_AGM


@njit(cache=True, nogil=True)
def cel_lanes(kc, p, a, b, out, count, passes, gm, e, root_p):
    """``out[k] = cel(kc[k], p[k], a[k], b[k])`` for ``k < count``, SIMD form.

    The same Landen/Bartky passes as :func:`cel` (Bulirsch 1969), but a
    fixed number ``passes`` of them for every lane and no data-dependent
    branch, so that LLVM vectorises the loop over lanes (AVX2/AVX-512).
    ``passes`` must be at least :func:`cel_passes` of the smallest ``kc``
    (then every lane has met the stopping test of ``cel``; further passes
    keep the integral invariant and only double the AGM pair).  Every
    ``kc`` must be nonzero and every ``p`` positive.  The input arrays are
    overwritten (they hold the iteration's state); ``gm, e, root_p`` are
    scratch arrays of at least ``count`` elements.
    """
    for k in range(count):
        gm[k] = 1.0
        k_c = abs(kc[k])
        kc[k] = k_c
        e[k] = k_c
        r = math.sqrt(p[k])
        root_p[k] = r
        b[k] = b[k] / r
    for _ in range(passes):
        for k in range(count):
            inv_root_p = 1.0 / root_p[k]
            f = a[k]
            a[k] = f + b[k] * inv_root_p
            g = e[k] * inv_root_p
            b[k] = 2.0 * (b[k] + f * g)
            root_p[k] = g + root_p[k]
            m = kc[k] + gm[k]
            gm[k] = m
            k_c = 2.0 * math.sqrt(e[k])
            kc[k] = k_c
            e[k] = k_c * m
    for k in range(count):
        m = gm[k]
        out[k] = HALF_PI * (b[k] + a[k] * m) / (m * (m + root_p[k]))


@njit(cache=True, nogil=True)
def cel_dual(kc, kc_dot, p, p_dot, a, a_dot, b, b_dot):
    """:func:`cel` and its derivative along a direction (forward mode).

    Returns ``cel(kc, p, a, b)`` and ``d cel = (dcel/dkc) kc_dot + (dcel/dp)
    p_dot + (dcel/da) a_dot + (dcel/db) b_dot``, by carrying the derivative
    of every quantity through the same passes as :func:`cel` (each pass is
    an algebraic map, differentiated exactly).  The value is bit-for-bit the
    one :func:`cel` returns; the derivative converges with the iteration
    (it is quadratically convergent too) and is good to ~1e-15 relative
    where it is not itself the small difference of large terms.
    """
    if kc == 0.0 or not (p > 0.0):
        return np.nan, np.nan
    if kc < 0.0:
        kc = -kc
        kc_dot = -kc_dot
    gm = 1.0
    gm_dot = 0.0
    e = kc
    e_dot = kc_dot
    root_p = math.sqrt(p)
    root_p_dot = 0.5 * p_dot / root_p
    b_dot = (b_dot - b * root_p_dot / root_p) / root_p
    b = b / root_p
    for _ in range(_MAX_AGM):
        inv_root_p = 1.0 / root_p
        inv_dot = -root_p_dot * inv_root_p * inv_root_p
        f = a
        f_dot = a_dot
        a = a + b * inv_root_p
        a_dot = a_dot + b_dot * inv_root_p + b * inv_dot
        g = e * inv_root_p
        g_dot = e_dot * inv_root_p + e * inv_dot
        b = 2.0 * (b + f * g)
        b_dot = 2.0 * (b_dot + f_dot * g + f * g_dot)
        root_p = g + root_p
        root_p_dot = g_dot + root_p_dot
        previous = gm
        gm = kc + gm
        gm_dot = kc_dot + gm_dot
        if abs(previous - kc) <= previous * _CEL_GAP:
            break
        root_e = math.sqrt(e)
        kc = 2.0 * root_e
        kc_dot = e_dot / root_e
        e = kc * gm
        e_dot = kc_dot * gm + kc * gm_dot
    num = b + a * gm
    num_dot = b_dot + a_dot * gm + a * gm_dot
    den = gm * (gm + root_p)
    den_dot = gm_dot * (gm + root_p) + gm * (gm_dot + root_p_dot)
    return HALF_PI * num / den, HALF_PI * (num_dot * den - num * den_dot) / (den * den)
