"""Independent checks of the closed-form total phase, and ``orbits verify``.

The paper checks eqn:GeometricPhase three ways; so does this module, each
way sharing no formula with the closed form it checks:

(a) :func:`rotation_by_integration` -- Euler's equations and quaternion
    kinematics integrated numerically (``scipy.integrate.solve_ivp``,
    DOP853, or the compiled DOP853 of :mod:`orbits.core.ode`).  The period
    is found by the integration itself (omega returning to omega0); after it
    the orientation must differ from the start by a rotation about M by
    ``Delta alpha`` mod 2 pi.
(b) :func:`montgomery` -- Montgomery's ``2ET/M - Omega`` with the period and
    the solid angle Omega enclosed by the polhode computed by quadrature
    along the polhode from the two invariants (no elliptic functions);
    Omega's sign by the right-hand rule.
(c) :func:`motion_phase` -- ``phi(T)`` of the exact motion (Carlson's R_J
    for the incomplete Pi of eqn:fullphi), against the Bulirsch ``cel`` of
    the closed form.

:func:`verify` runs all three over the paper's 6446 initial conditions
(293 bodies x 22 angles, or more) and reports the largest discrepancy of
each; it also checks that the closed form of the exact theta (the orbit
``total_phase`` and ``phases`` take) agrees with that of the double
omega0 the three checks start from, within the rounding of omega0, and
that the closed form as the public functions compute it
(``total_phase``'s SIMD kernels, ``phases``, the table of ``orbits
phase``, and ``spin_phases``) agrees with the closed form of its orbit.
"""

import math
from collections import namedtuple

import numpy as np
import pandas as pd
from scipy.integrate import solve_ivp

from ._args import broadcast, held_warnings, integer, positive_finite, real_array, real_scalar
from .bodies import region_sample, unit_moments
from .core import checks as _checks
from .core import phase as _phase
from .core.ode import STATE_SIZE, euler_rhs
from .errors import AngleError, ArgumentTypeError, InputError, OrbitsError
from .limits import (
    GAP_ROUNDING_FACTOR,
    ODE_ERROR_FACTOR,
    PHASE_ULPS,
    ROUTE_ULPS,
    VERIFY_ODE_RTOL,
    check_verify_size,
)
from .motion import Motion, as_body
from .threads import threads_for

TOLERANCE = 1e-9
# longest closure check: q periods integrated at rtol 1e-13
MAX_CLOSURE_PERIODS = 100_000
TWO_PI = 2.0 * np.pi
# the integration tolerances rotation_by_integration accepts: SciPy raises an
# rtol below 100 eps to 100 eps itself (with a warning), and the compiled
# DOP853 at rtol = atol = 1e-300 takes minutes of steps that cannot be
# interrupted; SciPy's error norm squares err/atol, which overflows (NaN,
# no result) for atol below ~1e-160 (measured: 1e-160 worked, 1e-200 not)
ODE_RTOL_RANGE = (100.0 * np.finfo(float).eps, 1e-3)
ODE_ATOL_RANGE = (1e-100, 1e-3)
MONTGOMERY_RTOL_RANGE = (_checks.MONTGOMERY_RTOL_MIN, _checks.MONTGOMERY_RTOL_MAX)
ENGINES = ("scipy", "compiled")

RotationCheck = namedtuple("RotationCheck", ["period", "angle", "off_axis", "expected", "error"])
RotationCheck.__doc__ = """Result of :func:`rotation_by_integration`.

period : time between returns of omega to omega0 (from the integration)
angle : rotation about M after ``periods`` periods, in [0, 2 pi)
off_axis : size (radians) of the part of that rotation not about M
expected : ``periods * Delta alpha`` mod 2 pi from the closed form
error : max(circular |angle - expected|, off_axis)
"""

MontgomeryCheck = namedtuple(
    "MontgomeryCheck", ["total_phase", "dynamic_phase", "solid_angle", "period"]
)


def _unit_motion(body_or_moments, theta, dtheta, phi):
    body = as_body(body_or_moments)
    return Motion.from_spin(body, theta, dtheta=dtheta, phi=phi)


def _spin_and_gap(body_or_moments, theta, dtheta, phi):
    """The unit moments, the unit spin and its separatrix gap, factored.

    The spin is that of :meth:`Motion.from_spin` (which validates the
    arguments); ``M^2 - 2 E I2 = -scale * offset * closing`` is the gap of
    the orbit as :func:`orbits.total_phase` takes it: from the exact offset
    of ``theta`` or ``dtheta`` from theta_c (a double omega0 cannot hold a
    separatrix distance below ~1e-16), or, for a spin that is not built
    from them that way (a ``theta`` outside [0, pi/2], taken as given), the
    exact gap of the double omega0.
    """
    motion = _unit_motion(body_or_moments, theta, dtheta, phi)
    unit = tuple(float(v) for v in motion.body.unit_moments)
    omega = tuple(float(v) for v in motion.omega0)
    from_offset = dtheta is not None
    angle = real_scalar("dtheta" if from_offset else "theta", dtheta if from_offset else theta)
    code, _, _, _, w1, w2, w3, scale, offset, closing = _phase.spin_from_angle(
        _phase.body_constants(*unit, real_scalar("phi", phi)), angle, from_offset
    )
    if code == _phase.STATUS_OK and (w1, w2, w3) == omega:
        return unit, omega, (scale, offset, closing)
    return unit, omega, _phase.vector_gap(*unit, *omega)


def _bounded(name, value, bounds, what):
    """A real number within ``bounds`` (inclusive), or an error naming ``name``."""
    number = real_scalar(name, value)
    low, high = bounds
    if not (math.isfinite(number) and low <= number <= high):
        raise InputError(
            f"{name} must be a number from {low:.3g} to {high:g} ({what}), got {number!r}"
        )
    return number


def circular_distance(a, b):
    """|a - b| on the circle, in [0, pi] (radians; NaN where either is not finite)."""
    a, b = real_array("a", a), real_array("b", b)
    with np.errstate(invalid="ignore"):
        d = np.mod(a - b, TWO_PI)
    return np.minimum(d, TWO_PI - d)


def rotation_by_integration(
    body_or_moments,
    theta=None,
    *,
    dtheta=None,
    phi=0.0,
    periods=1,
    rtol=1e-12,
    atol=1e-14,
    engine="scipy",
):
    """Check (a): integrate Euler's equations and the orientation.

    Parameters
    ----------
    body_or_moments, theta, dtheta, phi
        The orbit, as in :func:`orbits.total_phase`.
    periods : int
        Number of periods to integrate (the rotation is then ``periods``
        times ``Delta alpha``), 1 to :data:`MAX_CLOSURE_PERIODS`.
    rtol, atol : float
        Integration tolerances (default 1e-12 and 1e-14): ``rtol`` from
        100 eps (2.2e-16 x 100, SciPy's own floor) to 1e-3, ``atol`` from
        1e-100 to 1e-3 (:data:`ODE_RTOL_RANGE`, :data:`ODE_ATOL_RANGE`).
    engine : {"scipy", "compiled"}
        ``solve_ivp(method="DOP853")`` with a terminal event, or the
        compiled DOP853 (same method, used by :func:`verify`).

    Returns
    -------
    RotationCheck
        ``period`` (found by the integration), ``angle`` (the rotation about
        M after ``periods`` periods, radians in [0, 2 pi)), ``off_axis`` (the
        part of the rotation not about M), ``expected`` (the closed form,
        mod 2 pi) and ``error`` (the larger of the two differences).

    Raises
    ------
    InputError
        ``engine``, ``periods``, ``rtol`` or ``atol`` out of range (checked
        before any integration), or
        the integration cannot reach the end of the last period: beyond
        10,000 turns of omega with ``engine="scipy"`` (refused before it
        starts), or beyond the compiled engine's 10^7 steps (a nearly
        symmetric body, or a spin very near the separatrix); ``omega0``
        along a principal axis, or with a component (at ``|omega0| = 1``)
        below the smallest normal double, 2.2e-308 (a subnormal keeps a
        few bits: the integration followed a wobble of the wrong size).

    Notes
    -----
    Euler's equations (Mecholsky's Eqs. 15a-c) and the attitude,
    :math:`\\dot R = R\\,[\\boldsymbol\\omega]_\\times`, integrated by DOP853;
    after one period :math:`R(T)R(0)^{\\mathsf T}` must be the rotation by
    :math:`\\Delta\\alpha` about :math:`\\mathbf M` (Eq. 19).

    Examples
    --------
    The paper's T-handle spin: 21.5303 rad, 2.68074 mod 2 pi.

    >>> import numpy as np, orbits
    >>> check = orbits.rotation_by_integration(
    ...     orbits.Body.preset("t-handle"), np.pi / 2 - 0.15, phi=np.pi / 2 - 0.2
    ... )
    >>> round(check.angle, 5), bool(check.error < 1e-9)
    (2.68074, True)
    """
    if not isinstance(engine, str) or engine not in ENGINES:
        raise InputError(f"engine must be 'scipy' or 'compiled', got {engine!r}")
    periods = integer("periods", periods, minimum=1, maximum=MAX_CLOSURE_PERIODS)
    rtol = _bounded("rtol", rtol, ODE_RTOL_RANGE, "relative tolerance of DOP853")
    atol = _bounded("atol", atol, ODE_ATOL_RANGE, "absolute tolerance of DOP853")
    motion = _unit_motion(body_or_moments, theta, dtheta, phi)
    # scale-free with |omega0| = 1 (period, angles, phases), and the
    # kernels' products neither underflow nor overflow at any scale
    i1, i2, i3 = (float(v) for v in motion.body.unit_moments)
    w = motion.omega0
    if np.count_nonzero(w) == 1:
        axis = ("I1", "I2", "I3")[int(np.flatnonzero(w)[0])]
        raise InputError(
            f"rotation_by_integration: omega0 lies along the principal axis {axis}: a "
            "steady rotation, whose omega never leaves omega0, has no period for the "
            "integration to find (the closed form gives its limit, as theta -> 0 or "
            "pi/2); take a spin off the axis"
        )
    tiny = (w != 0.0) & (np.abs(w) < np.finfo(float).tiny)
    if tiny.any():
        # a subnormal component keeps a few bits: the integration follows a
        # wobble of the wrong size (theta = 5e-324: the period 0.0123 found
        # for 6.589, an error of 0.29 reported against a right closed form)
        axis = ("I1", "I2", "I3")[int(np.argmax(np.abs(w)))]
        raise InputError(
            f"rotation_by_integration: omega0 = {w.tolist()} (|omega0| = 1) has a "
            "component below the smallest normal double (2.2e-308), which keeps only a "
            f"few bits: too near the axis {axis} for the integration to follow (the "
            "closed form and check (c), the exact motion, still apply)"
        )
    expected = np.mod(periods * motion_closed_form(motion), TWO_PI)
    # the closed-form period (|omega0| = 1) bounds the work: turns of omega
    closed_period = float(motion.period) / float(np.linalg.norm(w))
    turns = int(periods) * closed_period / TWO_PI
    beyond = (
        f"(closed-form period {closed_period:.6g} in units of 1/|w0|: a nearly "
        "symmetric body or a spin very near the separatrix); check (b), "
        "orbits.montgomery, and check (c), the exact motion, still apply"
    )
    if engine == "scipy" and turns > _SCIPY_TURNS:
        raise InputError(
            f"rotation_by_integration: {int(periods)} period(s) are {turns:.3g} turns of "
            f"omega, beyond the {_SCIPY_TURNS:,} that engine='scipy' integrates in "
            f"reasonable time {beyond}; engine='compiled' takes up to "
            f"{_checks.ODE_MAX_STEPS:,} steps"
        )
    if engine == "compiled":
        period, angle, off_axis = _checks.rotation_after_periods(
            i1, i2, i3, w[0], w[1], w[2], periods, rtol, atol, _checks.ODE_MAX_STEPS
        )
    else:
        span = 2.0 * int(periods) * closed_period + TWO_PI
        period, angle, off_axis = _rotation_scipy((i1, i2, i3), w, int(periods), rtol, atol, span)
    if not (np.isfinite(angle) and np.isfinite(off_axis)):
        budget = (
            f"within {_checks.ODE_MAX_STEPS:,} steps"
            if engine == "compiled"
            else "within twice its closed-form length"
        )
        raise InputError(
            f"rotation_by_integration: the integration did not reach the end of period "
            f"{int(periods)} {budget} {beyond}"
        )
    error = max(float(circular_distance(angle, expected)), off_axis)
    # Python floats from either engine (scipy's gave period as np.float64)
    return RotationCheck(
        float(period), float(angle), float(off_axis), float(expected), float(error)
    )


def motion_closed_form(motion):
    """The closed-form Delta alpha (eqn:GeometricPhase) for a :class:`Motion`."""
    from .phases import spin_phases

    return float(spin_phases(motion.body, motion.omega0)["total_phase"].iloc[0])


# the most turns of omega ``rotation_by_integration(engine="scipy")`` takes on
# (solve_ivp steps in Python: 1,229 turns took 2.9 s on a 2-core EPYC VM, so
# the limit is about 25 s; the compiled engine is ~80x faster)
_SCIPY_TURNS = 10_000


def _rotation_scipy(moments, omega0, periods, rtol, atol, span):
    """solve_ivp(DOP853) over [0, span] with a terminal event at the ``periods``-th return."""
    inertia = np.asarray(moments, dtype=float)
    y0 = np.concatenate([omega0, [1.0, 0.0, 0.0, 0.0]])

    def rhs(t, y):
        dy = np.empty(STATE_SIZE)
        euler_rhs(inertia, y, dy)
        return dy

    component, direction = _checks.return_event(*inertia, *omega0)
    if direction == 0.0:
        return np.nan, np.nan, np.nan
    target = y0[component]

    def event(t, y):
        return y[component] - target

    event.direction = direction
    # SciPy counts a zero at the very start as a crossing: ask for one more
    event.terminal = periods + 1
    solution = solve_ivp(rhs, (0.0, span), y0, method="DOP853", rtol=rtol, atol=atol, events=event)
    times = solution.t_events[0]
    states = solution.y_events[0]
    keep = times > 0.0
    times, states = times[keep], states[keep]
    if times.size < periods:
        return np.nan, np.nan, np.nan
    angle, off_axis = _checks.rotation_about_momentum(states[periods - 1][3:], *inertia, *omega0)
    return times[periods - 1] / periods, float(angle), float(off_axis)


def montgomery(body_or_moments, theta=None, *, dtheta=None, phi=0.0, rtol=1e-14):
    r"""Check (b): ``2ET/M - Omega`` with T and Omega by quadrature.

    Parameters
    ----------
    body_or_moments : Body or array_like, shape (3,)
        Principal moments, any order and scale.
    theta, dtheta, phi : float
        The spin direction as in :func:`orbits.total_phase` (radians; one of
        ``theta`` and ``dtheta``), with :math:`|\boldsymbol\omega_0| = 1`.
        The orbit is the one :func:`orbits.total_phase` evaluates: its
        separatrix distance comes from the exact offset of ``theta`` (or
        ``dtheta``) from the critical angle, not from the rounded omega0,
        so ``dtheta`` down to 1e-300 (and below) is resolved.
    rtol : float
        Relative tolerance of the adaptive Gauss-Legendre quadratures, from
        1e-15 to 1e-3 (:data:`MONTGOMERY_RTOL_RANGE`).

    Returns
    -------
    MontgomeryCheck
        ``total_phase = dynamic_phase - solid_angle``; ``solid_angle`` is
        signed by the right-hand rule (positive on SAM, negative on LAM).
        For the T-handle spin of the paper it is 2.12519.  All in radians,
        ``period`` in units of :math:`1/|\boldsymbol\omega_0|`.

    Raises
    ------
    AngleError, SeparatrixError, NonPhysicalBodyError, SymmetricTopError
        As :func:`orbits.total_phase`.
    InputError
        ``rtol`` out of range (checked before the quadrature starts), or the
        quadrature did not converge within its budget of panels.

    Notes
    -----
    Montgomery's formula, Mecholsky's Eq. (1) (eqn:montgomery),

    .. math::

        \Delta\alpha = \frac{2ET}{M} - \Omega ,

    with the period :math:`T` and the solid angle :math:`\Omega` enclosed by
    the polhode both found by quadrature along the polhode, parameterised by
    the azimuth's distance from the polhode's I2 side (where the integrands
    change on the scale of the separatrix distance, and near the thin-rod
    corner on the scale of the small moment difference; the panels are
    graded geometrically down to both): no elliptic function is used, so the
    check shares no formula with the closed form of Eq. (20).  Against
    mpmath it agrees to a few 1e-16 relative for ``|dtheta|`` from 1e-10 to
    1e-320 and for rods ``(eps, 1, 1 + eps)`` down to ``eps = 1e-15``
    (tests/test_checks.py, docs/checks.md).

    Examples
    --------
    >>> import numpy as np, orbits
    >>> body = orbits.Body.preset("t-handle")
    >>> check = orbits.montgomery(body, np.pi / 2 - 0.15, phi=np.pi / 2 - 0.2)
    >>> round(check.total_phase, 4), round(check.solid_angle, 5)
    (21.5303, 2.12519)
    """
    rtol = _bounded("rtol", rtol, MONTGOMERY_RTOL_RANGE, "relative tolerance of the quadrature")
    # scale-free with |omega0| = 1 (period, angles, phases), and the
    # kernels' products neither underflow nor overflow at any scale
    unit, omega, gap = _spin_and_gap(body_or_moments, theta, dtheta, phi)
    total, dynamic, solid, period, _ = _checks.montgomery_phase(*unit, *omega, *gap, rtol)
    if not (math.isfinite(total) and math.isfinite(period)):
        raise InputError(
            f"montgomery: the quadrature did not converge to rtol {rtol:g} within "
            f"{_checks.MONTGOMERY_MAX_PANELS:,} panels; give a larger rtol"
        )
    return MontgomeryCheck(total, dynamic, solid, period)


def motion_phase(body_or_moments, theta=None, *, dtheta=None, phi=0.0):
    """Check (c): ``phi(T) - 2 pi`` (SAM) or ``phi(T)`` (LAM) from the exact motion.

    The Euler angle :math:`\\phi` of :class:`orbits.Motion` (Mecholsky's
    Eq. A12, with Carlson's :math:`R_J`) after one period, per Eq. (19);
    radians.

    Parameters
    ----------
    body_or_moments : Body or array_like, shape (3,)
        One body (moments in any order and scale).
    theta : float, optional
        Polar angle of omega0 from the I3 axis, radians (folded as
        :func:`orbits.total_phase` folds it).  Give ``theta`` or ``dtheta``.
    dtheta : float, optional
        The offset ``theta - theta_c`` from the separatrix instead, radians,
        nonzero (negative on SAM, positive on LAM).
    phi : float
        Azimuth of omega0 from the I1 axis, radians; default 0.

    Returns
    -------
    float
        Radians; equal to :func:`orbits.total_phase` of the same spin
        (an independent evaluation: the motion's Euler angle).

    Examples
    --------
    >>> import numpy as np, orbits
    >>> body = orbits.Body.preset("t-handle")
    >>> round(orbits.motion_phase(body, np.pi / 2 - 0.15, phi=np.pi / 2 - 0.2), 4)
    21.5303
    """
    return _unit_motion(body_or_moments, theta, dtheta, phi).total_phase()


def closure_errors(moments, dtheta, periods, rtol=1e-13):
    """Independent integration check of closed orbits (``catalog --verify``).

    Parameters
    ----------
    moments : array_like, shape (n, 3) or (3,)
        Principal moments (any order, any scale).
    dtheta : float or array_like, shape (n,)
        Offsets from the critical angle (phi = 0), finite and nonzero.
    periods : int or array_like of int, shape (n,)
        After how many periods each orbit should close (the catalog's q),
        1 to :data:`MAX_CLOSURE_PERIODS`.
    rtol : float
        Integration tolerance, from 100 eps (2.2e-14) to 1e-3
        (:data:`ODE_RTOL_RANGE`; at 1e-300 the integration near the
        separatrix did not finish).

    Returns
    -------
    float or ndarray, shape (n,)
        A float for one orbit given as scalars (moments of shape (3,),
        scalar ``dtheta`` and ``periods``), else one entry per orbit.
        The angle (radians) by which the orientation after ``q`` periods
        differs from the start.  For ``|dtheta| >= 1e-3``: Euler's equations
        with quaternion kinematics integrated (compiled DOP853) over the q
        periods from omega0, the angle of ``R(qT) R(0)^-1``.  Closer to the
        separatrix a double omega0 cannot hold the orbit, and the phase of a
        period comes from a quarter period integrated from the orbit's
        closest approach to the I2 axis (exact reversibility of Euler's
        equations makes the four quarters equal); the angle is then
        ``|q Delta alpha|`` reduced to [0, pi].  That path's own error is
        about ``rtol * (I3/I1) * q`` (:func:`closure_error_budget`): for a
        thin rod it, not the orbit, can exceed a tolerance of 1e-8.

    Examples
    --------
    >>> import orbits
    >>> rows = orbits.closed_orbits(orbits.Body.preset("fig6"), n_max=3)
    >>> errors = orbits.closure_errors(
    ...     rows[["I1", "I2", "I3"]].to_numpy(), rows["dtheta"].to_numpy(), rows["q"].to_numpy()
    ... )
    >>> bool((errors < 1e-10).all())
    True

    Raises
    ------
    NonPhysicalBodyError, SymmetricTopError
        Invalid moments.
    AngleError
        ``dtheta`` not finite, zero, or outside the range of theta.
    InputError
        ``periods`` not integers in range, ``rtol`` out of range, shapes
        that do not match.
    """
    moments, dtheta, periods, rtol, scalar = _closure_arguments(moments, dtheta, periods, rtol)
    out = np.full(dtheta.shape, np.nan)  # an unwritten entry reads as NaN (refused)
    with threads_for(out.size, serial_below=2):
        _checks.closure_batch(
            np.ascontiguousarray(moments),
            np.ascontiguousarray(dtheta),
            np.ascontiguousarray(periods),
            rtol,
            out,
        )
    bad = ~np.isfinite(out)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise AngleError(
            f"dtheta = {float(dtheta[k])!r} puts theta outside [0, pi/2] for the "
            f"body {moments[k].tolist()} (unit scale)"
        )
    return float(out[0]) if scalar else out


def _closure_arguments(moments, dtheta, periods, rtol):
    """The checked arguments of :func:`closure_errors`, broadcast to one row per orbit.

    The fifth value says whether the call was for one orbit given as
    scalars (moments (3,), scalar dtheta and periods): its answer is a float.
    """
    dtheta = real_array("dtheta", dtheta, AngleError)
    scalar = dtheta.ndim == 0
    dtheta = np.atleast_1d(dtheta)
    if not np.all(np.isfinite(dtheta)) or np.any(dtheta == 0.0):
        raise AngleError("dtheta must be finite and nonzero (0 is the separatrix)")
    with held_warnings():  # dropped (not catch_warnings: not thread-safe)
        # a closure depends on the phases only, which a rod moved onto the
        # flat edge keeps (and a catalog's |I| = 1 moments of one moved
        # already would be reported a second time)
        moments, _ = unit_moments(moments)
    periods = real_array("periods", periods)
    scalar = scalar and periods.ndim == 0 and moments.ndim == 1
    if (
        not np.all(np.isfinite(periods))
        or np.any(periods != np.round(periods))
        or np.any(periods < 1)
        or np.any(periods > MAX_CLOSURE_PERIODS)
    ):
        raise InputError(
            f"periods (the catalog's q) must be integers from 1 to "
            f"{MAX_CLOSURE_PERIODS}, got {periods.ravel()[:5].tolist()}"
        )
    rtol = _bounded("rtol", rtol, ODE_RTOL_RANGE, "relative tolerance of DOP853")
    shape = broadcast(
        [("moments", moments.shape[:-1]), ("dtheta", dtheta.shape), ("periods", periods.shape)]
    )
    if len(shape) != 1:
        raise InputError(
            f"closure_errors takes one row per orbit: moments (n, 3) or "
            f"(3,), dtheta and periods (n,), got broadcast shape {shape}"
        )
    dtheta = np.broadcast_to(dtheta, shape)
    moments = np.broadcast_to(moments, shape + (3,))
    periods = np.broadcast_to(periods.astype(np.int64), shape)
    return moments, dtheta, periods, rtol, scalar


# closure_errors' quarter path (|dtheta| < 1e-3) is accurate to about
# rtol * I3/I1 a period: phi turns at up to M/I1 where w2 = 0, which
# magnifies the integration's relative error by I3/I1 (measured at rtol
# 1e-13: 0.4-0.8 of that on 1e-6 and 1e-9 rods, 1.6 at rtol 1e-9)
QUARTER_ERROR_FACTOR = 10.0


def closure_error_budget(moments, dtheta, periods, rtol=1e-13):
    """What :func:`closure_errors` itself may be off by, radians, per orbit.

    On the quarter path (``|dtheta| < 1e-3``), ``QUARTER_ERROR_FACTOR *
    rtol * (I3/I1) * q``: negligible for most bodies (3e-12 at I3/I1 = 3),
    but 1e-6 for a rod with I1 = 1e-6 I3, where an orbit that closes
    exactly reads as open by up to that much.  0 on the direct path (its
    error is the integrator's, ~1e-12).  Arguments as for
    :func:`closure_errors` (moments broadcast against ``dtheta``), and
    refused as it refuses them.
    """
    moments, dtheta, periods, rtol, scalar = _closure_arguments(moments, dtheta, periods, rtol)
    ratio = moments[..., 2] / moments[..., 0]
    quarter = np.abs(dtheta) < _checks.FULL_INTEGRATION_FROM
    budget = np.where(quarter, QUARTER_ERROR_FACTOR * rtol * ratio * periods, 0.0)
    return float(budget[0]) if scalar else budget


# the integration and quadrature tolerances of verify's checks (the ODE's
# rtol, VERIFY_ODE_RTOL, and check (a)'s ODE_ERROR_FACTOR are in
# orbits.limits, which the command line's help quotes too)
VERIFY_ODE_ATOL = 1e-14
VERIFY_QUAD_RTOL = 1e-14
# the public routes of the closed form verify evaluates (summary["routes"])
ROUTES = (
    ("total_phase", "orbits.total_phase, bodies in one call (SIMD kernel total_phase_many)"),
    (
        "total_phase_one_body",
        "orbits.total_phase, one body per call (SIMD kernel total_phase_one_body)",
    ),
    ("phases", "orbits.phases, the table of 'orbits phase --theta' (parts_from_spin)"),
    ("spin_phases", "orbits.spin_phases, a spin vector (parts_from_vector_array)"),
)
_CHECKS = (
    ("montgomery", "montgomery_error"),
    ("ode_rotation", "ode_error"),
    ("exact_motion", "motion_error"),
    ("theta_orbit", "theta_orbit_error"),
    ("closed_form_routes", "routes_error"),
)


class VerifyReport(namedtuple("VerifyReport", ["table", "summary", "passed"])):
    """Result of :func:`verify`.

    table : DataFrame, one row per initial condition (I1, I2, I3, theta, branch,
        the closed form, each check and each public route with its
        discrepancy; see :func:`verify`)
    summary : dict in the ``orbits verify --json`` format
    passed : every check passed (see :func:`verify`)
    """

    __slots__ = ()

    def _rows(self):
        summary = self.summary
        rows = [
            (f"{name}: max |discrepancy|", check["max_abs_error"], "rad")
            for name, check in summary["checks"].items()
        ]
        rows.append(
            ("ODE period vs eqn:TK: max |dT|", summary["ode_period_max_abs_error"], "1/|w0|")
        )
        return rows

    def __repr__(self):
        summary = self.summary
        checks = ", ".join(
            f"{name} {'n/a' if value is None else format(value, '.2e')}"
            for name, value, _ in self._rows()
        )
        return (
            f"VerifyReport(passed={self.passed}, {summary['initial_conditions']} initial "
            f"conditions, tolerance {summary['tolerance']:g} rad; {checks}; "
            "rows in .table)"
        )

    def _repr_html_(self):
        from .units import html_table

        summary = self.summary
        rows = [
            ("result", "passed" if self.passed else "FAILED", ""),
            ("initial conditions", summary["initial_conditions"], ""),
            ("tolerance", float(summary["tolerance"]), "rad"),
            *(
                (name, "n/a" if value is None else value, unit)
                for name, value, unit in self._rows()
            ),
        ]
        return html_table("orbits.verify: closed form against independent checks", rows)


def ode_error_budget(ode_period, rtol=VERIFY_ODE_RTOL):
    """The error check (a) is allowed from its integrator, radians.

    Parameters
    ----------
    ode_period : float or array_like
        The period the integration found, in units of ``1/|w0|`` (so that
        ``ode_period`` is the angle ``|w0| T``, radians, the body turns
        through at its initial rate in one period); NaN where there is none.
    rtol : float
        The relative tolerance of the integration (verify's: 1e-12).

    Returns
    -------
    float or ndarray
        ``ODE_ERROR_FACTOR * rtol * |w0| T`` (radians; a float for a scalar
        ``ode_period``, NaN where it is NaN): ten times the largest error
        per unit of ``rtol |w0| T`` measured where DOP853's error falls
        with ``rtol`` (see :data:`ODE_ERROR_FACTOR`).

    Examples
    --------
    >>> from orbits import checks
    >>> round(checks.ode_error_budget(94434.8), 10)  # (1, 1.0001, 1.0002), theta 0.75
    5.666e-07
    """
    period = real_array("ode_period", ode_period)
    if np.any(period < 0.0) or np.any(np.isinf(period)):
        raise InputError("ode_period must be >= 0 and finite (NaN where there is none)")
    rtol = _bounded("rtol", rtol, ODE_RTOL_RANGE, "relative tolerance of DOP853")
    budget = ODE_ERROR_FACTOR * rtol * period
    return float(budget) if budget.ndim == 0 else budget


def _verify_arguments(n_angles, tolerance, progress, chunk):
    """Validate the arguments shared by :func:`verify` and :func:`verify_body`."""
    n_angles = integer("n_angles", n_angles, minimum=1)
    tolerance = positive_finite("tolerance", tolerance)
    chunk = integer("chunk", chunk, minimum=1)
    if progress is not None and not callable(progress):
        raise ArgumentTypeError(
            f"progress must be a callable (progress(done)) or None, got {type(progress).__name__}"
        )
    return n_angles, tolerance, progress, chunk


def verify(n_bodies=293, n_angles=22, *, tolerance=TOLERANCE, progress=None, chunk=2048):
    """The paper's exhaustive check, at any scale.

    ``n_bodies`` bodies spread evenly over the region of physical bodies
    (:func:`orbits.bodies.region_sample`) times ``n_angles`` angles
    ``theta_j = (j + 1/2) (pi/2) / n_angles`` (phi = 0).  The defaults,
    293 x 22 = 6446, reproduce the paper's count of initial conditions (the
    paper says 292 bodies x 22 angles = 6446, but 292 x 22 = 6424).

    Each body is checked in the canonical form every public function gives
    the kernels (:func:`orbits.bodies.unit_moments`: an exact power-of-two
    scaling), so the body checked is the body named, bit for bit.

    Parameters
    ----------
    n_bodies, n_angles : int
        Positive integers; their product is bounded by the memory allowed
        (half of this machine's, about 2 kB per initial condition).
    tolerance : float
        Largest discrepancy allowed (radians), positive and finite.  A
        discrepancy within :data:`PHASE_ULPS` (16) spacings of doubles at
        ``|Delta alpha|`` passes too: no double can agree more closely with
        a phase of 1e8 rad than ~1e-8 rad.  Check (a) is also allowed its
        integrator's own error, :func:`ode_error_budget` (``6 * rtol * |w0|
        T``, T the period it found; 5.7e-7 rad for the 15,000 turns of
        (1, 1.0001, 1.0002) at theta = 0.75), and next to the separatrix
        what one rounding of its state moves the phase,
        :func:`gap_rounding_allowance` (``20 * eps / g * |d Delta alpha /
        d ln g|``, g the relative gap), where those are larger: the table's
        ``ode_allowance`` is what each row was held to.
    progress : callable, optional
        ``progress(done)`` after each chunk of initial conditions.
    chunk : int
        Initial conditions per batch (a positive integer).

    Returns
    -------
    VerifyReport
        ``table`` (one row per initial condition), ``summary`` (the largest
        error of each check) and ``passed``.  Four checks: (b)
        ``montgomery``, (a) ``ode_rotation`` and (c) ``exact_motion`` against
        the closed form (the ``closed_form`` column, eqn:GeometricPhase for
        the orbit through the double omega0), and ``closed_form_routes``:
        the closed form as :func:`orbits.total_phase` (both SIMD kernels),
        :func:`orbits.phases` (``orbits phase --theta``) and
        :func:`orbits.spin_phases` compute it, each against the same formula
        evaluated by the scalar kernel for the same orbit, which must agree
        to :data:`ROUTE_ULPS` (64) spacings of doubles whatever the
        tolerance.

    Raises
    ------
    InputError, ArgumentTypeError
        An argument of the wrong type or out of range (before any work).

    Examples
    --------
    >>> import orbits
    >>> report = orbits.verify(n_bodies=4, n_angles=3)
    >>> report.passed, report.summary["initial_conditions"]
    (True, 12)
    """
    n_bodies = integer("n_bodies", n_bodies, minimum=1)
    n_angles, tolerance, progress, chunk = _verify_arguments(n_angles, tolerance, progress, chunk)
    check_verify_size(n_bodies, n_angles)
    bodies = region_sample(n_bodies)
    unit, exponent = unit_moments(bodies)
    return _verify_grid(unit, exponent, n_angles, tolerance, progress, chunk, one_body=False)


def verify_body(body, n_angles=22, *, tolerance=TOLERANCE, progress=None, chunk=2048):
    """:func:`verify` for one body of the caller's (``orbits verify BODY``).

    The checks at ``theta_j = (j + 1/2) (pi/2) / n_angles`` (phi = 0) for
    the body's canonical moments (:attr:`Body.unit_moments`, the exact
    power-of-two scaling every public function uses: the body checked is
    the body given, bit for bit; the table's I1, I2, I3 are its moments as
    given).  The phases do not depend on the scale; the tolerances of the
    integrators are absolute for ``|omega0| = 1`` and moments near 1.

    Parameters
    ----------
    body : Body or array_like, shape (3,)
        The body, or its principal moments (any order, any scale).
    n_angles : int
        Angles ``theta_j`` checked (default 22, as the paper's check).
    tolerance : float
        Radians each discrepancy may reach (or 16 spacings of doubles at
        the phase, where that is larger), as :func:`verify`.
    progress : callable, optional
        Called with the number of initial conditions of each finished chunk.
    chunk : int
        Initial conditions per chunk of work.

    Returns
    -------
    VerifyReport

    Raises
    ------
    InputError, ArgumentTypeError, NonPhysicalBodyError, SymmetricTopError
        A bad body or argument (before any work).
    """
    body = as_body(body)
    n_angles, tolerance, progress, chunk = _verify_arguments(n_angles, tolerance, progress, chunk)
    check_verify_size(1, n_angles)
    unit = np.asarray(body.unit_moments, dtype=float)[None, :]
    exponent = np.array([body.exponent])
    return _verify_grid(unit, exponent, n_angles, tolerance, progress, chunk, one_body=True)


def _verify_grid(unit, exponent, n_angles, tolerance, progress, chunk, one_body):
    """The checks for every body (rows of canonical ``unit``) times ``n_angles`` angles."""
    n_bodies = unit.shape[0]
    angles = (np.arange(n_angles) + 0.5) * (0.5 * np.pi / n_angles)
    moments = np.ascontiguousarray(np.repeat(unit, n_angles, axis=0))
    theta = np.tile(angles, n_bodies)
    phi = np.zeros_like(theta)
    n = theta.size
    # NaN until written: a row the kernel did not reach can never read as 0
    out = np.full((n, len(_checks.CHECK_COLUMNS)), np.nan)
    for start in range(0, n, chunk):
        stop = min(start + chunk, n)
        with threads_for(stop - start, serial_below=2):
            _checks.check_batch(
                moments[start:stop],
                theta[start:stop],
                phi[start:stop],
                VERIFY_ODE_RTOL,
                VERIFY_ODE_ATOL,
                VERIFY_QUAD_RTOL,
                out[start:stop],
            )
        if progress is not None:
            progress(stop - start)
    # every row written (the kernel writes every entry; branch is never NaN)
    unwritten = np.isnan(out[:, _checks.CHECK_COLUMNS.index("branch")])
    if unwritten.any():
        raise AssertionError(
            f"verify: {int(unwritten.sum())} of {n} initial conditions were not evaluated"
        )
    table = pd.DataFrame(out, columns=_checks.CHECK_COLUMNS)
    table.insert(0, "theta", theta)
    # the moments as given (the canonical ones times 2**exponent, exact)
    given = np.ldexp(moments, np.repeat(np.asarray(exponent), n_angles)[:, None])
    for k, name in enumerate(("I1", "I2", "I3")):
        table.insert(k, name, given[:, k])
    code = table["branch"].to_numpy()
    table["branch"] = np.where(code > 0, "SAM", np.where(code < 0, "LAM", "separatrix"))
    closed = table["closed_form"].to_numpy()
    table["montgomery_error"] = np.abs(table["montgomery"] - closed)
    table["motion_error"] = np.abs(table["motion"] - closed)
    # the orbit of the exact theta (angle_triplet, the path of total_phase
    # and phases) against that of the double omega0 the checks start from
    table["theta_orbit_error"] = np.abs(table["closed_form_theta"] - closed)
    table["ode_error"] = np.maximum(
        circular_distance(table["ode_angle"], closed), table["ode_off_axis"]
    )
    # rows whose integration ran out of steps, or that were not integrated
    # because one period needs more steps than the budget: no ODE values
    ode_code = table["ode_period"].to_numpy()
    predicted = ode_code == _checks.STEP_BUDGET_PREDICTED
    exhausted = (ode_code == _checks.STEP_BUDGET_EXHAUSTED) | predicted
    table.loc[exhausted, "ode_period"] = np.nan
    table["ode_period_error"] = np.abs(table["ode_period"] - table["period"])
    # the discrepancy check (a) is allowed at each row (radians)
    table["ode_allowance"] = _ode_limit(table, _allowance(closed, tolerance))
    route_failures = _add_routes(table, unit, moments, theta, n_angles, one_body)
    summary = {
        "initial_conditions": int(n),
        "bodies": int(n_bodies),
        "angles": int(n_angles),
        "tolerance": tolerance,
    }
    summary.update(_summarize(table, tolerance, exhausted, route_failures, predicted))
    return VerifyReport(table, summary, summary["passed"])


def _allowance(closed, tolerance):
    """``max(tolerance, PHASE_ULPS * spacing(|closed|))`` (radians; NaN where
    ``closed`` is not finite): what checks (b) and (c) are allowed."""
    closed = np.asarray(closed, dtype=float)
    finite = np.isfinite(closed)
    spacing = np.where(finite, np.spacing(np.abs(np.where(finite, closed, 1.0))), np.nan)
    return np.maximum(tolerance, PHASE_ULPS * spacing)


def gap_rounding_allowance(relative_gap, gap_slope):
    """What the rounding of a double state moves check (a) by, radians.

    Parameters
    ----------
    relative_gap : float or array_like
        The orbit's distance from the separatrix, ``g = |M^2 - 2 E I2| /
        (I3 (I3 - I2) w3^2 + I1 (I2 - I1) w1^2)``: the gap over the two
        terms it is the difference of (the ``relative_gap`` column of
        verify's table).
    gap_slope : float or array_like
        ``|d Delta alpha / d ln g|`` (rad; ``gap_slope``).

    Returns
    -------
    float or ndarray
        ``GAP_ROUNDING_FACTOR * eps / g * |d Delta alpha / d ln g|``: a double
        state holds ``g`` only to about ``eps / g`` relative, so an
        integration in doubles cannot place the phase closer than that next
        to the separatrix, whatever its tolerance (see
        :data:`orbits.limits.GAP_ROUNDING_FACTOR`).  Far from it the term
        is negligible.

    Examples
    --------
    >>> from orbits import checks
    >>> f"{checks.gap_rounding_allowance(2.97e-7, 6.7645):.3g}"  # verify(29300), row 301239
    '1.01e-07'
    """
    eps = np.finfo(float).eps
    gap = real_array("relative_gap", relative_gap)
    slope = real_array("gap_slope", gap_slope)
    if np.any(gap < 0.0) or np.any(slope < 0.0):
        raise InputError(
            "relative_gap and gap_slope (|d Delta alpha / d ln g|) must be >= 0 "
            "(NaN where there is none)"
        )
    # a zero gap (the separatrix, or one that underflowed) allows nothing:
    # NaN, which the allowance's fmax passes over
    safe = np.where(gap > 0.0, gap, np.nan)
    term = GAP_ROUNDING_FACTOR * eps * slope / safe
    return float(term) if term.ndim == 0 else term


def theta_orbit_allowance(table, spacing):
    """What the orbit of the exact theta may differ from that of the double omega0 by, radians.

    The checks start from omega0 = ``spin_vector(theta)`` rounded to
    doubles; ``total_phase`` and ``phases`` take the orbit of the exact
    ``theta`` (its offset from theta_c).  The two are the same orbit up to
    that rounding: within :data:`~orbits.limits.ROUTE_ULPS` spacings of
    doubles at Delta alpha, or next to the separatrix what the rounding of
    the state moves the phase by (:func:`gap_rounding_allowance`), whatever
    the tolerance.  Measured: at most 14 ulps far from the separatrix and
    0.22 of this allowance over verify(29300, 22) and verify(2930, 200).
    """
    return _with_gap_rounding(table, ROUTE_ULPS * spacing)


def _with_gap_rounding(table, limit):
    """``limit``, raised where the rounding of the state allows more
    (:func:`gap_rounding_allowance`; unchanged for a table without the
    ``relative_gap`` and ``gap_slope`` columns)."""
    if "relative_gap" in table and "gap_slope" in table:
        limit = np.fmax(
            limit,
            gap_rounding_allowance(
                table["relative_gap"].to_numpy(), table["gap_slope"].to_numpy()
            ),
        )
    return limit


def _ode_limit(table, allowance):
    """What check (a) is allowed at each row: the largest of ``allowance``,
    its integrator's error budget (:func:`ode_error_budget` of the period it
    found) and, next to the separatrix, the rounding of the state
    (:func:`gap_rounding_allowance`); a table without those columns has
    only ``allowance``."""
    limit = allowance
    if "ode_period" in table:
        limit = np.fmax(limit, ode_error_budget(table["ode_period"].to_numpy()))
    return _with_gap_rounding(table, limit)


def _add_routes(table, unit, moments, theta, n_angles, one_body):
    """The closed form through each public route (columns ``route_*``).

    Each route runs on the rows that have a closed form; its value is
    compared with the scalar kernel's closed form for the same orbit
    (``closed_form_theta`` for the routes that take ``theta``, the orbit of
    the exact angle; ``closed_form`` for :func:`orbits.spin_phases`, the
    orbit of the double omega0), both at least 2 pi as the public functions
    give them (:func:`orbits.phases.at_least_two_pi`).  Adds the columns
    ``route_<name>`` and ``routes_error`` (the largest difference, NaN where
    a route gave no value).  Returns ``{route: message}`` for routes that
    raised.
    """
    from .phases import phases, spin_phases, total_phase

    n = theta.size
    rows = np.flatnonzero(np.isfinite(table["closed_form_theta"].to_numpy()))
    omega = table[["w1", "w2", "w3"]].to_numpy()
    failures = {}
    values = {name: np.full(n, np.nan) for name, _ in ROUTES}

    def run(name, where, function, *args, column=None):
        if where.size == 0:
            return
        try:
            result = function(*args)
        except OrbitsError as error:
            failures.setdefault(name, f"{type(error).__name__}: {error}")
            return
        if column is not None:
            result = result[column]
        values[name][where] = np.asarray(result, dtype=float).reshape(-1)

    run("total_phase", rows, total_phase, moments[rows], theta[rows])
    for b in range(unit.shape[0]):
        mine = rows[(rows >= b * n_angles) & (rows < (b + 1) * n_angles)]
        run("total_phase_one_body", mine, total_phase, unit[b], theta[mine])
    # 'orbits phase BODY --theta ...' passes one body: its own kernel path
    body = unit[0] if one_body else moments[rows]
    run("phases", rows, phases, body, theta[rows], column="total_phase")
    run("spin_phases", rows, spin_phases, moments[rows], omega[rows], column="total_phase")
    error = np.zeros(n)
    for name, _ in ROUTES:
        table[f"route_{name}"] = values[name]
        error = np.maximum(error, np.abs(values[name] - _route_reference(table, name)))
    table["routes_error"] = np.where(np.isfinite(table["closed_form_theta"]), error, np.nan)
    return failures


def _route_reference(table, name):
    """What route ``name`` is compared with: the scalar kernel's closed form
    of the same orbit, raised to 2 pi where below it by rounding, as the
    public functions give it."""
    from .phases import at_least_two_pi

    column = "closed_form" if name == "spin_phases" else "closed_form_theta"
    return at_least_two_pi(table[column].to_numpy(dtype=float, copy=True))


def _summarize(table, tolerance, exhausted, route_failures=None, predicted=None):
    """Largest discrepancy of each check, never NaN (strict JSON).

    A discrepancy passes when it is within ``max(tolerance, PHASE_ULPS *
    spacing(|Delta alpha|))`` (the public routes: within ``ROUTE_ULPS *
    spacing``, whatever the tolerance); the ODE check (a) also within its
    integrator's own error, :func:`ode_error_budget` of the period it found
    (``ODE_ERROR_FACTOR * rtol * |w0| T``), and next to the separatrix
    within the rounding of its state, :func:`gap_rounding_allowance`, where
    those are larger.  Each check reports the largest allowance it was
    held to and its largest
    discrepancy as a fraction of the allowance at that row.  A row on the
    separatrix (no closed form) or a check that gave no value is counted
    and explained; its discrepancy is ``None``, never NaN.  The ODE check
    (a) is *not applicable* at the rows of ``exhausted``, where the
    integration could not complete one period within its step budget, or
    (the rows of ``predicted``, a subset) was not started because both
    periods need more steps than that (a nearly symmetric body: the period
    is then ~1e8 rotations); that is not a failure.  Every other missing
    value fails the verification.
    """
    route_failures = route_failures or {}
    predicted = np.zeros(len(table), bool) if predicted is None else np.asarray(predicted)
    closed = table["closed_form"].to_numpy()
    has_closed = np.isfinite(closed) & np.isfinite(table["closed_form_theta"].to_numpy())
    on_separatrix = int(np.count_nonzero(~has_closed))
    spacing = np.where(has_closed, np.spacing(np.abs(np.where(has_closed, closed, 1.0))), np.nan)
    allowance = _allowance(closed, tolerance)  # as the table's ode_allowance was made
    limits = {
        "closed_form_routes": ROUTE_ULPS * spacing,
        "ode_rotation": _ode_limit(table, allowance),
        "theta_orbit": theta_orbit_allowance(table, spacing),
    }
    checks = {}
    passed = on_separatrix == 0
    for name, column in _CHECKS:
        errors = table[column].to_numpy()
        ran = np.isfinite(errors) & has_closed
        missing = int(np.count_nonzero(has_closed & ~ran))
        limit = limits.get(name, allowance)
        beyond = ran & ~(errors <= limit)
        entry = {
            "max_abs_error": float(errors[ran].max()) if ran.any() else None,
            "max_ulps": float(np.max(errors[ran] / spacing[ran])) if ran.any() else None,
            "largest_allowance": float(limit[ran].max()) if ran.any() else None,
            "max_fraction_of_allowance": (
                float(np.max(errors[ran] / limit[ran])) if ran.any() else None
            ),
            "beyond_tolerance": int(np.count_nonzero(beyond)),
            "not_applicable": 0,
            "failed_to_evaluate": 0,
            "passed": True,
            "reason": None,
        }
        reasons = []
        if name == "ode_rotation":
            # beyond what (b) and (c) are allowed, within the integrator's
            # error or, next to the separatrix, the rounding of its state
            entry["within_integrator_error_only"] = int(
                np.count_nonzero(ran & ~beyond & ~(errors <= allowance))
            )
            skipped = has_closed & ~ran & exhausted
            entry["not_applicable"] = int(np.count_nonzero(skipped))
            missing -= entry["not_applicable"]
            reasons.extend(_ode_not_applicable(table, skipped & ~predicted, skipped & predicted))
        if name == "closed_form_routes":
            for route, message in route_failures.items():
                reasons.append(f"{route} raised {message}")
            entry["routes"] = {}
            for route, _ in ROUTES:
                value = table[f"route_{route}"].to_numpy()
                reference = _route_reference(table, route)
                ok = has_closed & np.isfinite(value)
                entry["routes"][route] = (
                    float(np.max(np.abs(value[ok] - reference[ok]) / np.spacing(reference[ok])))
                    if ok.any()
                    else None
                )
            if entry["beyond_tolerance"]:
                reasons.append(
                    f"the public routes differ from the closed form by more than "
                    f"{ROUTE_ULPS} ulps at {entry['beyond_tolerance']} initial condition(s)"
                )
        if name == "theta_orbit" and entry["beyond_tolerance"]:
            reasons.append(
                f"the closed form of the exact theta differs from that of the double "
                f"omega0 by more than the rounding of omega0 allows at "
                f"{entry['beyond_tolerance']} initial condition(s)"
            )
        if missing:
            entry["failed_to_evaluate"] = missing
            reasons.append(f"no value (not finite) at {missing} initial condition(s)")
        if on_separatrix:
            reasons.append(
                f"{on_separatrix} initial condition(s) on the separatrix have no closed form"
            )
        entry["reason"] = "; ".join(reasons) or None
        entry["passed"] = bool(missing == 0 and entry["beyond_tolerance"] == 0)
        passed = passed and entry["passed"]
        checks[name] = entry
    period_error = table["ode_period_error"].to_numpy()
    period_error = period_error[np.isfinite(period_error)]
    # spacing of doubles at the largest phase: no check can agree more closely
    magnitude = np.abs(closed[has_closed])
    largest = float(magnitude.max()) if magnitude.size else None
    resolution = float(np.spacing(largest)) if magnitude.size else None
    return {
        "checks": checks,
        "ode_period_max_abs_error": float(period_error.max()) if period_error.size else None,
        "max_abs_phase": largest,
        "phase_resolution": resolution,
        "phase_ulps": PHASE_ULPS,
        "route_ulps": ROUTE_ULPS,
        "ode_rtol": VERIFY_ODE_RTOL,
        "ode_error_factor": ODE_ERROR_FACTOR,
        "gap_rounding_factor": GAP_ROUNDING_FACTOR,
        "largest_allowance": float(np.max(allowance[has_closed])) if has_closed.any() else None,
        "on_separatrix": on_separatrix,
        "passed": bool(passed),
    }


def _ode_not_applicable(table, ran_out, predicted):
    """Why check (a) has no value at the rows ``ran_out`` (the integration
    used up its steps) and ``predicted`` (not started: both periods need
    more steps than that); a list of zero to two sentences."""
    reasons = []
    periods = table["period"].to_numpy()
    if ran_out.any():
        reasons.append(
            f"the integration did not complete one period within "
            f"{_checks.ODE_MAX_STEPS:,} steps at {int(np.count_nonzero(ran_out))} "
            f"initial condition(s) (closed-form period up to "
            f"{float(np.max(periods[ran_out])):.4g} / |w0|, a nearly symmetric body or a "
            "spin near the separatrix)"
        )
    if predicted.any():
        inertia = table[["I1", "I2", "I3"]].to_numpy()[predicted]
        omega = table[["w1", "w2", "w3"]].to_numpy()[predicted]
        shortest = np.fmin(periods[predicted], table["montgomery_period"].to_numpy()[predicted])
        fewest = min(
            _checks.ode_steps_at_least(*i, *w, float(t))
            for i, w, t in zip(inertia, omega, shortest)
        )
        reasons.append(
            f"one period needs more than {_checks.ODE_MAX_STEPS:,} steps at "
            f"{int(np.count_nonzero(predicted))} initial condition(s), which were not "
            f"integrated (at least {fewest:.2g} steps from the closed-form and the "
            f"quadrature period, up to {float(np.max(periods[predicted])):.4g} / |w0|: "
            "a nearly symmetric body)"
        )
    return reasons


def exact_motion_mpmath(moments, omega0, times, dps=40):
    """The exact motion evaluated in mpmath at ``dps`` digits (a reference).

    Same solution as :class:`orbits.Motion` (eqn:Omegas, eqn:eulerangles,
    eqn:fullphi) but with mpmath's ``ellipfun``, ``ellipf`` and ``ellippi``,
    the parameter ``m`` formed at high precision, and no use of this
    package's kernels.  Needs mpmath (``pip install orbits[test]``).

    Parameters
    ----------
    moments : array_like, shape (3,)
        Principal moments, any order, of an asymmetric physical body.
    omega0 : array_like, shape (3,)
        Initial angular velocity in the principal axes (sorted order), not
        on the separatrix.
    times : array_like, shape (n,)
        Finite times, n >= 1.
    dps : int
        Decimal digits, 15 to 10,000.

    Returns
    -------
    omega, euler, omega_space : ndarray
        Shapes (n, 3): body-frame omega, Euler angles (phi, theta, psi with
        psi in (-pi, pi]), space-frame omega.

    Raises
    ------
    NonPhysicalBodyError, SymmetricTopError, SeparatrixError, AngleError, InputError
        As :class:`orbits.Motion` for ``moments`` and ``omega0`` (which it
        checks them with, using none of its values); ``times`` empty or not
        finite; ``dps`` out of range.
    """
    try:
        import mpmath as mp
    except ImportError as error:  # pragma: no cover
        raise InputError("exact_motion_mpmath needs mpmath") from error
    Motion(np.sort(real_array("moments", moments)), omega0)  # the same refusals
    times = real_array("times", times)
    if times.ndim != 1 or times.size == 0 or not np.all(np.isfinite(times)):
        raise InputError(f"times must be a non-empty 1-d array of finite times, got {times!r}")
    dps = integer("dps", dps, minimum=15, maximum=10_000)
    with mp.workdps(dps):
        i1, i2, i3 = (mp.mpf(float(v)) for v in sorted(moments))
        w1, w2, w3 = (mp.mpf(float(v)) for v in omega0)
        two_e = i1 * w1**2 + i2 * w2**2 + i3 * w3**2
        m_sq = i1**2 * w1**2 + i2**2 * w2**2 + i3**2 * w3**2
        momentum = mp.sqrt(m_sq)
        gap_m1, gap_3m = m_sq - two_e * i1, two_e * i3 - m_sq
        sam = m_sq > two_e * i2
        if sam:
            k2 = (i2 - i1) * gap_3m / ((i3 - i2) * gap_m1)
            rate = mp.sqrt((i3 - i2) * gap_m1 / (i1 * i2 * i3))
            sign = 1 if w3 >= 0 else -1
            amp = (
                mp.sqrt(gap_3m / (i1 * (i3 - i1))),
                sign * mp.sqrt(gap_3m / (i2 * (i3 - i2))),
                sign * mp.sqrt(gap_m1 / (i3 * (i3 - i1))),
            )
            cos0, sin0 = w1 / amp[0] if amp[0] else 1, w2 / amp[1] if amp[1] else 0
            n = -i3 * (i2 - i1) / (i1 * (i3 - i2))
        else:
            k2 = (i3 - i2) * gap_m1 / ((i2 - i1) * gap_3m)
            rate = mp.sqrt((i2 - i1) * gap_3m / (i1 * i2 * i3))
            sign = 1 if w1 >= 0 else -1
            amp = (
                sign * mp.sqrt(gap_3m / (i1 * (i3 - i1))),
                sign * mp.sqrt(gap_m1 / (i2 * (i2 - i1))),
                mp.sqrt(gap_m1 / (i3 * (i3 - i1))),
            )
            cos0, sin0 = w3 / amp[2] if amp[2] else 1, w2 / amp[1] if amp[1] else 0
            n = -i3 * gap_m1 / (i1 * gap_3m)
        quarter = mp.ellipk(k2)
        pi_complete = mp.ellippi(n, k2)

        def pi_of(tau):
            j = mp.nint(tau / (2 * quarter))
            parity = -1 if int(j) % 2 else 1
            sn, cn, dn = (mp.ellipfun(kind, tau, m=k2) for kind in ("sn", "cn", "dn"))
            reduced = mp.atan2(parity * sn, parity * cn)
            return 2 * j * pi_complete + mp.ellippi(n, reduced, k2), sn, cn, dn

        tau0 = mp.ellipf(mp.atan2(sin0, cos0), k2)
        pi0 = pi_of(tau0)[0]
        coef = momentum * (i3 - i1) / (i1 * i3 * rate)
        rows = []
        for t in times:
            t = mp.mpf(float(t))
            value, sn, cn, dn = pi_of(tau0 + rate * t)
            phi = momentum * t / i3 + coef * (value - pi0)
            if sam:
                w = (amp[0] * cn, amp[1] * sn, amp[2] * dn)
            else:
                w = (amp[0] * dn, amp[1] * sn, amp[2] * cn)
            theta = mp.atan2(mp.sqrt((i1 * w[0]) ** 2 + (i2 * w[1]) ** 2), i3 * w[2])
            psi = mp.atan2(i1 * w[0], i2 * w[1])
            cf, sf, ct, st, cp, sp = (
                mp.cos(phi),
                mp.sin(phi),
                mp.cos(theta),
                mp.sin(theta),
                mp.cos(psi),
                mp.sin(psi),
            )
            x = cp * w[0] - sp * w[1]
            y = sp * w[0] + cp * w[1]
            y, z = ct * y - st * w[2], st * y + ct * w[2]
            rows.append(
                [float(v) for v in (*w, phi, theta, psi, cf * x - sf * y, sf * x + cf * y, z)]
            )
    rows = np.array(rows)
    return rows[:, 0:3], rows[:, 3:6], rows[:, 6:9]
