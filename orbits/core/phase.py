"""Closed-form total phase of the force-free asymmetric top (numba kernels).

All kernels take raw principal moments ``I1 < I2 < I3`` (any positive
scale: the phase is homogeneous of degree 0 in the moments, so they are
never normalised here -- normalising would round away the small
differences ``I3 - I2`` of nearly symmetric bodies) and a unit initial
angular velocity

    omega0 = (sin(theta) cos(phi), sin(theta) sin(phi), cos(theta))

in the principal frame.  ``theta`` is measured from the I3 axis and ``phi``
from the I1 axis.

Formulas (Mecholsky 2019, "Analytic formula for the Geometric Phase of an
Asymmetric Top"; labels are the paper's LaTeX labels):

* ``M^2 - 2 E I1 = I2 (I2-I1) w2^2 + I3 (I3-I1) w3^2`` and
  ``2 E I3 - M^2 = I1 (I3-I1) w1^2 + I2 (I3-I2) w2^2`` are sums of
  non-negative terms (eqn:MM, eqn:EM), so they carry no cancellation.
* ``M^2 - 2 E I2 = A cos^2(theta) - B_phi sin^2(theta)`` with
  ``A = I3 (I3-I2)`` and ``B_phi = I1 (I2-I1) cos^2(phi)`` vanishes on the
  separatrix; it is evaluated in the factored form
  ``-(A + B_phi) sin(dtheta) sin(theta + theta_c)``, where
  ``tan(theta_c) = sqrt(A / B_phi)`` and ``dtheta = theta - theta_c``
  (see :func:`spin_gap`).
* ``1 - k^2`` follows from the identity
  ``(I3-I2)(M^2-2EI1) - (I2-I1)(2EI3-M^2) = (I3-I1)(M^2-2EI2)``.
* eqn:GeometricPhase, with ``I1 K + (I3-I1) Pi(n|k^2)`` written as one
  Bulirsch integral ``I3 cel(kc, 1-n, 1, b)``:

  - SAM (``M^2 > 2EI2``): ``1-n = I2 (I3-I1) / (I1 (I3-I2))``,
    ``b = (I3-I1)/(I3-I2)``, ``D = sqrt((I3-I2)(M^2-2EI1)/(I1 I2 I3))``,
    ``Delta alpha = 4 M cel / (I1 D) - 2 pi``.
  - LAM (``M^2 < 2EI2``): ``1-n = (I3-I1) M^2 / (I1 (2EI3-M^2))``,
    ``b = 2E (I3-I1) / (2EI3-M^2)``,
    ``D = sqrt((I2-I1)(2EI3-M^2)/(I1 I2 I3))``,
    ``Delta alpha = 4 M cel / (I1 D)``.

  Period ``T = 4 K / D`` (eqn:TK) with ``K = cel(kc, 1-n, 1, 1-n)`` from the
  same AGM loop.
"""

import math

import numpy as np
from numba import njit, prange

from .angles import fold_checked
from .elliptic import cel, cel_lanes, cel_pair, cel_passes
from .exact import separatrix_gap_exact
from .launch import parallel_kernel
from .trig import cos_small, sin_small

TWO_PI = 2.0 * math.pi
# Delta alpha >= 2 pi at both ends of every branch, 2 pi exactly only as the
# flat edge's theta -> 0 limit, where rounding can land a few ulp below
# (3.6e-15 rad measured); at_least_two_pi raises such values to 2 pi and
# keeps any value further below as computed (only a counterexample to the
# paper's conjecture, a minimum inside a branch, could give one)
TWO_PI_ROUNDING = 2.0**-40
HALF_PI = 0.5 * math.pi
QUARTER_PI = 0.25 * math.pi
# pi/2 - HALF_PI: the part of pi/2 that the double HALF_PI rounds away
HALF_PI_LOW = 6.123233995736766e-17
_END_SLACK = 4.0 * 2.220446049250313e-16
# below this |sin(dtheta)| the gap is assembled factor by factor (underflow)
_TINY_OFFSET = 1.0e-200
# the rounding error of theta_c and of pi/2 - theta_c (body_constants), in
# units of 2**-53 times the smaller of the two: at most ~6 by the error
# analysis (the roundings of A, B_phi and cos phi, halved by the square roots
# and scaled by sin cos in atan2, atan2's own, and pi/2 - theta's low part),
# at most 3.4 measured against mpmath over 20,000 bodies; twice that margin
SIDE_SLACK = 16.0 * 2.0**-53

# the smallest kc = sqrt(1 - k^2) an orbit may have: 10**12 steps of the
# subnormals (4.9e-312), as the command line's smallest --dtheta.  Below it
# kc keeps fewer than 12 digits and the period ~ log(4/kc) loses more than
# 1e-15 relative (spins (e, 1, e) with e ~ 1e-320: 5e-7; at 5e-324 kc is 0);
# only a spin vector that near the separatrix gets there, (e, 1, e) for e
# below ~1e-311 on the Fig. 6 body (an offset dtheta >= 4.9e-312 gives kc
# above 1e-170 on every body swept, phi = pi/2 the lowest).  Such orbits are
# the separatrix's.
KC_FLOOR = 2.0**-1074 * 1e12

BRANCH_SAM = 1  # short-axis mode, M^2 > 2 E I2: M circles the I3 axis
BRANCH_LAM = -1  # long-axis mode,  M^2 < 2 E I2: M circles the I1 axis
BRANCH_SEPARATRIX = 0

STATUS_OK = 0
STATUS_OUT_OF_RANGE = 1
STATUS_SEPARATRIX = 2
STATUS_NOT_FINITE = 3
# |theta| beyond the fold limit (orbits.phases.FOLD_LIMIT): not folded
STATUS_TOO_LARGE = 4


@njit(cache=True, nogil=True)
def at_least_two_pi(total):
    """``Delta alpha`` raised to ``2 pi`` where it lies below by rounding alone.

    Within :data:`TWO_PI_ROUNDING` (relative) below ``2 pi``: ``2 pi``;
    anything else (NaN included) as given.
    """
    if total < TWO_PI and total >= TWO_PI * (1.0 - TWO_PI_ROUNDING):
        return TWO_PI
    return total


@njit(cache=True, nogil=True)
def critical_angle(i1, i2, i3, phi):
    """Polar angle of omega0 on the separatrix ``M^2 = 2 E I2``.

    ``tan(theta_c) = sqrt(I3 (I3-I2) / (I1 (I2-I1) cos^2 phi))``: the
    paper's critical-angle formula with the erratum in eqn:beta corrected
    (its denominator is ``I3 (I3 - I2)``, not ``I3 (I3 - I1)``).
    """
    a = i3 * (i3 - i2)
    b = i1 * (i2 - i1)
    return math.atan2(math.sqrt(a), math.sqrt(b) * abs(math.cos(phi)))


@njit(cache=True, nogil=True)
def body_constants(i1, i2, i3, phi):
    """Per-(body, phi) constants shared by every polar angle.

    Returns ``cos phi, sin phi, theta_c, pi/2 - theta_c, sqrt(A),
    sqrt(B_phi), sqrt(A + B_phi)`` with ``A = I3 (I3-I2)`` and
    ``B_phi = I1 (I2-I1) cos^2 phi``.  Both angles come from ``atan2``
    directly, so each is accurate where it is small.
    """
    cphi = math.cos(phi)
    sphi = math.sin(phi)
    a = i3 * (i3 - i2)
    b = i1 * (i2 - i1) * cphi * cphi
    root_a = math.sqrt(a)
    root_b = math.sqrt(b)
    return (
        cphi,
        sphi,
        math.atan2(root_a, root_b),
        math.atan2(root_b, root_a),
        root_a,
        root_b,
        math.sqrt(a + b),
    )


@njit(cache=True, nogil=True)
def side_slack(theta_c, co_theta_c):
    """Radians within which a given ``theta`` may lie on either side of ``theta_c``.

    :data:`SIDE_SLACK` times the smaller of ``theta_c`` and ``pi/2 - theta_c``
    (as :func:`body_constants` gives them): a bound on the rounding error of
    the one of the two that :func:`angle_triplet` subtracts from.
    """
    return SIDE_SLACK * min(theta_c, co_theta_c)


@njit(cache=True, nogil=True)
def end_slack(dtheta):
    """Radians an offset ``dtheta`` may reach past ``theta = 0`` or ``pi/2``
    and be taken as that end: the rounding of ``pi/2 - theta_c`` or
    ``-theta_c`` as a caller writes them (``_END_SLACK``, 4 ulp of pi/2),
    and at most ``2**-27 |dtheta|``.

    The phase is even about each end (``theta -> -theta`` and ``theta -> pi -
    theta`` are symmetries of the top), so the end's value differs from the
    folded spin's by ``~(x / delta)^2`` for an overshoot ``x`` and an end
    ``delta`` from the separatrix: below 2**-54 with the second bound.  An
    end within ~1e-7 of the separatrix (``phi`` next to pi/2, where
    ``theta_c -> pi/2``) takes no slack there: the spin past the end folds
    back onto the other branch (``dtheta = 3e-16`` at ``phi = pi/2`` on the
    Fig. 6 body gave 261.85 on LAM; the spin is SAM, 249.53).
    """
    return min(_END_SLACK, abs(dtheta) * 2.0**-27)


@njit(cache=True, nogil=True)
def angle_triplet(angle, from_offset, theta_c, co_theta_c):
    """``theta, dtheta, co_theta`` and a status code from the given angle.

    ``angle`` is ``theta`` or, with ``from_offset``, ``dtheta``.  Each of the
    three is formed so that it keeps its relative precision where it is
    small: ``pi/2 - theta`` in two parts, and the offset from the smaller
    pair (``pi/2 - theta_c`` is far better known than ``theta_c`` for an
    oblate body).  An offset a hair past an end of [0, pi/2] (within
    :func:`end_slack`) lands on the end, with the end's offset.

    A ``theta`` within the rounding error of the computed ``theta_c``
    (:func:`side_slack`) is ``STATUS_SEPARATRIX``: the sign of
    ``theta - theta_c``, the branch, cannot be told in double precision
    there (an offset ``dtheta`` is exact and never is).
    """
    if not math.isfinite(angle):
        return angle, angle, angle, STATUS_NOT_FINITE
    if from_offset:
        dtheta = angle
        theta = theta_c + dtheta
        co_theta = co_theta_c - dtheta
        # past an end by rounding alone: the end itself, with the end's own
        # offset (the spin and its separatrix gap must agree)
        if theta < 0.0:
            if theta < -end_slack(dtheta):
                return theta, dtheta, co_theta, STATUS_OUT_OF_RANGE
            theta, dtheta, co_theta = 0.0, -theta_c, HALF_PI
        if co_theta < 0.0:
            if co_theta < -end_slack(dtheta):
                return theta, dtheta, co_theta, STATUS_OUT_OF_RANGE
            theta, dtheta, co_theta = HALF_PI, co_theta_c, 0.0
    else:
        theta = angle
        if theta < 0.0 or theta > HALF_PI:
            return theta, theta - theta_c, HALF_PI - theta, STATUS_OUT_OF_RANGE
        co_theta = (HALF_PI - theta) + HALF_PI_LOW
        if theta_c <= QUARTER_PI:
            dtheta = theta - theta_c
        else:
            dtheta = co_theta_c - co_theta
        if abs(dtheta) <= side_slack(theta_c, co_theta_c):
            return theta, dtheta, co_theta, STATUS_SEPARATRIX
    if dtheta == 0.0:
        return theta, dtheta, co_theta, STATUS_SEPARATRIX
    return theta, dtheta, co_theta, STATUS_OK


@njit(cache=True, nogil=True)
def given_angle(angle, from_offset, fold_limit):
    """The polar angle as the kernels use it, and a status code.

    ``theta`` (``from_offset`` false) is folded into ``[0, pi/2]``
    (:func:`orbits.core.angles.fold_one`) unless it is finite with
    ``|theta| > fold_limit`` (``STATUS_TOO_LARGE``); ``dtheta`` is not
    folded.  NaN and inf pass through (:func:`angle_triplet` flags them).
    """
    if from_offset:
        return angle, STATUS_OK
    folded, ok = fold_checked(angle, fold_limit)
    return folded, STATUS_OK if ok else STATUS_TOO_LARGE


@njit(cache=True, nogil=True)
def spin_gap(cphi, sphi, root_a, root_b, root_ab, theta, dtheta, co_theta):
    """Unit spin and ``M^2 - 2 E I2`` as a product of three factors.

    Returns ``w1, w2, w3, scale, offset, closing`` with
    ``M^2 - 2 E I2 = -scale * offset * closing``, ``scale > 0`` and
    ``closing >= 0``; ``offset`` carries the sign and the separatrix
    distance.  The factors are never multiplied here, because at
    ``|dtheta| ~ 1e-300`` the product can underflow.

    Notes
    -----
    ``M^2 - 2 E I2 = A cos^2 t - B_phi sin^2 t
    = -(A + B_phi) sin(t - t_c) sin(t + t_c)``, and with
    ``sin t_c = sqrt(A/(A+B_phi))``, ``cos t_c = sqrt(B_phi/(A+B_phi))``,
    ``sin(t + t_c) = (sin t sqrt(B_phi) + cos t sqrt(A)) / sqrt(A + B_phi)``:
    a sum of non-negative terms, accurate even when ``t + t_c -> pi``
    (oblate bodies).  ``sin(t - t_c) = sin(dtheta)`` holds the small
    distance at full relative precision.
    """
    w3 = math.sin(co_theta) if co_theta < theta else math.cos(theta)
    st = math.sin(theta)
    closing = st * root_b + w3 * root_a
    return st * cphi, st * sphi, w3, root_ab, math.sin(dtheta), closing


@njit(cache=True, nogil=True)
def spin_from_angle(constants, angle, from_offset):
    """The unit spin and its separatrix gap from one polar angle.

    ``constants`` from :func:`body_constants`; ``angle`` is ``theta`` or,
    with ``from_offset``, ``dtheta``.  Returns ``code, theta, dtheta, theta_c,
    w1, w2, w3, scale, offset, closing`` (see :func:`angle_triplet` and
    :func:`spin_gap`); when ``code`` is not ``STATUS_OK`` the spin is zero.
    """
    cphi, sphi, theta_c, co_theta_c, root_a, root_b, root_ab = constants
    theta, dtheta, co_theta, code = angle_triplet(angle, from_offset, theta_c, co_theta_c)
    if code != STATUS_OK:
        return code, theta, dtheta, theta_c, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    w1, w2, w3, scale, offset, closing = spin_gap(
        cphi, sphi, root_a, root_b, root_ab, theta, dtheta, co_theta
    )
    return code, theta, dtheta, theta_c, w1, w2, w3, scale, offset, closing


@njit(cache=True, nogil=True)
def vector_gap(i1, i2, i3, w1, w2, w3):
    """``M^2 - 2 E I2`` in the factor form of :func:`spin_gap` for a vector.

    The orbit through a spin given in doubles is exact, and so is its
    separatrix gap ``I3 (I3-I2) w3^2 - I1 (I2-I1) w1^2``: it is evaluated in
    double-double arithmetic and rounded once (:mod:`orbits.core.exact`).

    Where ``w1`` and ``w3`` are below ~1e-150 their squares are subnormal
    and the gap would lose its relative precision (and with it ``kc``:
    ``spin_phases`` of (1e-160, 1, 1e-160) on the Fig. 6 body was 6.8e-6
    off, and (0, 1, 1e-170) was called the separatrix).  There ``w1, w3``
    are scaled by ``2^k`` (exact) and the factor ``2^-2k`` is carried by
    ``scale`` and ``closing``, with ``|offset|`` near ``2^-700`` so that
    :func:`orbit_constants` takes the square roots factor by factor and
    nothing underflows.
    """
    return scaled_vector_gap(i1, i2, i3, w1, w3, 0)


@njit(cache=True, nogil=True)
def scaled_vector_gap(i1, i2, i3, w1, w3, speed):
    """:func:`vector_gap` of the spin ``omega / 2**speed``, from ``omega``'s
    own components ``w1, w3`` (``w2`` does not enter the gap).

    The kernels see a spin scaled by ``2**-speed`` (largest component in
    [1/2, 1)); that scaling rounds a component it takes below the smallest
    normal double (2.2e-308), and near a nearly symmetric body such a
    component sets the gap: (0, 1, 1e-317) on I = (1, 1 + 1e-12, 1.5),
    halved first, had a period 6.9e-10 off.  The small components are
    therefore scaled from the given ones, by one exact power of two.
    """
    small = max(abs(w1), abs(w3))
    # small / 2**speed lies in [2**(top - 1), 2**top)
    top = math.frexp(small)[1] - speed
    if small == 0.0 or top >= -479:  # the larger scaled one >= 2^-480: exact
        gap = separatrix_gap_exact(i1, i2, i3, math.ldexp(w1, -speed), math.ldexp(w3, -speed))
        return 1.0, -gap, 1.0
    k = -top  # the scaled pair times 2^k, the larger in [1/2, 1): exact
    offset = -separatrix_gap_exact(
        i1, i2, i3, math.ldexp(w1, k - speed), math.ldexp(w3, k - speed)
    )
    if offset == 0.0:
        return 1.0, 0.0, 1.0
    shift = max(0, math.frexp(offset)[1] + 700)  # |offset| 2^-shift near 2^-700
    rest = 2 * k - shift  # the gap is offset 2^-(shift + rest)
    half = rest // 2
    return math.ldexp(1.0, -half), math.ldexp(offset, -shift), math.ldexp(1.0, half - rest)


@njit(cache=True, nogil=True)
def scaled_spin(i1, i2, i3, w1, w2, w3, speed):
    """``omega / 2**speed`` and its separatrix gap: ``u1, u2, u3, scale,
    offset, closing``, the gap from the given components
    (:func:`scaled_vector_gap`), for the kernels of spin vectors."""
    scale, offset, closing = scaled_vector_gap(i1, i2, i3, w1, w3, speed)
    return (
        math.ldexp(w1, -speed),
        math.ldexp(w2, -speed),
        math.ldexp(w3, -speed),
        scale,
        offset,
        closing,
    )


@njit(cache=True, nogil=True)
def orbit_constants(i1, i2, i3, w1, w2, w3, scale, offset, closing):
    """Elliptic constants of the orbit through ``omega = (w1, w2, w3)``.

    Parameters
    ----------
    i1, i2, i3 : float
        Principal moments, ascending, any scale.
    w1, w2, w3 : float
        Angular velocity in the principal frame, any magnitude.
    scale, offset, closing : float
        ``M^2 - 2 E I2 = -scale * offset * closing`` (see :func:`spin_gap`).

    Returns
    -------
    branch, two_e, m_sq, gap_m1, gap_3m, kc, q, p, b : float
        Branch code (+1 SAM, -1 LAM, 0 separatrix); ``2E`` and ``M^2``
        (eqn:E, eqn:J); the invariants ``M^2 - 2 E I1`` and ``2 E I3 - M^2``;
        ``kc = sqrt(1 - k^2)`` for the ``k`` of eqn:TK;
        ``q`` with ``D^2 = q / (I1 I2 I3)`` for the ``D`` of eqn:ABCD(d);
        and ``p, b`` such that ``cel(kc, p, 1, b) = (I1 K + (I3-I1) Pi(n|k^2))
        / I3`` with ``p = 1 - n`` of eqn:GeometricPhase.  On LAM ``k``,
        ``kc`` and ``q`` are the images under ``1 <-> 3`` (eqn:TK), while
        ``p`` and ``b`` are those of the paper's own LAM case of
        eqn:GeometricPhase (not the relabelled SAM ones: that relabelling
        gives Delta alpha - 4 pi).

    Notes
    -----
    ``M^2 - 2 E I1`` and ``2 E I3 - M^2`` are sums of non-negative terms.
    ``1 - k^2`` follows from the identity
    ``(I3-I2)(M^2-2EI1) - (I2-I1)(2EI3-M^2) = (I3-I1)(M^2-2EI2)``:
    ``1 - k^2 = (I3-I1)(M^2-2EI2) / ((I3-I2)(M^2-2EI1))`` on SAM and
    ``(I3-I1)(2EI2-M^2) / ((I2-I1)(2EI3-M^2))`` on LAM, so it is never
    formed as ``1 - m``.
    """
    d21 = i2 - i1
    d31 = i3 - i1
    d32 = i3 - i2
    s1 = w1 * w1
    s2 = w2 * w2
    s3 = w3 * w3
    two_e = i1 * s1 + i2 * s2 + i3 * s3
    m_sq = i1 * i1 * s1 + i2 * i2 * s2 + i3 * i3 * s3
    gap_m1 = i2 * d21 * s2 + i3 * d31 * s3  # M^2 - 2 E I1
    gap_3m = i1 * d31 * s1 + i2 * d32 * s2  # 2 E I3 - M^2
    if offset == 0.0 or closing == 0.0:
        return 0, two_e, m_sq, gap_m1, gap_3m, 0.0, 0.0, 0.0, 0.0
    if offset < 0.0:  # M^2 > 2 E I2
        branch = BRANCH_SAM
        q = d32 * gap_m1
        p = i2 * d31 / (i1 * d32)
        b = d31 / d32
    else:
        branch = BRANCH_LAM
        q = d21 * gap_3m
        p = d31 * m_sq / (i1 * gap_3m)
        b = two_e * d31 / gap_3m
    magnitude = abs(offset)
    if magnitude > _TINY_OFFSET:
        kc = math.sqrt(d31 * scale * magnitude * closing / q)
    else:
        kc = math.sqrt(d31 / q) * math.sqrt(scale) * math.sqrt(magnitude) * math.sqrt(closing)
    if kc < KC_FLOOR:  # beyond a double's reach of the separatrix (KC_FLOOR)
        return 0, two_e, m_sq, gap_m1, gap_3m, 0.0, 0.0, 0.0, 0.0
    return branch, two_e, m_sq, gap_m1, gap_3m, kc, q, p, b


@njit(cache=True, nogil=True)
def elliptic_parameter(i1, i2, i3, branch, gap_m1, gap_3m, kc):
    """``m = k^2`` of eqn:TK: ``(I2-I1)(2EI3-M^2) / ((I3-I2)(M^2-2EI1))`` on
    SAM, its 1 <-> 3 image on LAM; ``1 - kc^2`` where that is above 1/2.

    Near the separatrix the quotient of gaps carries a few ulps of rounding,
    which put ``m`` above 1 (1 + 4 ulp) on 7 of the 58 rows of the t-handle
    catalog (n up to 30; 67 of 571 with q <= 5), outside the domain of
    ``K(m)``; ``kc`` comes from the factored ``M^2 - 2EI2``
    (:func:`orbit_constants`), so ``1 - kc^2`` is as accurate as ``kc^2``
    (a few ulps, scaled by ``kc^2 < 1/2``) and never above 1 (it rounds to
    1 when ``1 - m < 1.1e-16``, where ``dtheta`` is the label to use).
    """
    complement = kc * kc
    if complement < 0.5:
        return 1.0 - complement
    if branch == BRANCH_SAM:
        return (i2 - i1) * gap_3m / ((i3 - i2) * gap_m1)
    return (i3 - i2) * gap_m1 / ((i2 - i1) * gap_3m)


@njit(cache=True, nogil=True)
def total_from_spin(i1, i2, i3, w1, w2, w3, scale, offset, closing):
    """Total phase ``Delta alpha`` (eqn:GeometricPhase) with one ``cel`` loop.

    ``Delta alpha = 4 M cel(kc, p, 1, b) / (I1 D) - 2 pi [SAM]``, where
    ``4 M / (I1 D) = 4 sqrt(M^2 I2 I3 / (I1 q))``.  Inf on the separatrix.
    """
    branch, two_e, m_sq, _, _, kc, q, p, b = orbit_constants(
        i1, i2, i3, w1, w2, w3, scale, offset, closing
    )
    if branch == BRANCH_SEPARATRIX:
        return np.inf
    total = 4.0 * math.sqrt(m_sq * i2 * i3 / (i1 * q)) * cel(kc, p, 1.0, b)
    return total - TWO_PI if branch == BRANCH_SAM else total


@njit(cache=True, nogil=True)
def parts_from_spin(i1, i2, i3, w1, w2, w3, scale, offset, closing):
    """``2E, M^2, m, branch, T, 2ET/M, Delta alpha`` for one orbit.

    ``T = 4 K / D`` (eqn:TK) with ``K = cel(kc, p, 1, p)`` from the same AGM
    loop as the total phase.  On the separatrix ``T``, ``2ET/M`` and
    ``Delta alpha`` are inf and ``m = 1``.
    """
    branch, two_e, m_sq, gap_m1, gap_3m, kc, q, p, b = orbit_constants(
        i1, i2, i3, w1, w2, w3, scale, offset, closing
    )
    if branch == BRANCH_SEPARATRIX:
        return two_e, m_sq, 1.0, 0, np.inf, np.inf, np.inf
    m_param = elliptic_parameter(i1, i2, i3, branch, gap_m1, gap_3m, kc)
    bracket, quarter = cel_pair(kc, p, 1.0, b, 1.0, p)
    rate = math.sqrt(q / (i1 * i2 * i3))
    momentum = math.sqrt(m_sq)
    total = 4.0 * momentum * bracket / (i1 * rate)
    if branch == BRANCH_SAM:
        total -= TWO_PI
    period = 4.0 * quarter / rate
    return two_e, m_sq, m_param, branch, period, two_e * period / momentum, total


# lanes per batch of the SIMD path (its state stays in L1), and batches per
# parallel task (the scratch rows are allocated once per task)
LANES = 256
BATCHES = 16
_ROWS = 10


@njit(cache=True, nogil=True, error_model="numpy")
def _lane_setup(work, j, i1, i2, i3, constants, angle, from_offset):
    """Fill lane ``j`` of ``work`` for one angle; returns the status code.

    Rows: 0 ``kc``, 1 ``p``, 2 ``a = 1``, 3 ``b``, 4 the factor
    ``4 M / (I1 D)`` and 5 the shift (``2 pi`` on SAM), as in
    :func:`total_from_spin`.  Lanes off the phase's domain get harmless
    values and an infinite factor.
    """
    code, _, _, _, w1, w2, w3, scale, offset, closing = spin_from_angle(
        constants, angle, from_offset
    )
    branch = BRANCH_SEPARATRIX
    if code == STATUS_OK:
        branch, _, m_sq, _, _, k_c, q, p, b = orbit_constants(
            i1, i2, i3, w1, w2, w3, scale, offset, closing
        )
    work[2, j] = 1.0
    if branch == BRANCH_SEPARATRIX:
        work[0, j] = 1.0
        work[1, j] = 1.0
        work[3, j] = 1.0
        work[4, j] = np.inf
        work[5, j] = 0.0
    else:
        work[0, j] = k_c
        work[1, j] = p
        work[3, j] = b
        work[4, j] = 4.0 * math.sqrt(m_sq * i2 * i3 / (i1 * q))
        work[5, j] = TWO_PI if branch == BRANCH_SAM else 0.0
    return code


@njit(cache=True, nogil=True, error_model="numpy")
def _lane_finish(work, count, out, lo):
    """``cel`` of the filled lanes, then ``out[lo + j]``, at least ``2 pi``."""
    smallest = 1.0
    for j in range(count):
        smallest = min(smallest, work[0, j])
    cel_lanes(
        work[0],
        work[1],
        work[2],
        work[3],
        work[6],
        count,
        cel_passes(smallest),
        work[7],
        work[8],
        work[9],
    )
    for j in range(count):
        total = work[4, j] * work[6, j] - work[5, j]
        # 2 pi where below it by rounding (at_least_two_pi); NaN stays NaN
        out[lo + j] = at_least_two_pi(total)


@njit(cache=True, nogil=True, error_model="numpy")
def _one_body_setup(i1, i2, i3, constants, theta, dtheta, co_theta, work, count):
    """Rows 0-5 of ``work`` (see :func:`_lane_setup`) for valid lanes, SIMD form.

    The arithmetic of :func:`spin_gap`, :func:`orbit_constants` and
    :func:`total_from_spin` with selects instead of branches and with
    ``sin``/``cos`` by polynomials on ``[0, pi/4]`` (the reduction uses the
    accurately known complement ``co_theta``), so that LLVM vectorises the
    loop.  Lanes must be valid (status OK); ``kc`` is formed as
    ``sqrt(r) sqrt(|sin dtheta|)``, which cannot underflow.
    """
    cphi, sphi, _, _, root_a, root_b, scale = constants
    d21 = i2 - i1
    d31 = i3 - i1
    d32 = i3 - i2
    p_sam = i2 * d31 / (i1 * d32)
    b_sam = d31 / d32
    inv_i1 = 1.0 / i1
    i23_i1 = i2 * i3 / i1
    for j in range(count):
        t = theta[j]
        c = co_theta[j]
        low = t <= QUARTER_PI
        x = t if low else c
        sx = sin_small(x)
        cx = cos_small(x)
        st = sx if low else cx
        w3 = cx if low else sx
        dt = dtheta[j]
        mag = abs(dt)
        near = mag <= QUARTER_PI
        y = mag if near else (HALF_PI - mag) + HALF_PI_LOW
        offset = sin_small(y) if near else cos_small(y)  # |sin dtheta|
        closing = st * root_b + w3 * root_a
        w1 = st * cphi
        w2 = st * sphi
        s1 = w1 * w1
        s2 = w2 * w2
        s3 = w3 * w3
        two_e = i1 * s1 + i2 * s2 + i3 * s3
        m_sq = i1 * i1 * s1 + i2 * i2 * s2 + i3 * i3 * s3
        gap_m1 = i2 * d21 * s2 + i3 * d31 * s3
        gap_3m = i1 * d31 * s1 + i2 * d32 * s2
        sam = dt < 0.0
        inv_q = 1.0 / (d32 * gap_m1 if sam else d21 * gap_3m)
        # d31 / gap_3m: only the LAM lanes use it (two divisions per lane in all)
        ratio = d31 / gap_3m
        work[0, j] = math.sqrt(d31 * scale * closing * inv_q) * math.sqrt(offset)
        work[1, j] = p_sam if sam else m_sq * ratio * inv_i1
        work[2, j] = 1.0
        work[3, j] = b_sam if sam else two_e * ratio
        work[4, j] = 4.0 * math.sqrt(m_sq * i23_i1 * inv_q)
        work[5, j] = TWO_PI if sam else 0.0


@parallel_kernel(cache=True, nogil=True)
def total_phase_one_body(i1, i2, i3, phi, angles, from_offset, fold_limit, out, status):
    """Total phase of one body at many polar angles (scalar ``phi``).

    ``angles`` are ``theta`` as given (folded here, :func:`given_angle`) or,
    with ``from_offset``, ``dtheta``; ``phi`` is already folded.  ``out``
    is at least ``2 pi`` (``orbits.phases.at_least_two_pi``).
    Per-body constants are computed once.  ``status`` receives one of the
    ``STATUS_*`` codes per point; ``out`` is inf where it is not OK.
    Batches of :data:`LANES` angles run through SIMD loops: the set-up of
    :func:`_one_body_setup` and the ``cel`` of
    :func:`orbits.core.elliptic.cel_lanes`, with the pass count of ``cel``
    for the smallest ``kc`` of the batch, which is enough for every lane
    (:func:`orbits.core.elliptic.cel_passes`): the same values as
    :func:`total_from_spin` to a few ulps.
    """
    constants = body_constants(i1, i2, i3, phi)
    theta_c = constants[2]
    co_theta_c = constants[3]
    # a valid stand-in for lanes off the domain (their result is replaced)
    safe = 0.5 * theta_c if theta_c > 0.0 else 0.5 * co_theta_c
    n = angles.shape[0]
    task = LANES * BATCHES
    for t in prange((n + task - 1) // task):
        work = np.empty((_ROWS, LANES))
        lane = np.empty((3, LANES))
        for lo in range(t * task, min(n, (t + 1) * task), LANES):
            count = min(n, lo + LANES) - lo
            bad = 0
            for j in range(count):
                angle, code = given_angle(angles[lo + j], from_offset, fold_limit)
                if code == STATUS_OK:
                    theta, dtheta, co_theta, code = angle_triplet(
                        angle, from_offset, theta_c, co_theta_c
                    )
                status[lo + j] = code
                if code != STATUS_OK:
                    bad += 1
                    theta, dtheta, co_theta, _ = angle_triplet(safe, False, theta_c, co_theta_c)
                lane[0, j] = theta
                lane[1, j] = dtheta
                lane[2, j] = co_theta
            # full batches pass the constant LANES: with the trip count known
            # at compile time LLVM's vector code is ~1.7x faster (measured)
            if count == LANES:
                _one_body_setup(i1, i2, i3, constants, lane[0], lane[1], lane[2], work, LANES)
            else:
                _one_body_setup(i1, i2, i3, constants, lane[0], lane[1], lane[2], work, count)
            if bad:
                for j in range(count):
                    if status[lo + j] != STATUS_OK:
                        work[4, j] = np.inf
                        work[5, j] = 0.0
            if count == LANES:
                _lane_finish(work, LANES, out, lo)
            else:
                _lane_finish(work, count, out, lo)


@parallel_kernel(cache=True, nogil=True)
def total_phase_many(i1, i2, i3, phi, angles, from_offset, fold_limit, out, status):
    """Total phase with every input an array of the same length (SIMD path).

    ``angles`` and ``out`` as for :func:`total_phase_one_body`; ``phi`` folded.
    """
    n = angles.shape[0]
    task = LANES * BATCHES
    for t in prange((n + task - 1) // task):
        work = np.empty((_ROWS, LANES))
        for lo in range(t * task, min(n, (t + 1) * task), LANES):
            count = min(n, lo + LANES) - lo
            for j in range(count):
                k = lo + j
                angle, code = given_angle(angles[k], from_offset, fold_limit)
                if code != STATUS_OK:
                    # a valid stand-in; its result is never read (the status)
                    angle = 0.5
                status[k] = _lane_setup(
                    work,
                    j,
                    i1[k],
                    i2[k],
                    i3[k],
                    body_constants(i1[k], i2[k], i3[k], phi[k]),
                    angle,
                    from_offset,
                )
                if code != STATUS_OK:
                    status[k] = code
            if count == LANES:
                _lane_finish(work, LANES, out, lo)
            else:
                _lane_finish(work, count, out, lo)


@parallel_kernel(cache=True, nogil=True)
def total_phase_one_body_scalar(i1, i2, i3, phi, angles, from_offset, out, status):
    """The scalar path of :func:`total_phase_one_body` (one looping ``cel`` per
    point, per-body constants once): the reference and the benchmark's
    baseline for the SIMD path."""
    constants = body_constants(i1, i2, i3, phi)
    for k in prange(angles.shape[0]):
        code, _, _, _, w1, w2, w3, scale, offset, closing = spin_from_angle(
            constants, angles[k], from_offset
        )
        status[k] = code
        out[k] = (
            total_from_spin(i1, i2, i3, w1, w2, w3, scale, offset, closing)
            if code == STATUS_OK
            else np.inf
        )


@parallel_kernel(cache=True, nogil=True)
def total_phase_many_scalar(i1, i2, i3, phi, angles, from_offset, out, status):
    """The scalar path of :func:`total_phase_many` (one ``cel`` loop per point).

    Kept as the reference of the SIMD path in the tests.
    """
    for k in prange(angles.shape[0]):
        code, _, _, _, w1, w2, w3, scale, offset, closing = spin_from_angle(
            body_constants(i1[k], i2[k], i3[k], phi[k]), angles[k], from_offset
        )
        status[k] = code
        out[k] = (
            total_from_spin(i1[k], i2[k], i3[k], w1, w2, w3, scale, offset, closing)
            if code == STATUS_OK
            else np.inf
        )


@njit(cache=True, nogil=True)
def _store_parts(out, k, first, parts):
    """Write the seven values of :func:`parts_from_spin` from column ``first``."""
    two_e, m_sq, m_param, branch, period, dynamic, total = parts
    out[k, first] = two_e
    out[k, first + 1] = m_sq
    out[k, first + 2] = m_param
    out[k, first + 3] = branch
    out[k, first + 4] = period
    out[k, first + 5] = dynamic
    out[k, first + 6] = total


@parallel_kernel(cache=True, nogil=True)
def critical_angle_many(i1, i2, i3, phi, out):
    """Vectorised :func:`critical_angle`."""
    for k in prange(out.shape[0]):
        out[k] = critical_angle(i1[k], i2[k], i3[k], phi[k])


@parallel_kernel(cache=True, nogil=True)
def parts_from_vector_array(i1, i2, i3, w1, w2, w3, speed, out):
    """:func:`parts_from_spin` for arbitrary spin vectors; ``out`` (n, 7).

    The spin of row ``k`` is ``(w1, w2, w3) / 2**speed[k]`` (exact scaling
    into the kernels' range; the gap from the given components,
    :func:`scaled_vector_gap`)."""
    for k in prange(out.shape[0]):
        spin = scaled_spin(i1[k], i2[k], i3[k], w1[k], w2[k], w3[k], speed[k])
        _store_parts(out, k, 0, parts_from_spin(i1[k], i2[k], i3[k], *spin))
