"""Geometric phase ``Omega`` (signed solid angle of the polhode) in closed form.

Montgomery's formula (eqn:montgomery) splits the total phase as
``Delta alpha = 2ET/M - Omega``.  Forming ``Omega = 2ET/M - Delta alpha``
subtracts two numbers of the size of ``T``, which grows without bound near
the sphere (``T ~ 1/(I3 - I1)``) and near the separatrix: at
``I3/I1 - 1 = 2e-12`` every digit is lost.  This module evaluates ``Omega``
as one Bulirsch ``cel`` with positive arguments and a positive prefactor,
so nothing large is ever subtracted.

Derivation (SAM, ``M^2 > 2 E I2``; notation of :mod:`orbits.core.phase`)
----------------------------------------------------------------------
Let ``u = M^2 - 2 E I1``, ``v = 2 E I3 - M^2``, ``w = M^2 - 2 E I2`` (all
``> 0`` on SAM, ``d32 u - d21 v = d31 w`` with ``dij = Ii - Ij``),
``D = sqrt(d32 u / (I1 I2 I3))``, ``T = 4 K / D`` (eqn:TK), and
``p = 1 - n = I2 d31 / (I1 d32) > 1`` for the characteristic ``n`` of
eqn:GeometricPhase, so that ``I1 K + d31 Pi(n|k^2) = I3 cel(kc, p, 1, b)``
with ``b = d31/d32`` and ``K = cel(kc, p, 1, p)``.  Then, ``cel`` being linear
in its last two arguments,

    2ET/M - Delta alpha = 2 pi - 4 / (M D I1) * cel(kc, p, u, d31 w / d32).

For ``p > 1`` the integral satisfies (a partial-fraction identity of the
integrand; the same map Bulirsch uses to treat ``p < 0``)

    cel(kc, p, a, b) = cel(kc, p', a', b')
                       + (pi/2) (a p - b) / sqrt(p (p - 1) (p - kc^2)),
    p' = (p - kc^2) / (p - 1),   a' = (b - a) / (p - 1),
    b' = a' p' + (1 - kc^2)(a p - b) / (p - 1)^2.

With ``a = u`` and ``b = d31 w / d32``: ``a p - b = d21 d31 M^2 / (I1 d32)``,
``p - 1 = I3 d21 / (I1 d32)`` and ``p - kc^2 = d21 d31 M^2 / (I1 d32 u)``
(from ``I3 u + I1 v = d31 M^2``), so the elementary term times
``4 / (M D I1)`` is exactly the ``2 pi`` and cancels it; further ``a' = -I1 v / I3``,
``p' = d31 M^2 / (I3 u)`` and ``b' = 0``.  Hence

    Omega_SAM = 4 v / (M D I3) * cel(kc, d31 M^2 / (I3 u), 1, 0)        (1)

and, by the index swap ``1 <-> 3`` that eqn:GeometricPhase prescribes on
LAM (it reverses the orientation, hence the sign),

    Omega_LAM = -4 u / (M D I1) * cel(kc, d31 M^2 / (I1 v), 1, 0),      (2)

with ``D = sqrt(d21 v / (I1 I2 I3))`` there.  ``cel(kc, p, 1, 0) =
int_0^{pi/2} cos^2 / ((cos^2 + p sin^2) sqrt(cos^2 + kc^2 sin^2))`` is
positive and stays finite on the separatrix (``kc -> 0``), where ``K``
diverges.  ``u`` and ``v`` are sums of non-negative terms, so (1) and (2)
keep full relative precision near the axes (``Omega -> 0`` like ``v`` or
``u``), near the sphere and at any distance from the separatrix.  Both were
checked against ``2ET/M - Delta alpha`` at 60 digits (agreement 1e-56) and
are tested against a direct quadrature of the solid angle enclosed by the
polhode (tests/test_solid_angle.py).
"""

import math

from numba import njit, prange

from .elliptic import cel
from .launch import parallel_kernel
from .phase import (
    BRANCH_SAM,
    BRANCH_SEPARATRIX,
    orbit_constants,
    scaled_spin,
)


@njit(cache=True, nogil=True)
def solid_angle_from_invariants(i1, i2, i3, branch, m_sq, gap_m1, gap_3m, kc):
    """``Omega`` from the orbit's invariants, eqs. (1) and (2) of the module.

    Parameters
    ----------
    i1, i2, i3 : float
        Principal moments, ascending, any scale.
    branch : int
        ``BRANCH_SAM`` (+1) or ``BRANCH_LAM`` (-1); NaN is returned on the
        separatrix (0).
    m_sq, gap_m1, gap_3m : float
        ``M^2``, ``u = M^2 - 2 E I1`` and ``v = 2 E I3 - M^2`` (eqn:MM,
        eqn:EM), each accurate to rounding.
    kc : float
        ``sqrt(1 - k^2)`` for the ``k`` of eqn:TK on this branch.

    Returns
    -------
    float
        The signed solid angle, ``> 0`` on SAM (M circles I3), ``< 0`` on
        LAM (M circles I1); ``2ET/M - Delta alpha`` of eqn:montgomery.
    """
    if branch == BRANCH_SEPARATRIX:
        return math.nan
    d31 = i3 - i1
    momentum = math.sqrt(m_sq)
    if branch == BRANCH_SAM:
        # 4 v / (M D I3) with D = sqrt((I3-I2) u / (I1 I2 I3)), factor by factor
        # so that no product of four moments is formed (range of doubles)
        p = d31 * (m_sq / (i3 * gap_m1))
        front = (
            4.0
            * (gap_3m / momentum)
            * math.sqrt(i1 / i3)
            * math.sqrt(i2 / (i3 - i2))
            / math.sqrt(gap_m1)
        )
        return front * cel(kc, p, 1.0, 0.0)
    p = d31 * (m_sq / (i1 * gap_3m))
    front = (
        4.0
        * (gap_m1 / momentum)
        * math.sqrt(i3 / i1)
        * math.sqrt(i2 / (i2 - i1))
        / math.sqrt(gap_3m)
    )
    return -front * cel(kc, p, 1.0, 0.0)


@njit(cache=True, nogil=True)
def solid_angle_from_spin(i1, i2, i3, w1, w2, w3, scale, offset, closing):
    """``Omega`` for the spin ``(w1, w2, w3)`` with the factored separatrix gap
    ``M^2 - 2 E I2 = -scale * offset * closing`` (see ``phase.spin_gap``)."""
    branch, _, m_sq, gap_m1, gap_3m, kc, _, _, _ = orbit_constants(
        i1, i2, i3, w1, w2, w3, scale, offset, closing
    )
    return solid_angle_from_invariants(i1, i2, i3, branch, m_sq, gap_m1, gap_3m, kc)


@parallel_kernel(cache=True, nogil=True)
def solid_angle_from_vector_array(i1, i2, i3, w1, w2, w3, speed, out):
    """``Omega`` for arbitrary spin vectors ``(w1, w2, w3) / 2**speed`` (as
    ``phase.parts_from_vector_array``); NaN on the separatrix.  The gap is
    the exact one of ``phase.scaled_spin``."""
    for k in prange(out.shape[0]):
        spin = scaled_spin(i1[k], i2[k], i3[k], w1[k], w2[k], w3[k], speed[k])
        out[k] = solid_angle_from_spin(i1[k], i2[k], i3[k], *spin)
