"""The exact motion on an evenly spaced time grid, without an R_J per point.

:func:`orbits.core.motion.state_at` costs one Jacobi evaluation (a walk up
the AGM table) and one Carlson ``R_J`` (the incomplete third-kind integral
of ``phi(t)``, eqn:fullphi) per time.  On an even grid ``u_k = u_0 + k
delta`` both have cheaper exact forms:

* ``sn, cn, dn`` at ``u_a + j delta`` from those at an anchor ``u_a`` and a
  table at ``j delta`` (``j <= BLOCK``), by the addition theorem (DLMF
  22.8.1-22.8.3).  Every point is one addition away from an exactly
  evaluated anchor, so rounding does not accumulate along the grid.
* ``P(u) = Pi(n; am u | m) = int_0^u dv / (1 - n sn^2 v)`` (the continued
  Legendre integral of :func:`orbits.core.motion.pi_of_u`) as a running
  sum of its increments over each step, each by Gauss-Legendre quadrature
  with :data:`GAUSS_ORDER` nodes, whose ``sn`` are again additions.

The quadrature is used only where it is accurate to rounding a priori.
``1 - n sn^2 v`` (``n < 0`` on both branches) vanishes at ``v = i y``
with ``sc(y | 1 - m) = 1 / sqrt(-n)`` (Jacobi's imaginary transformation
``sn(i y | m) = i sc(y | 1 - m)``, DLMF 22.6(iv)), so the integrand is
analytic in the strip ``|Im v| < y`` (:func:`pole_distance`, checked
against mpmath in the tests).  Each grid step is split into the fewest
equal substeps (at most :data:`MAX_SUBSTEPS`) no longer than ``y /
POLE_MARGIN``; the Bernstein ellipse of a substep ``h`` then reaches
``rho ~ 4 y / h >= 4 POLE_MARGIN`` and ``rho**(-2 GAUSS_ORDER)`` is below
1e-19 (Trefethen, *Approximation Theory and Approximation Practice*,
Thm. 19.3).  A coarser grid, or an uneven one, is evaluated point by point.
Each block is also checked against the exact value at the next anchor and
recomputed point by point if they differ by more than
``BLOCK_TOLERANCE eps |P|``.
"""

import math

import numpy as np
from numba import njit, prange

from .elliptic import AGM_LEVELS, ellipf_kc, jacobi_from_table
from .launch import parallel_kernel
from .motion import (
    SLOT_GEOMETRIC,
    SLOT_KC,
    SLOT_LEVELS,
    SLOT_MEANS,
    SLOT_N,
    SLOT_RATE,
    SLOT_TAU0,
    half_period_index,
    omega_space_at,
    omega_space_from_pieces,
    pi_of_u,
    rotation_from_euler,
    state_at,
    state_from_pieces,
)

# points per block: two exact evaluations per block, a table of BLOCK + 1 entries
BLOCK = 64
# Gauss-Legendre nodes per step (on [0, 1]) and the required ratio of the
# integrand's pole distance to the step; a coarser grid step is split into
# up to MAX_SUBSTEPS equal substeps.  (Measured over 300 random bodies and
# spins: the running P stays within 12 eps |P| of the exact value down to a
# ratio of 10, and departs from it at 5: 57 eps, at 3: 6900 eps.)
GAUSS_ORDER = 5
POLE_MARGIN = 20.0
MAX_SUBSTEPS = 4
# fewer points than this: the table costs more than it saves
MIN_POINTS = 2 * BLOCK
# largest accepted mismatch at a block's end, in units of eps * |P|
BLOCK_TOLERANCE = 64.0

_nodes, _weights = np.polynomial.legendre.leggauss(GAUSS_ORDER)
GAUSS_NODES = 0.5 * (_nodes + 1.0)
GAUSS_WEIGHTS = 0.5 * _weights
EPS = np.finfo(np.float64).eps

# rows of the per-block pieces array filled by :func:`block_pieces`
PIECE_PI, PIECE_SN, PIECE_CN, PIECE_DN, PIECE_J = range(5)
PIECES = 5


@njit(cache=True, nogil=True)
def even_step(times):
    """The step ``h`` if ``times`` is evenly spaced to rounding, else 0.

    Accepts ``t_k = t_0 + k h`` within 4 ulps of the largest ``|t|``
    (``numpy.linspace`` and ``arange`` grids); the grid may decrease.
    """
    n = times.shape[0]
    if n < 2:
        return 0.0
    first = times[0]
    step = (times[n - 1] - first) / (n - 1)
    if step == 0.0 or not math.isfinite(step):
        return 0.0
    tolerance = 4.0 * EPS * max(abs(first), abs(times[n - 1]))
    for k in range(n):
        if abs(times[k] - (first + k * step)) > tolerance:
            return 0.0
    return step


@njit(cache=True, nogil=True)
def pole_distance(orbit):
    """``y``: the integrand of ``P`` is analytic for ``|Im v| < y``.

    ``1 - n sn^2(i y | m) = 1 + n sc^2(y | 1 - m)`` (Jacobi's imaginary
    transformation, DLMF 22.6(iv)) first vanishes at
    ``am(y | 1 - m) = atan(1 / sqrt(-n))``; the complementary modulus of
    ``1 - m`` is ``k = sqrt(m)``.  ``n = 0`` (a spin exactly along I1): the
    integrand is 1 and ``K(1 - m)`` is returned as a finite cap.  (``n > 0``
    cannot occur; it would give NaN and the direct path.)
    """
    n = orbit[SLOT_N]
    kc = orbit[SLOT_KC]
    k = math.sqrt((1.0 - kc) * (1.0 + kc))
    angle = 0.5 * math.pi if n == 0.0 else math.atan(1.0 / math.sqrt(-n))
    return ellipf_kc(angle, k)


@njit(cache=True, nogil=True)
def _add(s, c, d, s2, c2, d2, m):
    """``sn, cn, dn`` of ``u + v`` from those of ``u`` and ``v`` (DLMF 22.8).

    The common denominator ``1 - m sn^2 u sn^2 v`` is formed as
    ``cn^2 u + sn^2 u dn^2 v``: near the separatrix both ``sn`` are close
    to 1 and the subtraction would lose digits (measured: 5e-12 relative
    in ``sn`` at 1 - m = 3e-19); the sum of squares does not.
    """
    inv = 1.0 / (c * c + s * s * d2 * d2)
    return (
        (s * c2 * d2 + s2 * c * d) * inv,
        (c * c2 - s * s2 * d * d2) * inv,
        (d * d2 - m * s * s2 * c * c2) * inv,
    )


@njit(cache=True, nogil=True)
def grid_tables(orbit, delta, substeps):
    """``sn, cn, dn`` at ``j delta`` (``j <= BLOCK``) and at the quadrature nodes.

    Returns ``(offsets, nodes, weights)``: shapes ``(3, BLOCK + 1)``, ``(3,
    substeps GAUSS_ORDER)`` and ``(substeps GAUSS_ORDER,)``; the nodes are
    those of ``GAUSS_ORDER``-point Gauss-Legendre on each of ``substeps``
    equal parts of ``[0, delta]``, the weights include ``delta``.  Every
    value is evaluated exactly (:func:`jacobi_from_table`).
    """
    levels = int(orbit[SLOT_LEVELS])
    means = orbit[SLOT_MEANS : SLOT_MEANS + AGM_LEVELS]
    geometric = orbit[SLOT_GEOMETRIC : SLOT_GEOMETRIC + AGM_LEVELS]
    offsets = np.empty((3, BLOCK + 1))
    for j in range(BLOCK + 1):
        s, c, d, _, _ = jacobi_from_table(j * delta, levels, means, geometric)
        offsets[0, j] = s
        offsets[1, j] = c
        offsets[2, j] = d
    count = substeps * GAUSS_ORDER
    nodes = np.empty((3, count))
    weights = np.empty(count)
    part = delta / substeps
    for i in range(substeps):
        for g in range(GAUSS_ORDER):
            k = i * GAUSS_ORDER + g
            s, c, d, _, _ = jacobi_from_table(
                (i + GAUSS_NODES[g]) * part, levels, means, geometric
            )
            nodes[0, k] = s
            nodes[1, k] = c
            nodes[2, k] = d
            weights[k] = GAUSS_WEIGHTS[g] * part
    return offsets, nodes, weights


@njit(cache=True, nogil=True)
def _step_integral(s, c, d, nodes, weights, n):
    """``P(u + delta) - P(u)`` by Gauss-Legendre from ``sn, cn, dn`` of ``u``."""
    total = 0.0
    for i in range(weights.shape[0]):
        s2 = nodes[0, i]
        c2 = nodes[1, i]
        d2 = nodes[2, i]
        # sn(u + v_i) = num / den (den as in _add); with n < 0,
        # 1 / (1 - n sn^2) = den^2 / (den^2 - n num^2) is a ratio of sums
        num = s * c2 * d2 + s2 * c * d
        den = c * c + s * s * d2 * d2
        den2 = den * den
        total += weights[i] * den2 / (den2 - n * num * num)
    return total


@njit(cache=True, nogil=True)
def _exact_piece(orbit, u, pieces, k):
    value, sn, cn, dn, j = pi_of_u(orbit, u)
    pieces[PIECE_PI, k] = value
    pieces[PIECE_SN, k] = sn
    pieces[PIECE_CN, k] = cn
    pieces[PIECE_DN, k] = dn
    pieces[PIECE_J, k] = j
    return value


@njit(cache=True, nogil=True)
def block_pieces(orbit, times, delta, offsets, nodes, weights, b, pieces):
    """Fill ``pieces[:, :hi - lo]`` for the points ``lo = b BLOCK`` to ``hi - 1``.

    The anchor ``lo`` is evaluated exactly, the other points from it.
    Returns True if the running ``P`` and the added ``sn, cn, dn`` matched
    the exact values at the next anchor (or the last point), False if the
    block failed that check and was recomputed point by point.  (Each block
    evaluates the next anchor itself: blocks run in parallel without a
    second parallel region.)
    """
    n_total = times.shape[0]
    lo = b * BLOCK
    hi = min(n_total, lo + BLOCK)
    tau0 = orbit[SLOT_TAU0]
    rate = orbit[SLOT_RATE]
    kc = orbit[SLOT_KC]
    m = (1.0 - kc) * (1.0 + kc)
    n = orbit[SLOT_N]
    u_anchor = tau0 + rate * times[lo]
    p = _exact_piece(orbit, u_anchor, pieces, 0)
    sa = pieces[PIECE_SN, 0]
    ca = pieces[PIECE_CN, 0]
    da = pieces[PIECE_DN, 0]
    s, c, d = sa, ca, da
    # the last increment runs on to the next anchor (or to the last point)
    end = hi if hi < n_total else hi - 1
    for k in range(lo + 1, end + 1):
        p += _step_integral(s, c, d, nodes, weights, n)
        j = k - lo
        s, c, d = _add(sa, ca, da, offsets[0, j], offsets[1, j], offsets[2, j], m)
        if k < hi:
            pieces[PIECE_PI, j] = p
            pieces[PIECE_SN, j] = s
            pieces[PIECE_CN, j] = c
            pieces[PIECE_DN, j] = d
            pieces[PIECE_J, j] = half_period_index(orbit, u_anchor + j * delta)
    if end == lo:
        return True
    u_end = tau0 + rate * times[end]
    exact, s_end, c_end, d_end, _ = pi_of_u(orbit, u_end)
    # the two u_end differ by rounding: a few ulps of u times |d/du| <= 1
    slack = BLOCK_TOLERANCE * EPS * (1.0 + abs(u_end))
    if (
        abs(p - exact) <= BLOCK_TOLERANCE * EPS * max(abs(exact), 1.0)
        and abs(s - s_end) <= slack
        and abs(c - c_end) <= slack
        and abs(d - d_end) <= slack
    ):
        return True
    for k in range(lo + 1, hi):
        _exact_piece(orbit, tau0 + rate * times[k], pieces, k - lo)
    return False


@njit(cache=True, nogil=True)
def grid_plan(orbit, times):
    """``(delta, substeps)`` if the block path applies to ``times``, else ``(0, 0)``.

    ``delta`` is the grid step in ``u``; ``substeps`` the parts each step's
    quadrature is split into so that each part is at most ``y /
    POLE_MARGIN`` (:func:`pole_distance`).
    """
    if times.shape[0] < MIN_POINTS:
        return 0.0, 0
    step = even_step(times)
    if step == 0.0:
        return 0.0, 0
    delta = orbit[SLOT_RATE] * step
    parts = abs(delta) * POLE_MARGIN / pole_distance(orbit)
    if not parts <= MAX_SUBSTEPS:
        return 0.0, 0
    return delta, max(1, int(math.ceil(parts)))


@njit(cache=True, nogil=True)
def _tables(orbit, times, fast):
    """``(delta, offsets, nodes, weights)`` of the block path; ``delta`` 0: none."""
    delta, substeps = grid_plan(orbit, times) if fast else (0.0, 0)
    if substeps == 0:
        return 0.0, np.empty((3, 0)), np.empty((3, 0)), np.empty(0)
    offsets, nodes, weights = grid_tables(orbit, delta, substeps)
    return delta, offsets, nodes, weights


@njit(cache=True, nogil=True)
def _run_block(orbit, times, tables, b, pieces, redone):
    """:func:`block_pieces` for block ``b``; marks ``redone[b]``; returns its time range."""
    delta, offsets, nodes, weights = tables
    if not block_pieces(orbit, times, delta, offsets, nodes, weights, b, pieces):
        redone[b] = 1
    lo = b * BLOCK
    return lo, min(times.shape[0], lo + BLOCK)


@njit(cache=True, nogil=True)
def _fill_state(k, w1, w2, w3, phi, theta, psi, omega, euler, rotation, omega_space):
    omega[k, 0] = w1
    omega[k, 1] = w2
    omega[k, 2] = w3
    euler[k, 0] = phi
    euler[k, 1] = theta
    euler[k, 2] = psi
    r = rotation[k]
    rotation_from_euler(phi, theta, psi, r)
    for row in range(3):
        omega_space[k, row] = r[row, 0] * w1 + r[row, 1] * w2 + r[row, 2] * w3


@parallel_kernel(cache=True, nogil=True)
def motion_on_grid(orbit, times, fast, omega, euler, rotation, omega_space):
    """Evaluate the motion at every time, in parallel.

    Fills ``omega`` (n, 3) body frame, ``euler`` (n, 3) as (phi, theta, psi),
    ``rotation`` (n, 3, 3) body -> space, and ``omega_space`` (n, 3).  With
    ``fast``, even grids take the block path of this module (without, every
    point is evaluated directly: the reference in the tests).  Returns the
    number of blocks that failed their end check and were recomputed point
    by point, or -1 when every point was evaluated directly.
    """
    n = times.shape[0]
    tables = _tables(orbit, times, fast)
    if tables[0] == 0.0:
        for k in prange(n):
            w1, w2, w3, phi, theta, psi = state_at(orbit, times[k])
            _fill_state(k, w1, w2, w3, phi, theta, psi, omega, euler, rotation, omega_space)
        return -1
    redone = np.zeros((n + BLOCK - 1) // BLOCK, dtype=np.int64)
    for b in prange(redone.shape[0]):
        pieces = np.empty((PIECES, BLOCK))
        lo, hi = _run_block(orbit, times, tables, b, pieces, redone)
        for k in range(lo, hi):
            i = k - lo
            w1, w2, w3, phi, theta, psi = state_from_pieces(
                orbit,
                times[k],
                pieces[0, i],
                pieces[1, i],
                pieces[2, i],
                pieces[3, i],
                pieces[4, i],
            )
            _fill_state(k, w1, w2, w3, phi, theta, psi, omega, euler, rotation, omega_space)
    return redone.sum()


@parallel_kernel(cache=True, nogil=True)
def omega_space_on_grid(orbit, times, fast, omega_space):
    """Only the space-frame angular velocity (the herpolhode), in parallel.

    Returns as :func:`motion_on_grid`.
    """
    n = times.shape[0]
    tables = _tables(orbit, times, fast)
    if tables[0] == 0.0:
        for k in prange(n):
            x, y, z = omega_space_at(orbit, times[k])
            omega_space[k, 0] = x
            omega_space[k, 1] = y
            omega_space[k, 2] = z
        return -1
    redone = np.zeros((n + BLOCK - 1) // BLOCK, dtype=np.int64)
    for b in prange(redone.shape[0]):
        pieces = np.empty((PIECES, BLOCK))
        lo, hi = _run_block(orbit, times, tables, b, pieces, redone)
        for k in range(lo, hi):
            i = k - lo
            x, y, z = omega_space_from_pieces(
                orbit, times[k], pieces[0, i], pieces[1, i], pieces[2, i], pieces[3, i]
            )
            omega_space[k, 0] = x
            omega_space[k, 1] = y
            omega_space[k, 2] = z
    return redone.sum()
