"""Every closed-form quantity of :func:`orbits.phases` in one parallel pass.

The fold of ``theta`` (:func:`orbits.core.phase.given_angle`), the phase parts
(:func:`orbits.core.phase.parts_from_spin`) and the solid angle
(:func:`orbits.core.solid_angle.solid_angle_from_spin`) per point, each the
same scalar function as on the separate paths, so the values are the same
bit for bit.
"""

import math

from numba import njit, prange

from .phase import (
    STATUS_OK,
    body_constants,
    given_angle,
    parts_from_spin,
    spin_from_angle,
)
from .solid_angle import solid_angle_from_spin

TWO_PI = 2.0 * math.pi


@njit(cache=True, nogil=True)
def table_row(i1, i2, i3, phi, angle, from_offset, fold_limit, out, k):
    """Row ``k`` of ``out`` (columns of :data:`orbits.core.phase.PARTS_COLUMNS`,
    then the solid angle) for ``theta`` as given (folded here,
    :func:`orbits.core.phase.given_angle`) or ``dtheta``; returns the status
    code.  Rows whose code is not OK hold NaN from column 3 on.
    """
    angle, code = given_angle(angle, from_offset, fold_limit)
    if code != STATUS_OK:
        out[k, 0] = angle
        for j in range(1, 11):
            out[k, j] = math.nan
        return code
    return table_row_folded(i1, i2, i3, phi, angle, from_offset, out, k)


@njit(cache=True, nogil=True)
def table_row_folded(i1, i2, i3, phi, angle, from_offset, out, k):
    """:func:`table_row` for ``theta`` already in ``[0, pi/2]`` (or ``dtheta``)."""
    code, values = table_values(i1, i2, i3, phi, angle, from_offset)
    for j in range(11):
        out[k, j] = values[j]
    return code


@njit(cache=True, nogil=True)
def table_values(i1, i2, i3, phi, angle, from_offset):
    """``code, (theta, dtheta, theta_c, 2E, M^2, m, branch, T, 2ET/M, Delta alpha,
    Omega)`` for ``theta`` already in ``[0, pi/2]`` (or ``dtheta``).

    ``Delta alpha`` is clamped to ``>= 2 pi`` (``orbits.phases.at_least_two_pi``);
    NaN from ``2E`` on when ``code`` is not OK.  The CUDA kernel calls this
    one (the fold needs ``np.fmod``, which device code lacks: the GPU path
    folds on the host).
    """
    code, theta, dtheta, theta_c, w1, w2, w3, scale, offset, closing = spin_from_angle(
        body_constants(i1, i2, i3, phi), angle, from_offset
    )
    nan = math.nan
    if code != STATUS_OK:
        return code, (theta, dtheta, theta_c, nan, nan, nan, nan, nan, nan, nan, nan)
    two_e, m_sq, m_param, branch, period, dynamic, total = parts_from_spin(
        i1, i2, i3, w1, w2, w3, scale, offset, closing
    )
    return code, (
        theta,
        dtheta,
        theta_c,
        two_e,
        m_sq,
        m_param,
        float(branch),
        period,
        dynamic,
        TWO_PI if total < TWO_PI else total,  # NaN stays NaN, as np.maximum
        solid_angle_from_spin(i1, i2, i3, w1, w2, w3, scale, offset, closing),
    )


@njit(cache=True, nogil=True, parallel=True)
def phase_table_many(i1, i2, i3, phi, angles, from_offset, fold_limit, out, status):
    """:func:`table_row` for every point; inputs arrays of one length ``n``,
    ``out`` (n, 11), ``status`` (n,) int8."""
    for k in prange(angles.shape[0]):
        status[k] = table_row(
            i1[k], i2[k], i3[k], phi[k], angles[k], from_offset, fold_limit, out, k
        )
