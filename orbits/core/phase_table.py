"""Every column of :func:`orbits.phases` in one parallel pass.

The fold of ``theta`` (:func:`orbits.core.phase.given_angle`), the phase parts
(:func:`orbits.core.phase.parts_from_spin`), the solid angle
(:func:`orbits.core.solid_angle.solid_angle_from_spin`) and the normalised
columns per point, each the same scalar function (and the same operations)
as on the separate paths, so the values are the same bit for bit.
"""

import math

from numba import njit, prange

from .launch import parallel_kernel
from .phase import (
    STATUS_OK,
    at_least_two_pi,
    body_constants,
    given_angle,
    parts_from_spin,
    spin_from_angle,
)
from .solid_angle import solid_angle_from_spin

TWO_PI = 2.0 * math.pi


@njit(cache=True, nogil=True)
def table_values(i1, i2, i3, phi, angle, from_offset):
    """``code, (theta, dtheta, theta_c, 2E, M^2, m, branch, T, 2ET/M, Delta alpha,
    Omega)`` for ``theta`` already in ``[0, pi/2]`` (or ``dtheta``).

    ``Delta alpha`` is clamped to ``>= 2 pi`` (``orbits.phases.at_least_two_pi``);
    NaN from ``2E`` on when ``code`` is not OK.
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
        at_least_two_pi(total),  # 2 pi where below it by rounding; NaN stays NaN
        solid_angle_from_spin(i1, i2, i3, w1, w2, w3, scale, offset, closing),
    )


# the float columns of orbits.phases, in its order ("branch" apart, as codes)
COLUMNS = (
    "I1",
    "I2",
    "I3",
    "theta",
    "dtheta",
    "phi",
    "theta_crit",
    "energy",
    "momentum",
    "D",
    "m",
    "period",
    "dynamic_phase",
    "total_phase",
    "geometric_phase",
)
N_COLUMNS = len(COLUMNS)


@njit(cache=True, nogil=True)
def phases_row(i1, i2, i3, phi, angle, from_offset):
    """``code, branch code, (the COLUMNS values)`` of one row of :func:`orbits.phases`.

    ``angle`` is ``theta`` already in ``[0, pi/2]`` or ``dtheta``.  The
    branch code is 0 on SAM, 1 on LAM (the categories of the ``branch``
    column).  Moments are normalised to ``|I| = 1`` here, and ``energy``,
    ``momentum`` and ``D`` are for them, with the operations and their order
    of the NumPy expressions they replace (``0.5 * 2E / |I|``,
    ``sqrt(M^2) / |I|``, ``M^2 / (2E |I|)``), so the values are the same bit
    for bit.  The CUDA kernel calls this one too.
    """
    code, values = table_values(i1, i2, i3, phi, angle, from_offset)
    theta, dtheta, theta_c, two_e, m_sq, m_param, branch, period, dynamic, total, omega = values
    norm = math.sqrt(i1 * i1 + i2 * i2 + i3 * i3)
    row = (
        i1 / norm,
        i2 / norm,
        i3 / norm,
        theta,
        dtheta,
        phi,
        theta_c,
        0.5 * two_e / norm,
        math.sqrt(m_sq) / norm,
        m_sq / (two_e * norm),
        m_param,
        period,
        dynamic,
        total,
        omega,
    )
    return code, 1 if branch < 0.0 else 0, row


@parallel_kernel(cache=True, nogil=True)
def phases_columns(i1, i2, i3, phi, angles, from_offset, fold_limit, columns, branch, status):
    """:func:`phases_row` for every angle, ``theta`` folded here.

    ``i1, i2, i3, phi`` have length ``n`` or 1 (one body, one azimuth: no
    broadcast copies); ``angles`` length ``n``.  ``columns`` (len(COLUMNS), n)
    receives the columns, ``branch`` (n,) int8 the branch codes, ``status``
    (n,) int8 the ``STATUS_*`` codes.
    """
    n = angles.shape[0]
    one = i1.shape[0] == 1
    one_phi = phi.shape[0] == 1
    for k in prange(n):
        # k - k, not 0: the prange index may be unsigned, and 0 with it
        # would unify to a float
        body = k - k if one else k
        azimuth = k - k if one_phi else k
        angle, code = given_angle(angles[k], from_offset, fold_limit)
        if code != STATUS_OK:
            status[k] = code
            branch[k] = 0
            for c in range(N_COLUMNS):
                columns[c, k] = math.nan
            continue
        code, lam, row = phases_row(i1[body], i2[body], i3[body], phi[azimuth], angle, from_offset)
        status[k] = code
        branch[k] = lam
        for c in range(N_COLUMNS):
            columns[c, k] = row[c]
