"""Montgomery's formula by quadrature along the polhode (numba kernels).

An independent check of the closed form: only the two invariants and
Euler's equations are used, no elliptic functions.  The angular momentum
in the body, ``M (sin v cos u, sin v sin u, cos v)`` about the axis the
polhode circles, is parameterised by its azimuth ``u``; the energy fixes
the polar angle ``v(u)``:

* SAM (circles I3)::

      g(u) = cos^2 u / I1 + sin^2 u / I2 - 1/I3
      sin^2 v = (2E/M^2 - 1/I3) / g(u)
      cos^2 v = (cos^2 u (M^2 - 2EI1)/I1 + sin^2 u (M^2 - 2EI2)/I2) / (M^2 g(u))

  and, from ``M' = M x omega``, ``u' = M cos v g(u) > 0`` for ``M3 > 0``:
  counter-clockwise seen from outside, so the enclosed (right-hand) region
  is the cap about I3 and ``Omega = +cap``.
* LAM (circles I1)::

      h(u) = 1/I1 - cos^2 u / I2 - sin^2 u / I3
      sin^2 v = (1/I1 - 2E/M^2) / h(u),   u' = -M cos v h(u)

  clockwise seen from outside: ``Omega = -cap``.

Then ``T = 4 int_0^{pi/2} du / |u'|``, ``cap = 4 int_0^{pi/2} (1 - cos v) du``
(the polhode is symmetric under both reflections), and Montgomery's
``Delta alpha = 2 E T / M - Omega`` (eqn:montgomery).
"""

import math

import numpy as np
from numba import njit

_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(20)
GAUSS_NODES = np.ascontiguousarray(_NODES)
GAUSS_WEIGHTS = np.ascontiguousarray(_WEIGHTS)
HALF_PI = 0.5 * math.pi
_STACK = 200


@njit(cache=True, nogil=True)
def _integrands(u, sam, inv, gap_m1, gap_3m, gap, m_sq, momentum):
    """(dt/du, 1 - cos v) at azimuth u.

    ``inv = (1/I1, 1/I2, 1/I3, 1/I1 - 1/I3, 1/I2 - 1/I3, 1/I1 - 1/I2)``,
    the differences formed as ``(Ij - Ii)/(Ii Ij)`` (a difference of the
    rounded reciprocals would lose every digit the moments share, all of
    them for a nearly symmetric body); the invariants enter as
    ``M^2 - 2 E I1``, ``2 E I3 - M^2`` and ``M^2 - 2 E I2`` so that
    ``cos^2 v`` keeps its relative accuracy at the saddle, where it is
    proportional to ``M^2 - 2 E I2``.
    """
    c2 = math.cos(u) ** 2
    s2 = 1.0 - c2
    if sam:
        denom = c2 * inv[3] + s2 * inv[4]
        cos_sq = (c2 * gap_m1 * inv[0] + s2 * gap * inv[1]) / (m_sq * denom)
        sin_sq = gap_3m * inv[2] / (m_sq * denom)
    else:
        denom = c2 * inv[5] + s2 * inv[3]
        cos_sq = (-c2 * gap * inv[1] + s2 * gap_3m * inv[2]) / (m_sq * denom)
        sin_sq = gap_m1 * inv[0] / (m_sq * denom)
    cos_v = math.sqrt(max(cos_sq, 0.0))
    dt_du = 1.0 / (momentum * cos_v * denom)
    return dt_du, sin_sq / (1.0 + cos_v)


@njit(cache=True, nogil=True)
def _panel(a, b, sam, inv, gap_m1, gap_3m, gap, m_sq, momentum):
    half = 0.5 * (b - a)
    mid = 0.5 * (a + b)
    time = 0.0
    area = 0.0
    for k in range(GAUSS_NODES.shape[0]):
        dt, dcap = _integrands(
            mid + half * GAUSS_NODES[k], sam, inv, gap_m1, gap_3m, gap, m_sq, momentum
        )
        time += GAUSS_WEIGHTS[k] * dt
        area += GAUSS_WEIGHTS[k] * dcap
    return half * time, half * area


@njit(cache=True, nogil=True)
def period_and_cap(i1, i2, i3, w1, w2, w3, gap, rtol):
    """Period T and the cap's solid angle from the invariants alone.

    ``gap = M^2 - 2 E I2`` (accurate; its sign picks the branch).
    Adaptive Gauss-Legendre (20 points per panel; a panel is split until
    its two halves agree with it to ``rtol`` of the running totals).

    Returns
    -------
    period, cap, branch : float
        ``branch`` is +1 (SAM) or -1 (LAM).
    """
    sam = gap > 0.0
    s1 = w1 * w1
    s2 = w2 * w2
    s3 = w3 * w3
    m_sq = i1 * i1 * s1 + i2 * i2 * s2 + i3 * i3 * s3
    gap_m1 = i2 * (i2 - i1) * s2 + i3 * (i3 - i1) * s3
    gap_3m = i1 * (i3 - i1) * s1 + i2 * (i3 - i2) * s2
    momentum = math.sqrt(m_sq)
    inv = np.array(
        [
            1.0 / i1,
            1.0 / i2,
            1.0 / i3,
            (i3 - i1) / (i1 * i3),
            (i3 - i2) / (i2 * i3),
            (i2 - i1) / (i1 * i2),
        ]
    )
    lo_stack = np.empty(_STACK)
    hi_stack = np.empty(_STACK)
    depth = 0
    edges = 16
    for k in range(edges):
        lo_stack[depth] = HALF_PI * k / edges
        hi_stack[depth] = HALF_PI * (k + 1) / edges
        depth += 1
    whole_t, whole_c = _panel(0.0, HALF_PI, sam, inv, gap_m1, gap_3m, gap, m_sq, momentum)
    total_t = 0.0
    total_c = 0.0
    scale_t = abs(whole_t)
    scale_c = abs(whole_c)
    while depth > 0:
        depth -= 1
        a = lo_stack[depth]
        b = hi_stack[depth]
        t_ab, c_ab = _panel(a, b, sam, inv, gap_m1, gap_3m, gap, m_sq, momentum)
        mid = 0.5 * (a + b)
        t_l, c_l = _panel(a, mid, sam, inv, gap_m1, gap_3m, gap, m_sq, momentum)
        t_r, c_r = _panel(mid, b, sam, inv, gap_m1, gap_3m, gap, m_sq, momentum)
        scale_t = max(scale_t, total_t + t_l + t_r)
        scale_c = max(scale_c, total_c + c_l + c_r)
        converged = abs(t_l + t_r - t_ab) <= rtol * scale_t and abs(
            c_l + c_r - c_ab
        ) <= rtol * max(scale_c, 1e-300)
        if converged or depth + 2 > _STACK or b - a < 1e-15:
            total_t += t_l + t_r
            total_c += c_l + c_r
        else:
            lo_stack[depth] = a
            hi_stack[depth] = mid
            lo_stack[depth + 1] = mid
            hi_stack[depth + 1] = b
            depth += 2
    return 4.0 * total_t, 4.0 * total_c, (1.0 if sam else -1.0)


@njit(cache=True, nogil=True)
def montgomery_phase(i1, i2, i3, w1, w2, w3, gap, rtol):
    """``Delta alpha = 2ET/M - Omega`` with T and Omega by quadrature.

    ``gap = M^2 - 2 E I2`` of the spin (see :func:`period_and_cap`).
    Returns ``(total, dynamic, omega_signed, period, branch)``.
    """
    two_e = i1 * w1 * w1 + i2 * w2 * w2 + i3 * w3 * w3
    momentum = math.sqrt(i1 * i1 * w1 * w1 + i2 * i2 * w2 * w2 + i3 * i3 * w3 * w3)
    period, cap, branch = period_and_cap(i1, i2, i3, w1, w2, w3, gap, rtol)
    signed = branch * cap  # right-hand rule: + on SAM, - on LAM
    dynamic = two_e * period / momentum
    return dynamic - signed, dynamic, signed, period, branch
