"""Total, dynamic and geometric phase in closed form.

Energy convention (the same across the API): every energy, momentum and
``D = M^2/(2E)`` is for the moments and the spin it is reported with.
:func:`phases` (and the catalogs and surveys built on it) takes a spin
*direction*, so its rows are in the paper's normalisation throughout: the
``I1, I2, I3`` columns are the moments normalised to ``|I| = 1``, the spin
has ``|omega0| = 1`` and energy, momentum and D are for those (times in
units of ``1/|omega0|``: seconds for 1 rad/s).  :func:`spin_phases` and
:class:`orbits.Motion` take a spin *vector* and use the moments as given:
kg m^2 and rad/s give J, J s, kg m^2 and s.  The phases and ``m`` do not
depend on either scale.  The initial spin of :func:`phases` is

    omega0 = (sin(theta) cos(phi), sin(theta) sin(phi), cos(theta))

in the principal frame, ``theta`` from the I3 axis and ``phi`` from the I1
axis, both in radians.  Any ``theta`` and ``phi`` are accepted and folded
into the fundamental domain ``0 <= theta, phi <= pi/2`` (:func:`fold_angle`):
the half-turns about each principal axis (flipping the signs of two
components of omega) and ``omega -> -omega`` with ``t -> -t`` map the
motion to one with the same T, E, M and total phase (about the mapped M),
and together they flip the sign of any component.  ``dtheta`` is not
folded (it is an offset from ``theta_c``; ``theta_c + dtheta`` must lie in
``[0, pi/2]``); ``phi`` is folded on both paths.

Branches: ``SAM`` (short-axis mode, ``M^2 > 2 E I2``, ``theta < theta_c``:
the angular momentum circles the I3 axis in the body) and ``LAM``
(long-axis mode, ``M^2 < 2 E I2``, ``theta > theta_c``: it circles I1).

The total phase ``Delta alpha`` (eqn:GeometricPhase) is the angle, right-
handed about the angular momentum, by which the body's orientation after
one period T differs from its start:  ``R(T) = Rot(M, Delta alpha) R(0)``.
It splits as ``Delta alpha = 2ET/M - Omega`` (eqn:montgomery) into the
dynamic phase ``2ET/M`` and the geometric phase ``Omega``, the signed solid
angle enclosed by the polhode (positive on SAM, negative on LAM).  ``Omega``
is evaluated in its own closed form (:mod:`orbits.core.solid_angle`), not as
that difference, which loses every digit near the sphere.
"""

import math
from collections import namedtuple

import numpy as np

from ._args import broadcast, finite_array, real_array
from ._args import flat_broadcast as _flat
from .bodies import (
    critical_angle,  # noqa: F401 (re-exported: defined in bodies, below this layer)
    unit_moments,
)
from .cells import exact_number, numbers_label
from .core import angles as _angles
from .core import phase as _kernels
from .core import phase_table as _table
from .core import solid_angle as _solid
from .device import check_device, cuda_kernels, run_cuda
from .errors import AngleError, InputError, SeparatrixError
from .threads import size_aware

HALF_PI = 0.5 * np.pi


# how a spin (or a Motion's omega0) on the separatrix as a double holds it is
# refused, after "on the separatrix M^2 = 2 E I2 (...)": k_c below
# orbits.core.phase.KC_FLOOR (4.9e-312), so 1 - k^2 below its square
TOO_NEAR_SEPARATRIX = "or so near it (1 - k^2 below 2.4e-623) that a double cannot hold its orbit"


class PhaseLimits(namedtuple("PhaseLimits", ["theta_zero", "theta_half_pi"])):
    """Limits of the total phase at the two ends of 0 < theta < pi/2 (phi = 0).

    theta_zero : eqn:alphamin1, ``2 pi sqrt(I1 I2 / ((I3-I2)(I3-I1)))``
    theta_half_pi : eqn:alphamin2, ``2 pi sqrt(I2 I3 / ((I2-I1)(I3-I1)))``
    """

    __slots__ = ()

    def _repr_html_(self):
        """The two limits in radians and in turns (one body), or their ranges."""
        from .units import html_table

        rows = []
        for name, value in (
            ("theta -> 0", self.theta_zero),
            ("theta -> pi/2", self.theta_half_pi),
        ):
            values = np.asarray(value, dtype=float)
            if values.ndim == 0:
                rows.append((f"total phase, {name}", float(values), "rad"))
                rows.append(("", float(values) / (2.0 * np.pi), "turns (x 2 pi)"))
            elif values.size == 0:
                rows.append((f"total phase, {name}", "(no bodies)", ""))
            else:
                low, high = float(values.min()), float(values.max())
                rows.append((f"total phase, {name}", f"{low:.10g} to {high:.10g}", "rad"))
        return html_table("PhaseLimits (eqn:alphamin1, eqn:alphamin2)", rows)


def _first_bad(array):
    flat = np.ravel(array)
    return flat[~np.isfinite(flat)][0]


# |angle| above which fold_angle refuses (the input's ulp exceeds 4e-10 rad)
FOLD_LIMIT = 2.0**21


def fold_angle(angle):
    """Fold polar or azimuthal angles into ``[0, pi/2]`` by the top's symmetries.

    The spin ``(sin t cos p, sin t sin p, cos t)`` has the same period,
    E, M and total phase as the one with each component's sign flipped
    (module docstring), i.e. as ``(|w1|, |w2|, |w3|)``.  Its angles are
    ``|t'|`` and ``|p'|`` with ``t' = t - k pi``, ``p' = p - j pi`` reduced to
    ``[-pi/2, pi/2]``: ``sin t`` and ``cos t`` change sign together under
    ``t -> t - pi``, and ``t -> -t`` flips ``w1`` and ``w2`` only.

    Parameters
    ----------
    angle : float or array_like
        Radians, finite.

    Returns
    -------
    ndarray
        Radians in ``[0, pi/2]``; values in ``[-pi/2, pi/2]`` come back as
        ``|angle|`` bit for bit.  Others are reduced by pi in double-double
        (``fl(pi)`` exactly by ``fmod``, then pi's low part): within about
        half an ulp of the result (1.1e-16 relative against mpmath over
        ``|angle| <= FOLD_LIMIT = 2**21``), except within a few ulps of a
        multiple of pi, where the result is tiny and its error is the
        rounding of pi's double-double times ``k`` (up to about 1.5e-26 rad
        at ``|angle| = 2**21``; 7.6e-27 rad, 1.7e-13 relative, measured at
        1889039.6626035427).  When every
        value already lies in ``[0, pi/2]`` the input array itself is returned
        (no copy).

    Raises
    ------
    AngleError
        A finite ``|angle| > FOLD_LIMIT``.
    """
    angle = np.asarray(angle, dtype=float)
    flat = np.ascontiguousarray(angle).reshape(-1)
    if _angles.all_folded(flat):
        return angle  # the common case: no copy (a fresh 8 MB array costs page faults)
    folded = np.empty_like(flat)
    first = _angles.fold_many(flat, FOLD_LIMIT, folded)
    if first >= 0:
        # beyond the limit the double's own spacing exceeds 4e-10 rad, and far
        # beyond it the double carries no fraction of a radian at all, so a
        # fold would be a made-up number
        raise AngleError(
            f"angle {exact_number(flat[first])} rad is too large to fold into "
            f"[0, pi/2] faithfully; give angles within +-{FOLD_LIMIT:.0f} rad"
        )
    return folded.reshape(angle.shape)


def _spin_inputs(moments, theta, dtheta, phi):
    """Validate and fold the angle arguments; return ``(from_offset, angle, phi, shape)``."""
    if (theta is None) == (dtheta is None):
        raise AngleError("give exactly one of theta and dtheta")
    from_offset = dtheta is not None
    name = "dtheta" if from_offset else "theta"
    angle = real_array(name, dtheta if from_offset else theta, AngleError)
    phi = finite_array("phi", phi, AngleError)
    if not from_offset:
        angle = fold_angle(angle)
    phi = fold_angle(phi)
    shape = broadcast([("moments", moments.shape[:-1]), (name, angle.shape), ("phi", phi.shape)])
    return from_offset, angle, phi, shape


def _check_status(status, moments, angle, phi, shape, from_offset):
    """Raise the error that the kernel's first non-OK status code stands for."""
    if not status.any():  # the common case, without an index array
        return
    bad = np.flatnonzero(status.ravel())
    k = int(bad[0])
    code = int(status.ravel()[k])
    value = float(_flat(angle, shape)[k])
    name = "dtheta" if from_offset else "theta"
    if code == _kernels.STATUS_NOT_FINITE:
        raise AngleError(f"{name} must be finite, got {value}")
    i1, i2, i3 = (float(_flat(moments[..., j], shape)[k]) for j in range(3))
    constants = _kernels.body_constants(i1, i2, i3, float(_flat(phi, shape)[k]))
    theta_c = constants[2]
    if code == _kernels.STATUS_OUT_OF_RANGE and not from_offset:
        # fold_angle puts every theta in [0, pi/2]: a fold that did not
        raise AngleError(
            f"theta folded to {exact_number(value)}, outside [0, pi/2] (an error in "
            "orbits.phases.fold_angle; please report it)"
        )
    if code == _kernels.STATUS_OUT_OF_RANGE:
        raise AngleError(
            f"theta_c + dtheta = {exact_number(theta_c)} + {exact_number(value)} is outside "
            f"[0, pi/2]: dtheta must lie in [-theta_c, pi/2 - theta_c] = "
            f"[{exact_number(-theta_c)}, {exact_number(constants[3])}]; dtheta is an "
            "offset from theta_c and is not folded (pass theta, which is folded by the "
            "top's symmetries)"
        )
    if not from_offset:
        slack = _kernels.side_slack(theta_c, constants[3])
        raise SeparatrixError(
            f"theta = {exact_number(value)} is within the rounding error of theta_c = "
            f"{exact_number(theta_c)} (|theta - theta_c| <= {slack:.3g} rad): on the "
            "separatrix M^2 = 2 E I2 or too near it to tell its side (SAM or LAM) "
            "in double precision; pass the offset dtheta = theta - theta_crit instead"
        )
    raise SeparatrixError(
        f"dtheta = {exact_number(value)} puts the spin on the separatrix M^2 = 2 E I2 "
        f"(theta_c = {exact_number(theta_c)}), where the period and the total phase "
        "are infinite; pass a nonzero dtheta"
    )


@size_aware
def _fast_inputs(moments, theta, dtheta, phi):
    """The inputs of the in-kernel path: ``(from_offset, angle, phi, shape)``.

    ``angle`` is the polar angle *as given* (the kernels fold and check it,
    :func:`orbits.core.phase.given_angle`); ``phi`` is checked and folded here
    (usually a scalar).  ``None`` when any of these checks fails: the caller
    then runs :func:`_spin_inputs`, which raises the error (in the order of
    the reference path).
    """
    if (theta is None) == (dtheta is None):
        raise AngleError("give exactly one of theta and dtheta")
    from_offset = dtheta is not None
    name = "dtheta" if from_offset else "theta"
    angle = real_array(name, dtheta if from_offset else theta, AngleError)
    phi = real_array("phi", phi, AngleError)
    if phi.ndim == 0:
        value = float(phi)
        if not (math.isfinite(value) and abs(value) <= FOLD_LIMIT):
            return None
        phi = np.asarray(_angles.fold_one(value))
    else:
        if not np.all(np.isfinite(phi)):
            return None
        try:
            phi = fold_angle(phi)
        except AngleError:
            return None
    try:
        shape = np.broadcast_shapes(moments.shape[:-1], angle.shape, phi.shape)
    except ValueError:
        return None
    return from_offset, angle, phi, shape


def _refuse_folded_near_separatrix(moments, theta, phi, phi_folded, shape):
    """SeparatrixError where folding ``theta`` or ``phi`` could have moved the
    spin across the separatrix.

    A folded angle is correctly rounded (:func:`fold_angle`), but the
    reduced angle itself is not a double: near ``theta_c``, or near the I2
    axis (``theta, phi -> pi/2``), that half ulp can decide the branch, and
    the fold gave the wrong one silently (e.g. theta = pi/2 with phi one ulp
    above pi/2).  The side is the sign of ``f = sqrt(I3 (I3-I2)) cos theta -
    sqrt(I1 (I2-I1)) sin theta cos phi``, decreasing in theta and
    increasing in phi on ``[0, pi/2]``: it is refused where ``f`` over the
    box of folded angles +- 2 ulps (0 where not folded) can take either sign.
    Angles in ``[0, pi/2]`` are not folded and never refused here.
    """
    theta = np.asarray(theta, dtype=float)
    phi = np.asarray(phi, dtype=float)
    half_pi = 0.5 * np.pi
    moved = [
        (np.broadcast_to(a, shape) < 0.0) | (np.broadcast_to(a, shape) > half_pi)
        for a in (theta, phi)
    ]
    if not (moved[0].any() or moved[1].any()):
        return
    where = np.flatnonzero((moved[0] | moved[1]).ravel())
    raw = _flat(theta, shape)[where]
    theta_f = fold_angle(raw)
    phi_f = _flat(phi_folded, shape)[where]
    i1, i2, i3 = (_flat(moments[..., k], shape)[where] for k in range(3))
    a = np.sqrt(i3 * (i3 - i2))
    b = np.sqrt(i1 * (i2 - i1))
    d_theta = np.where(moved[0].ravel()[where], 2.0 * np.spacing(theta_f), 0.0)
    d_phi = np.where(moved[1].ravel()[where], 2.0 * np.spacing(phi_f), 0.0)

    def side(t, p):
        t, p = np.clip(t, 0.0, half_pi), np.clip(p, 0.0, half_pi)
        return a * np.cos(t) - b * np.sin(t) * np.cos(p)

    high = side(theta_f - d_theta, phi_f + d_phi)
    low = side(theta_f + d_theta, phi_f - d_phi)
    slack = 8.0 * np.finfo(float).eps * (a + b)
    bad = (low <= slack) & (high >= -slack)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        given_phi = float(_flat(phi, shape)[where[k]])
        raise SeparatrixError(
            f"theta = {exact_number(raw[k])}, phi = {exact_number(given_phi)} fold into "
            f"[0, pi/2] within the fold's rounding of the separatrix M^2 = 2 E I2 "
            "(its side, SAM or LAM, cannot be told); give theta and phi within "
            "[0, pi/2], or the offset dtheta"
        )


def _raise_for(status, moments, theta, dtheta, phi):
    """Raise the error of the reference path for inputs the kernels flagged."""
    from_offset, angle, phi, shape = _spin_inputs(moments, theta, dtheta, phi)
    _check_status(status, moments, angle, phi, shape, from_offset)
    raise AssertionError("a kernel flagged a point that the reference path accepts")


@size_aware
def total_phase(body_or_moments, theta=None, *, dtheta=None, phi=0.0, device="cpu"):
    """Total phase ``Delta alpha`` (eqn:GeometricPhase), radians.

    Parameters
    ----------
    body_or_moments : Body or array_like, shape (..., 3)
        Principal moments in any order and scale (sorted internally).
    theta : float or array_like, optional
        Polar angle of omega0 from the I3 axis, radians; any value with
        ``|theta| <= FOLD_LIMIT`` (2**21 rad), folded into [0, pi/2] by
        :func:`fold_angle`.
    dtheta : float or array_like, optional
        Offset ``theta - theta_c`` from the critical angle instead of
        ``theta``.  Near the separatrix the phase is ill-conditioned in
        ``theta`` (relative error ~ eps / |theta - theta_c|) but not in
        ``dtheta``: with ``dtheta`` the result keeps ~1e-15 relative
        accuracy down to ``|dtheta| = 1e-300``.
    phi : float or array_like
        Azimuth of omega0 from the I1 axis, radians (default 0); any
        value with ``|phi| <= FOLD_LIMIT``, folded into [0, pi/2].  The fold is rounded once: for
        ``phi`` outside [0, pi/2] near an odd multiple of pi/2 that half
        ulp is large beside ``cos phi``, and near the separatrix the result
        loses digits with it (1.4e-7 relative at ``phi = pi/2 + 1e-12``,
        ``dtheta = -1e-300``, against 1e-16 for ``phi = pi/2 - 1e-12``):
        give ``phi`` in [0, pi/2] there.
    device : {"cpu", "cuda"}
        Where the kernels run.  ``"cuda"`` needs an NVIDIA GPU and the
        ``orbits[cuda]`` extra; it evaluates the same scalar functions
        (one ``cel`` loop per point, :func:`orbits.core.phase.total_from_spin`)
        and agrees with the CPU path to within 1e-14 relative (on an NVIDIA
        H200: at most 2.4e-15 over 10^6 angles of the Fig. 6 body; NVVM
        fuses multiply-adds, so the last bits may differ).

    Returns
    -------
    ndarray
        ``Delta alpha``, broadcast over bodies and angles (NumPy
        broadcasting, by position: a pandas Series or DataFrame is taken as
        its values, its index neither aligned nor kept).  On SAM it is
        ``phi_Euler(T) - 2 pi``, on LAM ``phi_Euler(T)`` (eqn:alphaproto);
        the orientation after one period is ``Rot(M, Delta alpha) R(0)``.

    Raises
    ------
    NonPhysicalBodyError, SymmetricTopError
        Invalid moments.
    AngleError
        Angles NaN or infinite, ``|theta|`` or ``|phi|`` beyond
        ``FOLD_LIMIT`` (2**21 rad: too large to fold, see
        :func:`fold_angle`), both or neither of theta/dtheta given, or
        ``theta_c + dtheta`` outside [0, pi/2].
    SeparatrixError
        ``dtheta == 0``, or a ``theta`` within the rounding error of
        ``theta_c`` (``|theta - theta_c| <= 16 * 2**-53 * min(theta_c,
        pi/2 - theta_c)``): on the separatrix, or too near it for double
        precision to tell its branch; pass ``dtheta`` there.  Also a
        ``theta`` or ``phi`` outside ``[0, pi/2]`` whose fold (rounded once)
        could have moved the spin across the separatrix (near ``theta_c``,
        or near the I2 axis ``theta, phi -> pi/2``).
    DeviceError
        ``device`` not ``"cpu"``/``"cuda"``, or ``"cuda"`` unavailable (no
        GPU, no numba-cuda, or a numba-cuda that does not compile here).

    Notes
    -----
    Mecholsky's Eq. (20) (eqn:GeometricPhase): on SAM (:math:`M^2 > 2EI_2`)

    .. math::

        \\Delta\\alpha = \\frac{MT}{I_3} + \\frac{4M(I_3-I_1)}{I_1 I_3}\\,
        \\frac{\\Pi\\left(-\\frac{I_3(I_2-I_1)}{I_1(I_3-I_2)} \\,\\middle|\\, k^2\\right)}
        {\\sqrt{(I_3-I_2)(M^2-2EI_1)/(I_1I_2I_3)}} - 2\\pi ,

    with :math:`T` and :math:`k` of Eqs. (16a, b) (eqn:TK), and on LAM its
    image under :math:`1 \\leftrightarrow 3` with :math:`+2\\pi` in place of
    :math:`-2\\pi` (the plain image is :math:`\\Delta\\alpha - 4\\pi`: at the
    Fig. 6 body and :math:`\\theta = 1.2`, 1.25936 for 13.82573).
    :math:`I_1K + (I_3-I_1)\\Pi` is evaluated as one Bulirsch
    :math:`\\operatorname{cel}(k_c, p, a, b)` with :math:`k_c = \\sqrt{1-k^2}`
    formed from the factored separatrix distance, never as :math:`1 - m`
    (docs: Numerical methods).

    The checks (finite, range), the fold of ``theta`` and the clamp at
    ``2 pi`` (:func:`at_least_two_pi`) run inside the parallel kernels; only
    when a kernel flags a point is the error worked out on the host.
    """
    device = check_device(device)
    moments, _ = unit_moments(body_or_moments)
    gpu = cuda_kernels() if device == "cuda" else None
    inputs = _fast_inputs(moments, theta, dtheta, phi)
    if inputs is None:
        _spin_inputs(moments, theta, dtheta, phi)  # raises
        raise AssertionError("the reference checks accept inputs the fast checks refused")
    from_offset, angle, phi_folded, shape = inputs
    out = np.empty(shape)
    status = np.empty(shape, dtype=np.int8)
    if moments.ndim == 1 and phi_folded.ndim == 0:
        # one body: its constants are computed once, angles used in place
        args = (
            moments[0],
            moments[1],
            moments[2],
            float(phi_folded),
            np.ascontiguousarray(angle, dtype=float).reshape(-1),
        )
        kernel = gpu.total_phase_one_body if gpu else _kernels.total_phase_one_body
    else:
        args = (
            *(_flat(moments[..., k], shape) for k in range(3)),
            _flat(phi_folded, shape),
            _flat(angle, shape),
        )
        kernel = gpu.total_phase_many if gpu else _kernels.total_phase_many
    args = (*args, from_offset, FOLD_LIMIT, out.reshape(-1), status.reshape(-1))
    if gpu:
        run_cuda(kernel, *args)
    else:
        kernel(*args)
    if status.any():  # the rare case: the reference path names the error
        _raise_for(status, moments, theta, dtheta, phi)
    if not from_offset:
        _refuse_folded_near_separatrix(moments, angle, phi, phi_folded, shape)
    return out


def at_least_two_pi(total):
    """``Delta alpha`` raised to ``2 pi`` where below it by rounding alone, in place.

    Within ``TWO_PI_ROUNDING`` (``2**-40``, relative) below ``2 pi``; a
    value further below is kept (as :func:`orbits.core.phase.at_least_two_pi`).

    ``Delta alpha >= 2 pi`` at both ends of every branch of every physical
    body (eqns alphamin1/2 with the triangle inequalities), with ``2 pi``
    only the limit theta -> 0 on the flat edge ``I3 = I1 + I2``
    (eqn:alphamin1 with ``I3 - I2 = I1``); there rounding can land a few
    ulp below, which would read as an orbit closing after one turn.  In
    between it rests on the paper's conjecture that the minimum lies at an
    end, which the surveys test on every body and
    :func:`orbits.minimum_phase` checks by a full scan (the search kernels
    themselves evaluate the phase unclamped).
    """
    two_pi = 2.0 * np.pi
    rounding = (total < two_pi) & (total >= two_pi * (1.0 - _kernels.TWO_PI_ROUNDING))
    total[rounding] = two_pi
    return total


@size_aware
def phases(body_or_moments, theta=None, phi=0.0, *, dtheta=None, device="cpu"):
    """Closed-form phases and their ingredients, one row per initial spin.

    Parameters are as for :func:`total_phase` (``device`` included: on
    ``"cuda"`` every column is computed on the GPU by the same scalar
    functions: within 4 ulps of the CPU path on numba's CUDA simulator; on
    hardware fused multiply-adds move the last bits, as for
    :func:`total_phase`, which is the one measured there).

    Returns
    -------
    pandas.DataFrame
        Columns, all in the paper's normalisation ``|I| = 1`` and
        ``|omega0| = 1`` (the ``I1, I2, I3`` columns are the normalised
        moments, and ``energy``, ``momentum``, ``D`` are for them; see
        :func:`spin_phases` for the moments and spin as given):

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
        ``D``
            ``M^2 / (2E)``, the orbit's label independent of ``|omega0|``,
            in the units of the moments (here ``|I| = 1``):
            ``I1 <= D <= I3``, ``D > I2`` on SAM, ``D < I2`` on LAM
            (Landau & Lifshitz, Mechanics, Sec. 37);
        ``m``
            elliptic parameter k^2 of eqn:TK (indices 1<->3 on LAM);
        ``period``
            T of eqn:TK, in units of 1/|omega0|;
        ``dynamic_phase``
            2ET/M;
        ``total_phase``
            Delta alpha, eqn:GeometricPhase;
        ``geometric_phase``
            Omega = 2ET/M - Delta alpha (eqn:montgomery), the signed solid
            angle of the polhode, from the cancellation-free closed form of
            :mod:`orbits.core.solid_angle` (relative error ~1e-15, also near
            the sphere, the axes and the separatrix).  Near an axis give
            ``theta``: ``theta_c + dtheta`` is rounded to ulp(theta_c), and
            Omega ~ theta^2 there.

    Raises
    ------
    As :func:`total_phase`.
    """
    device = check_device(device)
    return phases_of_unit_moments(
        unit_moments(body_or_moments)[0], theta, phi, dtheta=dtheta, device=device
    )


@size_aware
def phases_of_unit_moments(moments, theta=None, phi=0.0, *, dtheta=None, device="cpu"):
    """:func:`phases` for moments already in the canonical form of
    :func:`orbits.bodies.unit_moments` (no second normalisation: the
    catalog and survey pass their roots here)."""
    import pandas as pd

    gpu = cuda_kernels() if check_device(device) == "cuda" else None
    inputs = _fast_inputs(moments, theta, dtheta, phi)
    if inputs is None:
        _spin_inputs(moments, theta, dtheta, phi)  # raises
        raise AssertionError("the reference checks accept inputs the fast checks refused")
    from_offset, angle, phi_folded, shape = inputs
    # one body or one azimuth: length-1 arrays, broadcast inside the kernel
    i1, i2, i3 = (
        moments[k : k + 1] if moments.ndim == 1 else _flat(moments[..., k], shape)
        for k in range(3)
    )
    phi_flat = phi_folded.reshape(1) if phi_folded.ndim == 0 else _flat(phi_folded, shape)
    angle_flat = _flat(angle, shape)
    n = angle_flat.shape[0]
    columns = np.empty((len(_table.COLUMNS), n))
    branch = np.empty(n, dtype=np.int8)
    status = np.empty(n, dtype=np.int8)
    args = (i1, i2, i3, phi_flat, angle_flat, from_offset, FOLD_LIMIT, columns, branch, status)
    if gpu:
        run_cuda(gpu.phases_columns, *args)
    else:
        _table.phases_columns(*args)
    if status.any():  # the rare case: the reference path names the error
        _raise_for(status.reshape(shape), moments, theta, dtheta, phi)
    if not from_offset:
        _refuse_folded_near_separatrix(moments, angle, phi, phi_folded, shape)
    # every column computed in the kernel (phase_table.phases_row): the
    # frame only wraps them
    table = dict(zip(_table.COLUMNS, columns))
    table["branch"] = pd.Categorical.from_codes(branch, categories=["SAM", "LAM"])
    return pd.DataFrame({name: table[name] for name in PHASES_COLUMNS}, copy=False)


# the columns of phases(): the kernel's float columns, with "branch" after theta_crit
PHASES_COLUMNS = _table.COLUMNS[:7] + ("branch",) + _table.COLUMNS[7:]


def _parts_columns(norm, two_e, m_sq, m_param, branch, period, dynamic, total, geometric):
    """The columns shared by :func:`phases` and :func:`spin_phases`."""
    import pandas as pd

    return {
        "branch": pd.Categorical.from_codes(
            (branch < 0).astype(np.int8), categories=["SAM", "LAM"]
        ),
        "energy": 0.5 * two_e / norm,
        "momentum": np.sqrt(m_sq) / norm,
        # D = M^2/(2E): the same for every |omega|; I1 <= D <= I3 in the row's moments
        "D": m_sq / (two_e * norm),
        "m": m_param,
        "period": period,
        "dynamic_phase": dynamic,
        "total_phase": at_least_two_pi(total),
        "geometric_phase": geometric,
    }


def phase_limits(body_or_moments):
    """Limits of ``Delta alpha`` as theta -> 0 and theta -> pi/2 (phi = 0).

    Near either axis the polhode shrinks to a point, the geometric phase
    vanishes and the total phase is all dynamic.  Linearising Euler's
    equations gives eqn:alphamin1 and eqn:alphamin2 (the paper labels both
    ``alpha_min,z``; the second is the limit at the I1, i.e. x, axis).

    Parameters
    ----------
    body_or_moments : Body or array_like, shape (..., 3)
        Bodies (moments in any order and scale).

    Returns
    -------
    PhaseLimits
        ``(theta_zero, theta_half_pi)``, each broadcast over bodies.
        Both exceed 2 pi for every physical body: the triangle
        inequalities give ``I3 - I2 <= I1`` and ``I3 - I1 <= I2``.

    Notes
    -----
    Mecholsky's Eqs. (28) and (29) (eqn:alphamin1, eqn:alphamin2):

    .. math::

        \\lim_{\\theta\\to0}\\Delta\\alpha = 2\\pi\\sqrt{\\frac{I_1I_2}{(I_3-I_2)(I_3-I_1)}},
        \\qquad
        \\lim_{\\theta\\to\\pi/2}\\Delta\\alpha = 2\\pi\\sqrt{\\frac{I_3I_2}{(I_2-I_1)(I_3-I_1)}} .

    The first equals :math:`2\\pi` exactly on the flat edge
    :math:`I_3 = I_1 + I_2` (erratum 7).
    """
    moments, _ = unit_moments(body_or_moments)
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
        along (I1, I2, I3) sorted ascending, any direction, any magnitude
        whose energy, momentum, ``D`` and period fit a normal double (use
        :attr:`Body.frame` to convert from your own axes).

    Returns
    -------
    pandas.DataFrame
        Columns ``I1, I2, I3`` (the moments as given, sorted) and ``w1, w2,
        w3`` (the spin as given) followed by ``branch, energy, momentum, D,
        m, period, dynamic_phase, total_phase, geometric_phase`` as in
        :func:`phases`, but for the moments and the spin *as given*, like
        :class:`orbits.Motion`: with moments in kg m^2 and omega in rad/s,
        ``energy`` is in J, ``momentum`` in J s, ``D = M^2/(2E)`` in kg m^2
        and ``period`` in s.  (Energy scales as ``|omega|^2`` and ``|I|``,
        momentum as ``|omega| |I|``, D as ``|I|`` only, the period as
        ``1/|omega|`` only; the phases not at all.)

    Raises
    ------
    NonPhysicalBodyError, SymmetricTopError
        Invalid moments.
    AngleError
        ``omega`` not finite, or zero.
    InputError
        The energy, momentum, ``D`` or period of a row does not fit a
        normal double (``|omega|`` or the moments too large or too small,
        e.g. ``|omega| ~ 1e155`` with moments of order 1, or a period of
        1.3e309 for moments ~1e308 and ``|omega| ~ 2e-308``).
    SeparatrixError
        ``M^2 == 2 E I2`` to rounding (including a spin exactly along I2).

    Notes
    -----
    A vector knows its distance from the separatrix only to rounding, so
    near it this path is ill-conditioned (as the ``theta`` path of
    :func:`total_phase`); use ``dtheta`` there.
    """
    import pandas as pd

    moments, exponent = unit_moments(body_or_moments)
    omega = real_array("omega", omega, AngleError)
    if omega.ndim == 0 or omega.shape[-1] != 3:
        raise AngleError(f"omega must have shape (..., 3), got {omega.shape}")
    if not np.all(np.isfinite(omega)):
        raise AngleError(f"omega must be finite, got {_first_bad(omega)}")
    shape = broadcast([("moments", moments.shape[:-1]), ("omega", omega.shape[:-1])])
    cols = [
        np.ascontiguousarray(np.broadcast_to(a[..., k], shape), dtype=float).ravel()
        for a in (moments, omega)
        for k in range(3)
    ]
    i1, i2, i3, w1, w2, w3 = cols
    if np.any((w1 == 0.0) & (w2 == 0.0) & (w3 == 0.0)):
        raise AngleError("omega must be nonzero")
    # |omega| scaled by an exact power of two into [1/2, 1): the phases do not
    # depend on it, and no square under- or overflows (omega = 1e-200 is fine)
    # (the kernels scale; the separatrix gap from the components as given,
    # since halving a subnormal component rounds it)
    _, speed = np.frexp(np.maximum(np.maximum(np.abs(w1), np.abs(w2)), np.abs(w3)))
    speed = speed.astype(np.int64)
    parts = np.empty((i1.shape[0], 7))
    _kernels.parts_from_vector_array(i1, i2, i3, w1, w2, w3, speed, parts)
    two_e, m_sq, m_param, branch, period, dynamic, total = parts.T
    geometric = np.empty(i1.shape[0])
    _solid.solid_angle_from_vector_array(i1, i2, i3, w1, w2, w3, speed, geometric)
    if np.any(branch == 0):
        k = int(np.flatnonzero(branch == 0)[0])
        raise SeparatrixError(
            f"omega = {numbers_label('', (w1[k], w2[k], w3[k]))} lies on the "
            f"separatrix M^2 = 2 E I2 (infinite period and phase), {TOO_NEAR_SEPARATRIX}"
        )
    # E, M and D for the moments and the spin *as given* (as Motion): the
    # kernel saw unit moments (times 2**-exponent) and a unit-scale spin
    # (times 2**-speed), both exact; Euler's equations are homogeneous, so
    # E ~ |I| |omega|^2, M ~ |I| |omega|, D ~ |I|, T ~ 1/|omega|.  A value
    # that over- or underflows is refused rather than rounded to 0 or inf.
    exponent = np.broadcast_to(exponent, shape).ravel()
    columns = _parts_columns(1.0, two_e, m_sq, m_param, branch, period, dynamic, total, geometric)
    for label, power in (
        ("energy", exponent + 2 * speed),
        ("momentum", exponent + speed),
        ("D", exponent),
        ("period", -speed),
    ):
        with np.errstate(over="ignore", under="ignore"):
            value = np.ldexp(columns[label], power)
        wrong = ~np.isfinite(value) | (value < np.finfo(float).tiny)
        if wrong.any():
            k = int(np.flatnonzero(wrong)[0])
            raise InputError(
                f"omega = {numbers_label('', (w1[k], w2[k], w3[k]))}: its {label} "
                "does not fit a normal double (|omega| or the moments too large or too "
                "small); the phases do not depend on |omega|: pass a unit spin"
            )
        columns[label] = value
    given = [np.ldexp(i, exponent) for i in (i1, i2, i3)]
    return pd.DataFrame(
        {
            "I1": given[0],
            "I2": given[1],
            "I3": given[2],
            # copies: the columns were read-only views of the caller's omega
            "w1": w1.copy(),
            "w2": w2.copy(),
            "w3": w3.copy(),
            **columns,
        },
        copy=False,  # one block per column: no consolidating copy
    )
