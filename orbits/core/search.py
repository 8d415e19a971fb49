"""Closed-orbit search: every offset where the total phase hits a level.

For one body (phi = 0, |omega0| = 1) each branch is parameterised by the
distance ``d = |dtheta|`` from the critical angle: ``dtheta = -d`` on SAM
(``0 < d <= theta_c``) and ``+d`` on LAM (``0 < d <= pi/2 - theta_c``).
``Delta alpha`` grows like ``log(1/d)`` as ``d -> 0``, so the roots of
``Delta alpha = L`` accumulate geometrically at the separatrix; in ``log d``
they are evenly spaced.

Default method (:func:`search_body`, per branch, :func:`newton_branch`):
``Delta alpha(d) = a ln(1/d) + b + O(d ln d)`` with ``a, b`` in closed form
(:func:`separatrix_expansion`) places every root; safeguarded Newton steps
in ``ln d`` with the analytic slope (:func:`phase_slope_of_offset`) finish
it, about 3 phase evaluations per root.  It assumes ``Delta alpha``
decreasing in ``d`` and checks the sign of every slope it computes; where
that fails it hands the branch to the bracketing method below.

Bracketing method (:func:`search_body_bracketing`, the reference), per
branch:

1. Scan ``Delta alpha`` on a merged grid: log-spaced in ``d`` from the
   smallest normal double (2.2e-308) up to the branch width, uniform in
   ``theta`` over the branch, and geometrically approaching the far end
   (``theta -> 0`` or ``pi/2``), where a dip below the end value would sit.
2. Split the branch at every interior extremum of the scanned values
   (each refined by golden section), so that ``Delta alpha`` is monotone on
   each piece; on a monotone piece every level between its end values has
   exactly one root.
3. Bracket each level between neighbouring scan points and solve with
   Brent's method, first in ``log d`` and then in ``d`` itself, so that the
   offset is found to a few ulps.

Levels above ``Delta alpha(2.2e-308)`` would need ``|dtheta|`` below the
smallest normal double; they are counted, not solved.

Scratch space: the per-body search (:func:`search_body_with`) allocates
nothing; it works in two caller-provided arrays, ``SCRATCH_FLOATS`` doubles
and ``SCRATCH_INTS`` int64 (:func:`new_scratch`).  The CPU kernels allocate
them once per chunk of bodies, the CUDA kernel (:mod:`orbits.core.cuda`)
as per-thread local arrays, so both run the same scalar code.
"""

import math

import numpy as np
from numba import njit, prange

from .elliptic import cel_dual
from .launch import parallel_kernel
from .phase import (
    BRANCH_SAM,
    BRANCH_SEPARATRIX,
    STATUS_OK,
    TWO_PI,
    body_constants,
    orbit_constants,
    spin_from_angle,
    total_from_spin,
)
from .tasks import MAX_WORKERS, take_task

SMALLEST_OFFSET = 2.2250738585072014e-308
LOG_POINTS = 64
UNIFORM_POINTS = 256
END_POINTS = 12
GRID_SIZE = LOG_POINTS + UNIFORM_POINTS + END_POINTS
_GOLDEN = 0.3819660112501051
# relative size of rounding noise in the scanned phase
_NOISE = 16.0 * 2.220446049250313e-16

# newton_branch's monotonicity probe: the phase at d = width 10**-(2**k)
# (k = 0 .. PROBE_DECADES - 1: from 1e-256 of the branch to a tenth) and
# at 0.2, 0.4, 0.6, 0.8 and 0.95 of the width, on every branch
PROBE_DECADES = 9
PROBE_POINTS = PROBE_DECADES + 5

# search_body_newton: a branch needs the bracketing search (call search_body)
NEEDS_BRACKETING = -2
INFO_SIZE = 12
(
    INFO_MIN_SAM,
    INFO_MIN_AT_SAM,
    INFO_MIN_LAM,
    INFO_MIN_AT_LAM,
    INFO_TOP_SAM,
    INFO_TOP_LAM,
    INFO_UNREACHED_SAM,
    INFO_UNREACHED_LAM,
    INFO_WIDTH_SAM,
    INFO_WIDTH_LAM,
    INFO_EVALUATIONS,
    INFO_FALLBACKS,
) = range(INFO_SIZE)

BRANCH_INFO_SIZE = 4  # minimum, where, value at the smallest offset, unreached


# params: I1, I2, I3, sign, the 7 body constants, the evaluation counter
PARAMS_SIZE = 12
_COUNTER = 11

# the float scratch of one body's search: params, branch info, then the scan
# grid, its values and the two merge buffers of branch_grid
_AT_INFO = PARAMS_SIZE
_AT_GRID = _AT_INFO + BRANCH_INFO_SIZE
_AT_VALUES = _AT_GRID + GRID_SIZE
_AT_HEAD = _AT_VALUES + GRID_SIZE
_AT_MERGED = _AT_HEAD + GRID_SIZE
SCRATCH_FLOATS = _AT_MERGED + GRID_SIZE
# the int scratch: the starts of the monotone pieces of search_branch
SCRATCH_INTS = GRID_SIZE + 2
# bodies per task of search_many (a worker takes one task at a time)
BODIES_PER_TASK = 16


@njit(cache=True, nogil=True)
def new_scratch():
    """Fresh scratch arrays for :func:`search_body_with` (CPU callers)."""
    return np.empty(SCRATCH_FLOATS), np.empty(SCRATCH_INTS, dtype=np.int64)


@njit(cache=True, nogil=True)
def _sorted_index(values, x, right):
    """``np.searchsorted(values, x, side="right" if right else "left")`` for
    ascending ``values``, without NumPy (device code has none)."""
    lo = 0
    hi = values.shape[0]
    if x != x:  # NaN sorts last, as in NumPy
        return hi
    while lo < hi:
        mid = (lo + hi) // 2
        if values[mid] < x or (right and values[mid] == x):
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(cache=True, nogil=True)
def phase_of_offset(d, params):
    """Total phase at ``dtheta = params[3] * d`` (phi = 0).

    ``params = (I1, I2, I3, sign, *body_constants(I1, I2, I3, 0), count)``;
    ``count`` (when present) is incremented: kernel evaluations of a search.
    """
    if params.shape[0] > _COUNTER:
        params[_COUNTER] += 1.0
    constants = (params[4], params[5], params[6], params[7], params[8], params[9], params[10])
    code, _, _, _, w1, w2, w3, scale, offset, closing = spin_from_angle(
        constants, params[3] * d, True
    )
    if code != STATUS_OK:
        return np.nan
    return total_from_spin(params[0], params[1], params[2], w1, w2, w3, scale, offset, closing)


KIND_PHASE = 0
KIND_SYNTHETIC = 1


@njit(cache=True, nogil=True)
def synthetic_profile(d, params):
    """A non-monotone stand-in for the phase, to test the search.

    ``A log(w/d) + B + C sin(k pi d / w) - D exp(-((w - d)/s)^2)`` with
    ``params = (A, B, C, k, D, s, w)``: it diverges at the separatrix like
    the phase, oscillates across the branch and dips next to the far end.
    """
    a, b, c, k, depth, spread, width = (
        params[0],
        params[1],
        params[2],
        params[3],
        params[4],
        params[5],
        params[6],
    )
    return (
        a * math.log(width / d)
        + b
        + c * math.sin(k * math.pi * d / width)
        - depth * math.exp(-(((width - d) / spread) ** 2))
    )


@njit(cache=True, nogil=True)
def _evaluate(kind, d, params):
    if kind == KIND_PHASE:
        return phase_of_offset(d, params)
    return synthetic_profile(d, params)


@njit(cache=True, nogil=True)
def _merge_two(a, b, out):
    i = 0
    j = 0
    for k in range(a.size + b.size):
        if j >= b.size or (i < a.size and a[i] <= b[j]):
            out[k] = a[i]
            i += 1
        else:
            out[k] = b[j]
            j += 1


@njit(cache=True, nogil=True)
def _merge_runs(values, first_end, second_end, head, merged):
    """``merged[:values.size]``: ``values`` sorted, given it is three ascending
    runs split at the two ends (``head`` holds ``second_end`` values)."""
    _merge_two(values[:first_end], values[first_end:second_end], head[:second_end])
    _merge_two(head[:second_end], values[second_end:], merged[: values.size])
    return merged


@njit(cache=True, nogil=True)
def branch_grid(width, out, head, merged):
    """Scan points ``d`` in (0, width], ascending; returns how many.

    ``out``, ``head`` and ``merged`` hold ``GRID_SIZE`` values each (the
    last two are scratch).
    """
    count = 0
    ratio = math.log(width / SMALLEST_OFFSET)
    for k in range(LOG_POINTS):
        out[count] = SMALLEST_OFFSET * math.exp(ratio * k / LOG_POINTS)
        count += 1
    for k in range(1, UNIFORM_POINTS + 1):
        out[count] = width * k / UNIFORM_POINTS
        count += 1
    for k in range(1, END_POINTS + 1):
        out[count] = width * (1.0 - 10.0 ** (-0.5 - 0.75 * k))
        count += 1
    # three ascending runs: merge them (the same order as np.sort, whose
    # generic quicksort cost more compile time than the whole scan)
    grid = _merge_runs(out[:count], LOG_POINTS, LOG_POINTS + UNIFORM_POINTS, head, merged)
    unique = 0
    for k in range(count):
        if k == 0 or grid[k] > grid[k - 1]:
            out[unique] = grid[k]
            unique += 1
    return unique


@njit(cache=True, nogil=True)
def _brent(kind, params, level, lo, hi, f_lo, f_hi, in_log):
    """Root of ``f(d) = level`` bracketed by ``[lo, hi]``.

    Brent-Dekker (inverse quadratic interpolation, secant, bisection) in
    ``x = log d`` (``in_log``) or ``x = d``.  Returns ``(best, other)``, in
    ``d``: Brent's best iterate and the other end of the final bracket
    (they coincide when the residual vanished exactly).
    """
    a, b = (math.log(lo), math.log(hi)) if in_log else (lo, hi)
    fa = f_lo - level
    fb = f_hi - level
    if fa == 0.0:
        return lo, lo
    if fb == 0.0:
        return hi, hi
    c = a
    fc = fa
    e = b - a
    step = e
    for _ in range(200):
        if (fb > 0.0) == (fc > 0.0):
            c = a
            fc = fa
            e = b - a
            step = e
        if abs(fc) < abs(fb):
            a, b, c = b, c, b
            fa, fb, fc = fb, fc, fb
        tol = 2.0 * 2.220446049250313e-16 * abs(b)
        half = 0.5 * (c - b)
        if abs(half) <= tol or fb == 0.0:
            break
        if abs(e) >= tol and abs(fa) > abs(fb):
            s = fb / fa
            if a == c:
                p = 2.0 * half * s
                q = 1.0 - s
            else:
                q = fa / fc
                r = fb / fc
                p = s * (2.0 * half * q * (q - r) - (b - a) * (r - 1.0))
                q = (q - 1.0) * (r - 1.0) * (s - 1.0)
            if p > 0.0:
                q = -q
            p = abs(p)
            if 2.0 * p < min(3.0 * half * q - abs(tol * q), abs(e * q)):
                e = step
                step = p / q
            else:
                step = half
                e = step
        else:
            step = half
            e = step
        a = b
        fa = fb
        b += step if abs(step) > tol else math.copysign(tol, half)
        fb = _evaluate(kind, math.exp(b) if in_log else b, params) - level
    if fb == 0.0:
        c = b
    if in_log:
        return math.exp(b), math.exp(c)
    return b, c


@njit(cache=True, nogil=True)
def solve_level(kind, params, level, lo, hi, f_lo, f_hi):
    """The ``d`` in ``[lo, hi]`` where ``f(d) = level`` (``f`` monotone there).

    Brent in ``log d`` to a narrow bracket, then Brent in ``d`` to a few
    ulps of ``d`` (the log stage alone leaves ~|log d| ulps).
    """
    if hi > 4.0 * lo:
        best, other = _brent(kind, params, level, lo, hi, f_lo, f_hi, True)
        if best == other:
            return best
        lo2, hi2 = min(best, other), max(best, other)
        f_lo2 = _evaluate(kind, lo2, params)
        f_hi2 = _evaluate(kind, hi2, params)
        if (f_lo2 - level > 0.0) != (f_hi2 - level > 0.0):
            lo, hi, f_lo, f_hi = lo2, hi2, f_lo2, f_hi2
    best, other = _brent(kind, params, level, lo, hi, f_lo, f_hi, False)
    return best


@njit(cache=True, nogil=True)
def _extremum(kind, params, lo, hi, want_min):
    """Golden-section search for the extremum of ``f`` on ``[lo, hi]``."""
    s = 1.0 if want_min else -1.0
    a = lo
    b = hi
    x1 = a + _GOLDEN * (b - a)
    x2 = b - _GOLDEN * (b - a)
    f1 = s * _evaluate(kind, x1, params)
    f2 = s * _evaluate(kind, x2, params)
    for _ in range(200):
        if b - a <= 1e-12 * b:
            break
        if f1 < f2:
            b = x2
            x2 = x1
            f2 = f1
            x1 = a + _GOLDEN * (b - a)
            f1 = s * _evaluate(kind, x1, params)
        else:
            a = x1
            x1 = x2
            f1 = f2
            x2 = b - _GOLDEN * (b - a)
            f2 = s * _evaluate(kind, x2, params)
    if f1 < f2:
        return x1, s * f1
    return x2, s * f2


@njit(cache=True, nogil=True)
def _bracket(values, start, stop, level):
    """Index k with ``level`` between ``values[k]`` and ``values[k+1]``.

    ``values[start:stop+1]`` is monotone and brackets ``level``.
    """
    increasing = values[stop] > values[start]
    lo = start
    hi = stop
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if (values[mid] < level) == increasing:
            lo = mid
        else:
            hi = mid
    return lo


@njit(cache=True, nogil=True)
def search_branch(kind, params, width, levels, root_level, root_offset, found, branch_info):
    """:func:`search_branch_with` with scratch space of its own."""
    floats, ints = new_scratch()
    return search_branch_with(
        kind, params, width, levels, root_level, root_offset, found, branch_info, floats, ints
    )


@njit(cache=True, nogil=True)
def search_branch_with(
    kind, params, width, levels, root_level, root_offset, found, branch_info, floats, ints
):
    """Every ``d`` in (0, width) with ``f(d)`` equal to a level.

    ``f`` is :func:`phase_of_offset` (``kind = KIND_PHASE``), the phase at
    distance ``d`` from the separatrix, or :func:`synthetic_profile`; it
    may rise and fall any number of times (resolved by the scan).  Roots
    are appended to ``root_level`` / ``root_offset`` from index ``found``
    (``d``, not signed).  ``branch_info`` receives the minimum of ``f`` and
    where it lies, ``f`` at the smallest offset and how many levels exceed
    that.  Returns the new count, or -1 if the arrays are too short.
    ``floats`` and ``ints`` are the scratch of :func:`search_body_with`
    (its ``params`` and branch info slots are not touched here).
    """
    grid = floats[_AT_GRID:_AT_VALUES]
    values = floats[_AT_VALUES:_AT_HEAD]
    piece_lo = ints
    capacity = root_offset.shape[0]
    count = branch_grid(
        width, grid, floats[_AT_HEAD:_AT_MERGED], floats[_AT_MERGED:SCRATCH_FLOATS]
    )
    for k in range(count):
        values[k] = _evaluate(kind, grid[k], params)
    # the phase at the smallest representable offset bounds the levels
    # whose roots a double can hold
    top = values[0]
    unreached = 0
    for j in range(levels.shape[0]):
        if levels[j] > top:
            unreached += 1
    # monotone pieces: split at interior extrema of the scan
    best_value = values[count - 1]
    best_at = grid[count - 1]
    pieces = 0
    piece_lo[pieces] = 0
    pieces += 1
    for k in range(1, count - 1):
        left = values[k] - values[k - 1]
        right = values[k + 1] - values[k]
        # near the far end the phase is flat to rounding; differences
        # within a few ulps are noise, not extrema
        noise = _NOISE * abs(values[k])
        if abs(left) <= noise or abs(right) <= noise:
            continue
        if left * right < 0.0:
            d_ext, f_ext = _extremum(kind, params, grid[k - 1], grid[k + 1], right > 0.0)
            # the refined extremum replaces the scan point, keeping the
            # scan ordered and each piece monotone
            if grid[k - 1] < d_ext < grid[k + 1] and (
                (right > 0.0 and f_ext <= values[k]) or (right < 0.0 and f_ext >= values[k])
            ):
                grid[k] = d_ext
                values[k] = f_ext
            piece_lo[pieces] = k
            pieces += 1
    piece_lo[pieces] = count - 1
    for k in range(count):
        if values[k] < best_value - _NOISE * abs(best_value):
            best_value = values[k]
            best_at = grid[k]
    branch_info[0] = best_value
    branch_info[1] = best_at
    branch_info[2] = top
    branch_info[3] = unreached
    for p in range(pieces):
        start = piece_lo[p]
        stop = piece_lo[p + 1]
        low = min(values[start], values[stop])
        high = max(values[start], values[stop])
        j = _sorted_index(levels, low, True)
        while j < levels.shape[0] and levels[j] < high:
            if found >= capacity:
                return -1
            k = _bracket(values, start, stop, levels[j])
            root_level[found] = j
            root_offset[found] = solve_level(
                kind, params, levels[j], grid[k], grid[k + 1], values[k], values[k + 1]
            )
            found += 1
            j += 1
    return found


@njit(cache=True, nogil=True)
def phase_slope_of_offset(d, params):
    """Total phase at ``dtheta = params[3] * d`` and its slope ``d Delta alpha / d ln d``.

    The value is bit-for-bit :func:`phase_of_offset`'s.  The slope is the
    chain rule through the set-up (``dtheta/d ln d = dtheta``) and
    :func:`orbits.core.elliptic.cel_dual` for the elliptic part, i.e. the
    analytic ``dK/dm``, ``dPi/dm`` and ``dPi/dn`` in the combination of
    eqn:GeometricPhase.  Returns ``(nan, nan)`` off the domain.
    """
    params[_COUNTER] += 1.0
    i1 = params[0]
    i2 = params[1]
    i3 = params[2]
    cphi = params[4]
    sphi = params[5]
    root_a = params[8]
    root_b = params[9]
    constants = (cphi, sphi, params[6], params[7], root_a, root_b, params[10])
    code, theta, dtheta, _, w1, w2, w3, scale, offset, closing = spin_from_angle(
        constants, params[3] * d, True
    )
    if code != STATUS_OK:
        return np.nan, np.nan
    branch, two_e, m_sq, gap_m1, gap_3m, kc, q, p, b = orbit_constants(
        i1, i2, i3, w1, w2, w3, scale, offset, closing
    )
    if branch == BRANCH_SEPARATRIX:
        return np.inf, np.nan
    d21 = i2 - i1
    d31 = i3 - i1
    d32 = i3 - i2
    # derivatives along x = ln d: d theta / dx = dtheta
    st_dot = w3 * dtheta
    w1_dot = cphi * st_dot
    w2_dot = sphi * st_dot
    w3_dot = -math.sin(theta) * dtheta
    s1_dot = 2.0 * w1 * w1_dot
    s2_dot = 2.0 * w2 * w2_dot
    s3_dot = 2.0 * w3 * w3_dot
    two_e_dot = i1 * s1_dot + i2 * s2_dot + i3 * s3_dot
    m_sq_dot = i1 * i1 * s1_dot + i2 * i2 * s2_dot + i3 * i3 * s3_dot
    closing_dot = st_dot * root_b + w3_dot * root_a
    if branch == BRANCH_SAM:
        q_rate = (i2 * d21 * s2_dot + i3 * d31 * s3_dot) / gap_m1
        p_dot = 0.0
        b_dot = 0.0
        shift = TWO_PI
    else:
        q_rate = (i1 * d31 * s1_dot + i2 * d32 * s2_dot) / gap_3m
        p_dot = p * (m_sq_dot / m_sq - q_rate)
        b_dot = b * (two_e_dot / two_e - q_rate)
        shift = 0.0
    # kc^2 = d31 scale sin(dtheta) closing / q (orbit_constants), in logs
    kc_dot = 0.5 * kc * (math.cos(dtheta) * dtheta / offset + closing_dot / closing - q_rate)
    integral, integral_dot = cel_dual(kc, kc_dot, p, p_dot, 1.0, 0.0, b, b_dot)
    factor = 4.0 * math.sqrt(m_sq * i2 * i3 / (i1 * q))
    factor_dot = 0.5 * factor * (m_sq_dot / m_sq - q_rate)
    return (factor * integral - shift, factor_dot * integral + factor * integral_dot)


@njit(cache=True, nogil=True)
def separatrix_expansion(params):
    """``a, b`` of ``Delta alpha(d) = a ln(1/d) + b + O(d ln d)`` on one branch.

    Near the separatrix ``kc^2 = kappa d (1 + O(d))`` with ``kappa =
    (I3-I1) sqrt(A + B_phi) c / q`` (:func:`orbits.core.phase.orbit_constants`,
    ``c`` the closing factor at ``theta_c``), and Bulirsch's integral has
    ``cel(kc, p, 1, b) = (b/p) ln(4/kc) + (1 - b/p) J(p) + O(kc^2 ln kc)``
    with ``J(p) = int_0^1 du / (1 + (p-1) u^2)`` (the divergent part comes
    from ``phi -> pi/2``, where the integrand is ``b / (p sqrt(cos^2 + kc^2))``).
    With the prefactor ``F = 4 M / (I1 D)`` at ``theta_c``: ``a = F b / (2p)``
    (``b/p = I1/I2`` on both branches) and ``b = F ((b/p)(ln 4 - ln(kappa)/2)
    + (1 - b/p) J(p)) - 2 pi [SAM]``.
    """
    i1 = params[0]
    i2 = params[1]
    i3 = params[2]
    cphi = params[4]
    sphi = params[5]
    theta_c = params[6]
    co_theta_c = params[7]
    root_a = params[8]
    root_b = params[9]
    scale = params[10]
    st = math.sin(theta_c)
    w3 = math.sin(co_theta_c) if co_theta_c < theta_c else math.cos(theta_c)
    w1 = st * cphi
    w2 = st * sphi
    closing = st * root_b + w3 * root_a
    d21 = i2 - i1
    d31 = i3 - i1
    d32 = i3 - i2
    s1 = w1 * w1
    s2 = w2 * w2
    s3 = w3 * w3
    two_e = i1 * s1 + i2 * s2 + i3 * s3
    m_sq = i1 * i1 * s1 + i2 * i2 * s2 + i3 * i3 * s3
    if params[3] < 0.0:  # SAM
        q = d32 * (i2 * d21 * s2 + i3 * d31 * s3)
        p = i2 * d31 / (i1 * d32)
        b = d31 / d32
        shift = TWO_PI
    else:
        gap_3m = i1 * d31 * s1 + i2 * d32 * s2
        q = d21 * gap_3m
        p = d31 * m_sq / (i1 * gap_3m)
        b = two_e * d31 / gap_3m
        shift = 0.0
    kappa = d31 * scale * closing / q
    if p > 1.0:
        r = math.sqrt(p - 1.0)
        j = math.atan(r) / r
    elif p < 1.0:
        r = math.sqrt(1.0 - p)
        j = math.atanh(r) / r
    else:
        j = 1.0
    factor = 4.0 * math.sqrt(m_sq * i2 * i3 / (i1 * q))
    ratio = b / p
    slope = 0.5 * factor * ratio
    return slope, factor * (
        ratio * (math.log(4.0) - 0.5 * math.log(kappa)) + (1.0 - ratio) * j
    ) - shift


@njit(cache=True, nogil=True)
def probe_offset(k, width):
    """The ``k``-th point of the monotonicity probe, ascending in ``k``
    (``0 <= k < PROBE_POINTS``); see :func:`monotone_at_probes`."""
    if k < PROBE_DECADES:
        return width * math.pow(10.0, -math.pow(2.0, PROBE_DECADES - 1 - k))
    j = k - PROBE_DECADES  # no tuple indexed at run time: the same code on CUDA
    return width * (0.95 if j == 4 else 0.2 * (j + 1))


@njit(cache=True, nogil=True)
def monotone_at_probes(kind, params, width, top, f_end):
    """Whether ``f`` decreases (within rounding) through the probe points.

    ``f`` is :func:`phase_of_offset` (``kind = KIND_PHASE``) or
    :func:`synthetic_profile`; ``top`` and ``f_end`` are its values at
    ``SMALLEST_OFFSET`` and at ``width``.  The probe evaluates ``f`` at
    :data:`PROBE_POINTS` fixed offsets spread over the whole branch (every
    branch, whatever levels are asked for), so that the search's
    assumption -- one root per level, the minimum at the end -- is tested
    on every body; a rise beyond rounding sends the branch to the
    bracketing scan, which finds every root and the true minimum.
    """
    previous = top
    for k in range(PROBE_POINTS):
        d = probe_offset(k, width)
        if not (d > SMALLEST_OFFSET and d < width):
            continue  # a branch narrower than 1e-52 rad: the decades below it
        value = _evaluate(kind, d, params)
        if not (value <= previous + _NOISE * abs(previous)):
            return False
        previous = value
    return f_end <= previous + _NOISE * abs(previous)


# Newton in ln d: stop once a step is below this (the next would be ~its
# square); give up (and fall back to the bracketing search) after _NEWTON_MAX
_STEP_DONE = 1.0e-9
_NEWTON_MAX = 60
_EPS = 2.220446049250313e-16
# a slope this far above zero (relative to the phase) is taken as real
_SLOPE_NOISE = 64.0 * _EPS


@njit(cache=True, nogil=True)
def newton_branch(params, width, levels, root_level, root_offset, found, branch_info):
    """Roots of one branch by expansion + safeguarded Newton in ``ln d``.

    Assumes ``Delta alpha`` decreases in ``d`` on ``(0, width]`` and checks it
    at every point it evaluates (the slope must be negative, beyond
    rounding), and first at fixed points over the whole branch
    (:func:`monotone_at_probes`), so that a branch with no level in its
    range is tested too.  Levels in ``(Delta alpha(width), Delta alpha(2.2e-308))``
    each have one root, placed by the separatrix expansion
    (:func:`separatrix_expansion`, ``ln d = (b - L)/a``), then Newton steps
    ``d <- d exp(-(f - L)/f')`` with the slope ``f'`` of
    :func:`phase_slope_of_offset`, kept inside the bracket that the
    evaluated points give (bisection in ``ln d`` otherwise).  Each root
    depends only on its own level, not on the others asked for (the same
    spin whether a level is solved alone or in a catalog).  Stepping ``d``
    by ``exp(step)`` rather than ``ln d`` keeps ``d``'s full relative
    precision down to 1e-308.

    Returns the new count, ``-1`` if the output is too short, or ``-2`` when
    the assumption fails or Newton does not converge: the caller then
    uses the bracketing search for this branch.
    """
    capacity = root_offset.shape[0]
    f_end = phase_of_offset(width, params)
    top = phase_of_offset(SMALLEST_OFFSET, params)
    if not (math.isfinite(f_end) and math.isfinite(top)) or not (top > f_end):
        return -2
    if not monotone_at_probes(KIND_PHASE, params, width, top, f_end):
        return -2
    unreached = 0
    for j in range(levels.shape[0]):
        if levels[j] > top:
            unreached += 1
    branch_info[0] = f_end
    branch_info[1] = width
    branch_info[2] = top
    branch_info[3] = unreached
    slope, intercept = separatrix_expansion(params)
    if not (slope > 0.0):
        return -2
    log_width = math.log(width)
    j = _sorted_index(levels, top, False) - 1
    first = found
    while j >= 0 and levels[j] > f_end:
        level = levels[j]
        if found >= capacity:
            return -1
        x_guess = (intercept - level) / slope
        lo = SMALLEST_OFFSET
        hi = width
        r_lo = top - level  # > 0
        r_hi = f_end - level  # < 0
        x_lo = math.log(lo)
        x_hi = log_width
        if not (x_lo < x_guess < x_hi):
            x_guess = 0.5 * (x_lo + x_hi)
        d = math.exp(x_guess)
        last_step = math.inf
        done = False
        for _ in range(_NEWTON_MAX):
            value, rate = phase_slope_of_offset(d, params)
            if not (rate < _SLOPE_NOISE * abs(value)):
                return -2
            residual = value - level
            if residual == 0.0:
                done = True
                break
            if residual > 0.0:
                lo = d
                r_lo = residual
            else:
                hi = d
                r_hi = residual
            step = -residual / rate
            if rate < 0.0 and abs(step) <= _STEP_DONE:
                d = d * math.exp(step)
                d = min(max(d, lo), hi)
                done = True
                break
            x = math.log(d)
            x_lo = math.log(lo)
            x_hi = math.log(hi)
            if rate < 0.0 and x_lo < x + step < x_hi and abs(step) < 0.5 * last_step:
                d = d * math.exp(step)
                last_step = abs(step)
            else:
                # Newton left the bracket or did not halve its step (it can
                # cycle where the phase flattens towards the far end): a
                # false-position step in ln d, kept off the bracket's ends
                t = min(max(r_hi / (r_hi - r_lo), 0.02), 0.98)
                x_new = x_hi - t * (x_hi - x_lo)
                last_step = abs(x_new - x)
                d = math.exp(x_new)
            if hi <= lo * (1.0 + 4.0 * _EPS):
                done = True
                break
        if not done:
            return -2
        root_level[found] = j
        root_offset[found] = d
        found += 1
        j -= 1
    # ascending levels within the branch, as the bracketing search stores them
    count = found - first
    for k in range(count // 2):
        a = first + k
        b = found - 1 - k
        root_level[a], root_level[b] = root_level[b], root_level[a]
        root_offset[a], root_offset[b] = root_offset[b], root_offset[a]
    return found


@njit(cache=True, nogil=True)
def _body_params(i1, i2, i3, params):
    """The body's constants (phi = 0); fills ``params`` (PARAMS_SIZE), the
    parameter vector of the phase, with the counter at 0."""
    constants = body_constants(i1, i2, i3, 0.0)
    for k in range(PARAMS_SIZE):
        params[k] = 0.0
    params[0] = i1
    params[1] = i2
    params[2] = i3
    for k in range(7):
        params[4 + k] = constants[k]
    return constants


@njit(cache=True, nogil=True)
def search_body(i1, i2, i3, levels, root_branch, root_level, root_offset, info):
    """:func:`search_body_with` with scratch space of its own."""
    floats, ints = new_scratch()
    return search_body_with(
        i1, i2, i3, levels, root_branch, root_level, root_offset, info, floats, ints
    )


@njit(cache=True, nogil=True)
def search_body_with(i1, i2, i3, levels, root_branch, root_level, root_offset, info, floats, ints):
    """All roots of ``Delta alpha = levels[j]`` on both branches of one body.

    Parameters
    ----------
    i1, i2, i3 : float
        Principal moments, ascending.
    levels : ndarray
        Target phases, ascending (``2 pi p / q``).
    root_branch, root_level, root_offset : ndarray
        Receive, per root, the branch (+1 SAM, -1 LAM), the index into
        ``levels`` and ``dtheta``.
    info : ndarray (INFO_SIZE,)
        Per branch: the minimum of the phase and its ``dtheta``, the phase
        at ``|dtheta| = 2.2e-308``, the number of levels above it (roots
        that would lie closer to the separatrix than a double can say),
        and the branch width; then the number of phase evaluations and of
        branches that fell back to the bracketing search.
    floats, ints : ndarray
        Scratch space, ``SCRATCH_FLOATS`` float64 and ``SCRATCH_INTS`` int64
        (:func:`new_scratch`); nothing is allocated here, so the same code
        runs in a CUDA thread (:mod:`orbits.core.cuda`).

    Returns
    -------
    int
        Number of roots found, or ``-1`` if the output arrays are too short.

    Notes
    -----
    Each branch is solved by :func:`newton_branch` (separatrix expansion,
    then Newton in ``ln d`` with the analytic slope); where its
    monotonicity check fails, by the scan-and-bracket
    :func:`search_branch` (see :func:`search_body_bracketing`).
    """
    params = floats[:PARAMS_SIZE]
    branch_info = floats[_AT_INFO:_AT_GRID]
    constants = _body_params(i1, i2, i3, params)
    found = np.int64(0)  # not a literal: one compiled signature of the callees
    fallbacks = 0
    for branch_index in range(2):
        params[3] = -1.0 if branch_index == 0 else 1.0
        width = constants[2] if branch_index == 0 else constants[3]
        start = found
        found = newton_branch(params, width, levels, root_level, root_offset, found, branch_info)
        if found == -2:
            fallbacks += 1
            found = search_branch_with(
                KIND_PHASE,
                params,
                width,
                levels,
                root_level,
                root_offset,
                start,
                branch_info,
                floats,
                ints,
            )
        if found < 0:
            return -1
        _record_branch(
            branch_index, width, start, found, branch_info, root_branch, root_offset, info
        )
    info[INFO_EVALUATIONS] = params[_COUNTER]
    info[INFO_FALLBACKS] = fallbacks
    return found


@njit(cache=True, nogil=True)
def search_body_newton(i1, i2, i3, levels, root_branch, root_level, root_offset, info):
    """:func:`search_body_newton_with` with scratch space of its own."""
    floats, ints = new_scratch()
    return search_body_newton_with(
        i1, i2, i3, levels, root_branch, root_level, root_offset, info, floats
    )


@njit(cache=True, nogil=True)
def search_body_newton_with(
    i1, i2, i3, levels, root_branch, root_level, root_offset, info, floats
):
    """:func:`search_body` without its fallback: ``NEEDS_BRACKETING`` instead.

    Returns the same as :func:`search_body` whenever no branch needs the
    bracketing search, which is then never compiled: a cold first catalog
    compiles only this (the fallback is rare; call :func:`search_body`).
    """
    params = floats[:PARAMS_SIZE]
    branch_info = floats[_AT_INFO:_AT_GRID]
    constants = _body_params(i1, i2, i3, params)
    found = np.int64(0)
    for branch_index in range(2):
        params[3] = -1.0 if branch_index == 0 else 1.0
        width = constants[2] if branch_index == 0 else constants[3]
        start = found
        found = newton_branch(params, width, levels, root_level, root_offset, found, branch_info)
        if found == -2:
            return NEEDS_BRACKETING
        if found < 0:
            return -1
        _record_branch(
            branch_index, width, start, found, branch_info, root_branch, root_offset, info
        )
    info[INFO_EVALUATIONS] = params[_COUNTER]
    info[INFO_FALLBACKS] = 0
    return found


@njit(cache=True, nogil=True)
def _record_branch(branch_index, width, start, found, branch_info, root_branch, root_offset, info):
    """Signs, branch labels and the branch's ``info`` slots (roots start..found)."""
    sign = -1.0 if branch_index == 0 else 1.0
    for k in range(start, found):
        root_branch[k] = 1 if branch_index == 0 else -1
        root_offset[k] *= sign
    info[INFO_MIN_SAM + 2 * branch_index] = branch_info[0]
    info[INFO_MIN_AT_SAM + 2 * branch_index] = sign * branch_info[1]
    info[INFO_TOP_SAM + branch_index] = branch_info[2]
    info[INFO_UNREACHED_SAM + branch_index] = branch_info[3]
    info[INFO_WIDTH_SAM + branch_index] = width


@njit(cache=True, nogil=True)
def search_body_bracketing(i1, i2, i3, levels, root_branch, root_level, root_offset, info):
    """The scan-and-bracket search of both branches (the reference).

    Every branch is scanned and split into monotone pieces
    (:func:`search_branch`); kept as the reference of :func:`search_body`
    in the tests and as its fallback.  Arguments, ``info`` and the result
    as for :func:`search_body` (no branch falls back: ``info`` counts 0).
    """
    floats, ints = new_scratch()
    params = floats[:PARAMS_SIZE]
    branch_info = floats[_AT_INFO:_AT_GRID]
    constants = _body_params(i1, i2, i3, params)
    found = np.int64(0)
    for branch_index in range(2):
        params[3] = -1.0 if branch_index == 0 else 1.0
        width = constants[2] if branch_index == 0 else constants[3]
        start = found
        found = search_branch_with(
            KIND_PHASE,
            params,
            width,
            levels,
            root_level,
            root_offset,
            found,
            branch_info,
            floats,
            ints,
        )
        if found < 0:
            return -1
        _record_branch(
            branch_index, width, start, found, branch_info, root_branch, root_offset, info
        )
    info[INFO_EVALUATIONS] = params[_COUNTER]
    info[INFO_FALLBACKS] = 0
    return found


@parallel_kernel(cache=True, nogil=True)
def search_many(moments, levels, root_branch, root_level, root_offset, counts, info):
    """:func:`search_body` for every row of ``moments`` (n, 3), in parallel.

    Row ``b``'s roots go to ``root_*[b, :counts[b]]``; ``counts[b] = -1``
    when its row of the output arrays was too short.  The workers take
    tasks of ``BODIES_PER_TASK`` bodies until none is left
    (:mod:`orbits.core.tasks`: a thread slowed by other work takes fewer);
    the scratch of :func:`search_body_with` is allocated once per worker
    that gets a task.
    """
    n = moments.shape[0]
    tasks = (n + BODIES_PER_TASK - 1) // BODIES_PER_TASK
    counter = np.zeros(1, dtype=np.int64)
    for _ in prange(min(tasks, MAX_WORKERS)):
        t = take_task(counter)
        if t < tasks:  # a worker that gets no task allocates nothing
            floats, ints = new_scratch()
            while t < tasks:
                for b in range(t * BODIES_PER_TASK, min(n, (t + 1) * BODIES_PER_TASK)):
                    counts[b] = search_body_with(
                        moments[b, 0],
                        moments[b, 1],
                        moments[b, 2],
                        levels,
                        root_branch[b],
                        root_level[b],
                        root_offset[b],
                        info[b],
                        floats,
                        ints,
                    )
                t = take_task(counter)
