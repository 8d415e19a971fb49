"""Total, dynamic and geometric phase in closed form.

Conventions (the paper's): moments normalised to ``|I| = 1`` for reported
energies and momenta, ``|omega0| = 1`` (so times are in units of
``1/|omega0|``: seconds for 1 rad/s), and the initial spin

    omega0 = (sin(theta) cos(phi), sin(theta) sin(phi), cos(theta))

in the principal frame, ``theta`` from the I3 axis and ``phi`` from the I1
axis, both in radians, ``0 <= theta <= pi/2``.  By the symmetries of the
top (omega -> -omega, reflections of the principal axes) every initial
spin maps to one in this range with the same phase.

Branches: ``SAM`` (short-axis mode, ``M^2 > 2 E I2``, ``theta < theta_c``:
the angular momentum circles the I3 axis in the body) and ``LAM``
(long-axis mode, ``M^2 < 2 E I2``, ``theta > theta_c``: it circles I1).

The total phase ``Delta alpha`` (eqn:GeometricPhase) is the angle, right-
handed about the angular momentum, by which the body's orientation after
one period T differs from its start:  ``R(T) = Rot(M, Delta alpha) R(0)``.
It splits as ``Delta alpha = 2ET/M - Omega`` (eqn:montgomery) into the
dynamic phase ``2ET/M`` and the geometric phase ``Omega``, the signed solid
angle enclosed by the polhode (positive on SAM, negative on LAM).
"""

from collections import namedtuple

import numpy as np
import pandas as pd

from .bodies import as_moments
from .core import phase as _kernels
from .errors import AngleError, SeparatrixError
from .threads import size_aware

HALF_PI = 0.5 * np.pi

PhaseLimits = namedtuple("PhaseLimits", ["theta_zero", "theta_half_pi"])
PhaseLimits.__doc__ = """Limits of the total phase at the two ends of 0 < theta < pi/2 (phi = 0).

theta_zero : eqn:alphamin1, ``2 pi sqrt(I1 I2 / ((I3-I2)(I3-I1)))``
theta_half_pi : eqn:alphamin2, ``2 pi sqrt(I2 I3 / ((I2-I1)(I3-I1)))``
"""


def _float_array(name, value):
    array = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(array)):
        raise AngleError(f"{name} must be finite, got {_first_bad(array)}")
    return array


def _first_bad(array):
    flat = np.ravel(array)
    return flat[~np.isfinite(flat)][0]


def _spin_inputs(moments, theta, dtheta, phi):
    """Validate the angle arguments; return ``(from_offset, angle, phi, shape)``."""
    if (theta is None) == (dtheta is None):
        raise AngleError("give exactly one of theta and dtheta")
    from_offset = dtheta is not None
    angle = np.asarray(dtheta if from_offset else theta, dtype=float)
    phi = _float_array("phi", phi)
    shape = np.broadcast_shapes(moments.shape[:-1], angle.shape, phi.shape)
    return from_offset, angle, phi, shape


def _flat(array, shape):
    return np.ascontiguousarray(np.broadcast_to(array, shape), dtype=float).ravel()


def _check_status(status, moments, angle, phi, shape, from_offset):
    """Raise the error that the kernel's first non-OK status code stands for."""
    bad = np.flatnonzero(status.ravel())
    if bad.size == 0:
        return
    k = int(bad[0])
    code = int(status.ravel()[k])
    value = float(_flat(angle, shape)[k])
    name = "dtheta" if from_offset else "theta"
    if code == _kernels.STATUS_NOT_FINITE:
        raise AngleError(f"{name} must be finite, got {value}")
    i1, i2, i3 = (float(_flat(moments[..., j], shape)[k]) for j in range(3))
    theta_c = _kernels.critical_angle(i1, i2, i3, float(_flat(phi, shape)[k]))
    if code == _kernels.STATUS_OUT_OF_RANGE:
        what = (f"theta_c + dtheta = {theta_c:.17g} + {value:.17g}"
                if from_offset else f"theta = {value:.17g}")
        raise AngleError(
            f"{what} is outside [0, pi/2]; by symmetry every spin maps into "
            "that range (theta is measured from the I3 axis)")
    raise SeparatrixError(
        f"{name} = {value:.17g} puts the spin on the separatrix M^2 = 2 E I2 "
        f"(theta_c = {theta_c:.17g}), where the period and the total phase "
        "are infinite; pass a nonzero dtheta = theta - theta_crit instead")


@size_aware
def critical_angle(body_or_moments, phi=0.0):
    """Polar angle ``theta_c`` of omega0 on the separatrix ``M^2 = 2 E I2``.

    ``tan(theta_c) = sqrt(I3 (I3 - I2) / (I1 (I2 - I1) cos^2 phi))``.  This is
    the paper's ``theta_crit = arccot(sqrt(beta))`` with the erratum in
    eqn:beta corrected: ``beta = I1 (I2-I1) / (I3 (I3-I2))``.

    Parameters
    ----------
    body_or_moments : Body or array_like, shape (..., 3)
    phi : float or array_like
        Azimuth of omega0 from the I1 axis, radians.

    Returns
    -------
    float or ndarray
        Radians in ``(0, pi/2]``; broadcast over bodies and ``phi``.

    Raises
    ------
    NonPhysicalBodyError, SymmetricTopError
        Invalid moments.
    AngleError
        ``phi`` not finite.
    """
    moments = as_moments(body_or_moments)
    phi = _float_array("phi", phi)
    shape = np.broadcast_shapes(moments.shape[:-1], phi.shape)
    out = np.empty(shape)
    _kernels.critical_angle_many(*(_flat(moments[..., k], shape) for k in range(3)),
                                 _flat(phi, shape), out.reshape(-1))
    return float(out) if out.ndim == 0 else out


@size_aware
def total_phase(body_or_moments, theta=None, *, dtheta=None, phi=0.0):
    """Total phase ``Delta alpha`` (eqn:GeometricPhase), radians.

    Parameters
    ----------
    body_or_moments : Body or array_like, shape (..., 3)
        Principal moments in any order and scale (sorted internally).
    theta : float or array_like, optional
        Polar angle of omega0 from the I3 axis, radians, in [0, pi/2].
    dtheta : float or array_like, optional
        Offset ``theta - theta_c`` from the critical angle instead of
        ``theta``.  Near the separatrix the phase is ill-conditioned in
        ``theta`` (relative error ~ eps / |theta - theta_c|) but not in
        ``dtheta``: with ``dtheta`` the result keeps ~1e-15 relative
        accuracy down to ``|dtheta| = 1e-300``.
    phi : float or array_like
        Azimuth of omega0 from the I1 axis, radians (default 0).

    Returns
    -------
    ndarray
        ``Delta alpha``, broadcast over bodies and angles.  On SAM it is
        ``phi_Euler(T) - 2 pi``, on LAM ``phi_Euler(T)`` (eqn:alphaproto);
        the orientation after one period is ``Rot(M, Delta alpha) R(0)``.

    Raises
    ------
    NonPhysicalBodyError, SymmetricTopError
        Invalid moments.
    AngleError
        Angles NaN or infinite, both or neither of theta/dtheta given, or
        ``theta`` outside [0, pi/2].
    SeparatrixError
        ``theta`` exactly on the separatrix (``dtheta == 0``).
    """
    moments = as_moments(body_or_moments)
    from_offset, angle, phi, shape = _spin_inputs(moments, theta, dtheta, phi)
    out = np.empty(shape)
    status = np.empty(shape, dtype=np.int8)
    if moments.ndim == 1 and phi.ndim == 0:
        # one body: its constants are computed once, angles used in place
        _kernels.total_phase_one_body(
            moments[0], moments[1], moments[2], float(phi),
            np.ascontiguousarray(angle, dtype=float).reshape(-1), from_offset,
            out.reshape(-1), status.reshape(-1))
    else:
        _kernels.total_phase_many(
            *(_flat(moments[..., k], shape) for k in range(3)), _flat(phi, shape),
            _flat(angle, shape), from_offset, out.reshape(-1), status.reshape(-1))
    _check_status(status, moments, angle, phi, shape, from_offset)
    return out


@size_aware
def phases(body_or_moments, theta=None, phi=0.0, *, dtheta=None):
    """Closed-form phases and their ingredients, one row per initial spin.

    Parameters are as for :func:`total_phase`.

    Returns
    -------
    pandas.DataFrame
        Columns, with ``|I| = 1`` and ``|omega0| = 1``:

        ``I1, I2, I3``
            normalised principal moments;
        ``theta, dtheta, phi, theta_crit``
            spin angles and critical angle, radians;
        ``branch``
            ``"SAM"`` (M^2 > 2 E I2) or ``"LAM"`` (M^2 < 2 E I2);
        ``energy``
            E = omega0 . I . omega0 / 2 (eqn:E);
        ``momentum``
            M = |I . omega0| (eqn:J);
        ``m``
            elliptic parameter k^2 of eqn:TK (indices 1<->3 on LAM);
        ``period``
            T of eqn:TK, in units of 1/|omega0|;
        ``dynamic_phase``
            2ET/M;
        ``total_phase``
            Delta alpha, eqn:GeometricPhase;
        ``geometric_phase``
            2ET/M - Delta alpha = Omega (eqn:montgomery).

    Raises
    ------
    As :func:`total_phase`.
    """
    moments = as_moments(body_or_moments)
    from_offset, angle, phi, shape = _spin_inputs(moments, theta, dtheta, phi)
    i1, i2, i3 = (_flat(moments[..., k], shape) for k in range(3))
    parts = np.empty((i1.shape[0], len(_kernels.PARTS_COLUMNS)))
    status = np.empty(i1.shape[0], dtype=np.int8)
    _kernels.phase_parts_many(i1, i2, i3, _flat(phi, shape), _flat(angle, shape),
                              from_offset, parts, status)
    _check_status(status, moments, angle, phi, shape, from_offset)
    (theta, dtheta, theta_c, two_e, m_sq, m_param, branch, period, dynamic,
     total) = parts.T
    norm = np.sqrt(i1 * i1 + i2 * i2 + i3 * i3)
    return pd.DataFrame({
        "I1": i1 / norm, "I2": i2 / norm, "I3": i3 / norm,
        "theta": theta, "dtheta": dtheta, "phi": _flat(phi, shape),
        "theta_crit": theta_c,
        **_parts_columns(norm, two_e, m_sq, m_param, branch, period, dynamic, total),
    })


def _parts_columns(norm, two_e, m_sq, m_param, branch, period, dynamic, total):
    """The columns shared by :func:`phases` and :func:`spin_phases`."""
    return {
        "branch": pd.Categorical.from_codes((branch < 0).astype(np.int8),
                                            categories=["SAM", "LAM"]),
        "energy": 0.5 * two_e / norm,
        "momentum": np.sqrt(m_sq) / norm,
        "m": m_param,
        "period": period,
        "dynamic_phase": dynamic,
        "total_phase": total,
        "geometric_phase": dynamic - total,
    }


def phase_limits(body_or_moments):
    """Limits of ``Delta alpha`` as theta -> 0 and theta -> pi/2 (phi = 0).

    Near either axis the polhode shrinks to a point, the geometric phase
    vanishes and the total phase is all dynamic.  Linearising Euler's
    equations gives eqn:alphamin1 and eqn:alphamin2 (the paper labels both
    ``alpha_min,z``; the second is the limit at the I1, i.e. x, axis).

    Returns
    -------
    PhaseLimits
        ``(theta_zero, theta_half_pi)``, each broadcast over bodies.
        Both exceed 2 pi for every physical body: the triangle
        inequalities give ``I3 - I2 <= I1`` and ``I3 - I1 <= I2``.
    """
    moments = as_moments(body_or_moments)
    i1, i2, i3 = moments[..., 0], moments[..., 1], moments[..., 2]
    at_zero = 2.0 * np.pi * np.sqrt(i1 * i2 / ((i3 - i2) * (i3 - i1)))
    at_half_pi = 2.0 * np.pi * np.sqrt(i2 * i3 / ((i2 - i1) * (i3 - i1)))
    if at_zero.ndim == 0:
        return PhaseLimits(float(at_zero), float(at_half_pi))
    return PhaseLimits(at_zero, at_half_pi)


@size_aware
def spin_phases(body_or_moments, omega):
    """Closed-form phases for arbitrary initial angular velocities.

    Parameters
    ----------
    body_or_moments : Body or array_like, shape (..., 3)
    omega : array_like, shape (..., 3)
        Initial angular velocity in the *principal* frame, components
        along (I1, I2, I3) sorted ascending, any magnitude, any direction
        (use :attr:`Body.frame` to convert from your own axes).

    Returns
    -------
    pandas.DataFrame
        Columns ``w1, w2, w3`` (the spin given) followed by ``branch,
        energy, momentum, m, period, dynamic_phase, total_phase,
        geometric_phase`` as in :func:`phases`, for ``|I| = 1`` and the
        given ``|omega|`` (energy scales as ``|omega|^2``, momentum as
        ``|omega|``, the period as ``1/|omega|``; the phases not at all).

    Raises
    ------
    NonPhysicalBodyError, SymmetricTopError
        Invalid moments.
    AngleError
        ``omega`` not finite, or zero.
    SeparatrixError
        ``M^2 == 2 E I2`` to rounding (including a spin exactly along I2).

    Notes
    -----
    A vector knows its distance from the separatrix only to rounding, so
    near it this path is ill-conditioned (as the ``theta`` path of
    :func:`total_phase`); use ``dtheta`` there.
    """
    moments = as_moments(body_or_moments)
    omega = np.asarray(omega, dtype=float)
    if omega.ndim == 0 or omega.shape[-1] != 3:
        raise AngleError(f"omega must have shape (..., 3), got {omega.shape}")
    if not np.all(np.isfinite(omega)):
        raise AngleError(f"omega must be finite, got {_first_bad(omega)}")
    shape = np.broadcast_shapes(moments.shape[:-1], omega.shape[:-1])
    cols = [np.ascontiguousarray(np.broadcast_to(a[..., k], shape),
                                 dtype=float).ravel()
            for a in (moments, omega) for k in range(3)]
    i1, i2, i3, w1, w2, w3 = cols
    if np.any((w1 == 0.0) & (w2 == 0.0) & (w3 == 0.0)):
        raise AngleError("omega must be nonzero")
    parts = np.empty((i1.shape[0], 7))
    _kernels.parts_from_vector_array(i1, i2, i3, w1, w2, w3, parts)
    two_e, m_sq, m_param, branch, period, dynamic, total = parts.T
    if np.any(branch == 0):
        k = int(np.flatnonzero(branch == 0)[0])
        raise SeparatrixError(
            f"omega = ({w1[k]:.17g}, {w2[k]:.17g}, {w3[k]:.17g}) lies on the "
            "separatrix M^2 = 2 E I2 (infinite period and phase)")
    norm = np.sqrt(i1 * i1 + i2 * i2 + i3 * i3)
    return pd.DataFrame({
        "w1": w1, "w2": w2, "w3": w3,
        **_parts_columns(norm, two_e, m_sq, m_param, branch, period, dynamic, total),
    })
