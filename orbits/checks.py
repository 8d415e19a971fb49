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

:func:`verify` runs all three over the paper's 292 bodies x 22 angles
(or more) and reports the largest discrepancy of each.
"""

from collections import namedtuple

import numpy as np
import pandas as pd
from scipy.integrate import solve_ivp

from ._args import broadcast, real_array, real_scalar
from .bodies import region_sample, unit_moments
from .core import checks as _checks
from .core import quadrature as _quadrature
from .core.exact import separatrix_gap_exact
from .core.ode import STATE_SIZE, euler_rhs
from .errors import AngleError, InputError
from .motion import Motion, as_body
from .threads import threads_for

TOLERANCE = 1e-9
# longest closure check: q periods integrated at rtol 1e-13
MAX_CLOSURE_PERIODS = 100_000
TWO_PI = 2.0 * np.pi

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


def circular_distance(a, b):
    """|a - b| on the circle, in [0, pi]."""
    d = np.mod(np.asarray(a) - np.asarray(b), TWO_PI)
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
        times ``Delta alpha``).
    rtol, atol : float
        Integration tolerances (``rtol <= 1e-12`` by default).
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
        The integration cannot reach the end of the last period: beyond
        10,000 turns of omega with ``engine="scipy"`` (refused before it
        starts), or beyond the compiled engine's 10^7 steps (a nearly
        symmetric body, or a spin very near the separatrix).

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
    if engine not in ("scipy", "compiled"):
        raise InputError(f"engine must be 'scipy' or 'compiled', got {engine!r}")
    if int(periods) != periods or periods < 1:
        raise InputError(f"periods must be a positive integer, got {periods}")
    motion = _unit_motion(body_or_moments, theta, dtheta, phi)
    # scale-free with |omega0| = 1 (period, angles, phases), and the
    # kernels' products neither underflow nor overflow at any scale
    i1, i2, i3 = (float(v) for v in motion.body.unit_moments)
    w = motion.omega0
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
            i1, i2, i3, w[0], w[1], w[2], int(periods), rtol, atol, _checks.ODE_MAX_STEPS
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
    return RotationCheck(period, angle, off_axis, float(expected), error)


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
    rtol : float
        Relative tolerance of the adaptive Gauss-Legendre quadratures.

    Returns
    -------
    MontgomeryCheck
        ``total_phase = dynamic_phase - solid_angle``; ``solid_angle`` is
        signed by the right-hand rule (positive on SAM, negative on LAM).
        For the T-handle spin of the paper it is 2.12519.  All in radians,
        ``period`` in units of :math:`1/|\boldsymbol\omega_0|`.

    Notes
    -----
    Montgomery's formula, Mecholsky's Eq. (1) (eqn:montgomery),

    .. math::

        \Delta\alpha = \frac{2ET}{M} - \Omega ,

    with the period :math:`T` and the solid angle :math:`\Omega` enclosed by
    the polhode both found by quadrature along the polhode, parameterised by
    its azimuth about the axis it circles: no elliptic function is used, so
    the check shares no formula with the closed form of Eq. (20).

    Examples
    --------
    >>> import numpy as np, orbits
    >>> body = orbits.Body.preset("t-handle")
    >>> check = orbits.montgomery(body, np.pi / 2 - 0.15, phi=np.pi / 2 - 0.2)
    >>> round(check.total_phase, 4), round(check.solid_angle, 5)
    (21.5303, 2.12519)
    """
    motion = _unit_motion(body_or_moments, theta, dtheta, phi)
    # scale-free with |omega0| = 1 (period, angles, phases), and the
    # kernels' products neither underflow nor overflow at any scale
    i1, i2, i3 = (float(v) for v in motion.body.unit_moments)
    w1, w2, w3 = motion.omega0
    gap = separatrix_gap_exact(i1, i2, i3, w1, w3)
    total, dynamic, solid, period, _ = _quadrature.montgomery_phase(
        i1, i2, i3, w1, w2, w3, gap, rtol
    )
    return MontgomeryCheck(total, dynamic, solid, period)


def motion_phase(body_or_moments, theta=None, *, dtheta=None, phi=0.0):
    """Check (c): ``phi(T) - 2 pi`` (SAM) or ``phi(T)`` (LAM) from the exact motion.

    The Euler angle :math:`\\phi` of :class:`orbits.Motion` (Mecholsky's
    Eq. A12, with Carlson's :math:`R_J`) after one period, per Eq. (19);
    radians.

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
    dtheta : array_like, shape (n,)
        Offsets from the critical angle (phi = 0), finite and nonzero.
    periods : array_like of int, shape (n,)
        After how many periods each orbit should close (the catalog's q),
        1 to :data:`MAX_CLOSURE_PERIODS`.
    rtol : float
        Integration tolerance, in (0, 1e-3].

    Returns
    -------
    ndarray
        The angle (radians) by which the orientation after ``q`` periods
        differs from the start.  For ``|dtheta| >= 1e-3``: Euler's equations
        with quaternion kinematics integrated (compiled DOP853) over the q
        periods from omega0, the angle of ``R(qT) R(0)^-1``.  Closer to the
        separatrix a double omega0 cannot hold the orbit, and the phase of a
        period comes from a quarter period integrated from the orbit's
        closest approach to the I2 axis (exact reversibility of Euler's
        equations makes the four quarters equal); the angle is then
        ``|q Delta alpha|`` reduced to [0, pi].

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
    dtheta = np.atleast_1d(real_array("dtheta", dtheta, AngleError))
    if not np.all(np.isfinite(dtheta)) or np.any(dtheta == 0.0):
        raise AngleError("dtheta must be finite and nonzero (0 is the separatrix)")
    moments, _ = unit_moments(moments)
    periods = real_array("periods", periods)
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
    rtol = real_scalar("rtol", rtol)
    if not (0.0 < rtol <= 1e-3):
        raise InputError(f"rtol must be in (0, 1e-3], got {rtol!r}")
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
    out = np.empty(dtheta.shape)
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
            f"dtheta = {dtheta[k]!r} puts theta outside [0, pi/2] for the "
            f"body {moments[k].tolist()} (unit scale)"
        )
    return out


class VerifyReport(namedtuple("VerifyReport", ["table", "summary", "passed"])):
    """Result of :func:`verify`.

    table : DataFrame, one row per initial condition (I1, I2, I3, theta, branch,
        the closed form and each check with its discrepancy)
    summary : dict in the ``orbits verify --json`` format
    passed : every discrepancy within the tolerance
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


def verify(n_bodies=293, n_angles=22, *, tolerance=TOLERANCE, progress=None, chunk=2048):
    """The paper's exhaustive check, at any scale.

    ``n_bodies`` bodies spread evenly over the region of physical bodies
    (:func:`orbits.bodies.region_sample`) times ``n_angles`` angles
    ``theta_j = (j + 1/2) (pi/2) / n_angles`` (phi = 0).  The defaults,
    293 x 22 = 6446, reproduce the paper's count of initial conditions (the
    paper says 292 bodies x 22 angles = 6446, but 292 x 22 = 6424).

    Parameters
    ----------
    progress : callable, optional
        ``progress(done)`` after each chunk of initial conditions.

    Returns
    -------
    VerifyReport
        ``table`` (one row per initial condition), ``summary`` (the largest
        error of each check) and ``passed``.

    Examples
    --------
    >>> import orbits
    >>> report = orbits.verify(n_bodies=4, n_angles=3)
    >>> report.passed, report.summary["initial_conditions"]
    (True, 12)
    """
    if int(n_bodies) != n_bodies or n_bodies < 1:
        raise InputError(f"bodies must be a positive integer, got {n_bodies}")
    if int(n_angles) != n_angles or n_angles < 1:
        raise InputError(f"angles must be a positive integer, got {n_angles}")
    bodies = region_sample(int(n_bodies))
    return _verify_grid(bodies, n_angles, tolerance, progress, chunk)


def verify_body(body, n_angles=22, *, tolerance=TOLERANCE, progress=None, chunk=2048):
    """:func:`verify` for one body of the caller's (``orbits verify BODY``).

    The three checks at ``theta_j = (j + 1/2) (pi/2) / n_angles`` (phi = 0)
    for the body's moments normalised to ``|I| = 1`` (the phases do not
    depend on the scale; the tolerances of the integrators are absolute).

    Returns
    -------
    VerifyReport
    """
    if int(n_angles) != n_angles or n_angles < 1:
        raise InputError(f"angles must be a positive integer, got {n_angles}")
    unit = as_body(body).normalized_moments
    return _verify_grid(unit[None, :], n_angles, tolerance, progress, chunk)


def _verify_grid(bodies, n_angles, tolerance, progress, chunk):
    """The three checks for every body (rows of ``bodies``) times ``n_angles`` angles."""
    n_bodies = bodies.shape[0]
    angles = (np.arange(n_angles) + 0.5) * (0.5 * np.pi / n_angles)
    moments = np.repeat(bodies, n_angles, axis=0)
    theta = np.tile(angles, int(n_bodies))
    phi = np.zeros_like(theta)
    out = np.empty((theta.size, len(_checks.CHECK_COLUMNS)))
    for start in range(0, theta.size, chunk):
        stop = min(start + chunk, theta.size)
        with threads_for(stop - start, serial_below=2):
            _checks.check_batch(
                moments[start:stop],
                theta[start:stop],
                phi[start:stop],
                1e-12,
                1e-14,
                1e-14,
                out[start:stop],
            )
        if progress is not None:
            progress(stop - start)
    table = pd.DataFrame(out, columns=_checks.CHECK_COLUMNS)
    table.insert(0, "theta", theta)
    for k, name in enumerate(("I1", "I2", "I3")):
        table.insert(k, name, moments[:, k])
    table["branch"] = np.where(table["branch"] > 0, "SAM", "LAM")
    closed = table["closed_form"].to_numpy()
    table["montgomery_error"] = np.abs(table["montgomery"] - closed)
    table["motion_error"] = np.abs(table["motion"] - closed)
    table["ode_error"] = np.maximum(
        circular_distance(table["ode_angle"], closed), table["ode_off_axis"]
    )
    # rows whose integration ran out of steps: their ODE values are absent
    exhausted = (table["ode_period"] == _checks.STEP_BUDGET_EXHAUSTED).to_numpy()
    table.loc[exhausted, "ode_period"] = np.nan
    table["ode_period_error"] = np.abs(table["ode_period"] - table["period"])
    summary = {
        "initial_conditions": int(theta.size),
        "bodies": int(n_bodies),
        "angles": int(n_angles),
        "tolerance": tolerance,
    }
    summary.update(_summarize(table, tolerance, exhausted))
    return VerifyReport(table, summary, summary["passed"])


def _summarize(table, tolerance, exhausted):
    """Largest discrepancy of each check, never NaN (strict JSON).

    A row on the separatrix (no closed form) or a check that gave no value
    is counted and explained; its discrepancy is ``None``, never NaN.  The
    ODE check (a) is *not applicable* at the rows of ``exhausted``, where
    the integration could not complete one period within its step budget
    (a nearly symmetric body: the period is then ~1e8 rotations); that is
    not a failure.  Every other missing value fails the verification.
    """
    closed = table["closed_form"].to_numpy()
    has_closed = np.isfinite(closed)
    on_separatrix = int(np.count_nonzero(~has_closed))
    checks = {}
    passed = on_separatrix == 0
    for name, column in (
        ("montgomery", "montgomery_error"),
        ("ode_rotation", "ode_error"),
        ("exact_motion", "motion_error"),
    ):
        errors = table[column].to_numpy()
        ran = np.isfinite(errors)
        missing = int(np.count_nonzero(has_closed & ~ran))
        entry = {
            "max_abs_error": float(errors[ran].max()) if ran.any() else None,
            "not_applicable": 0,
            "failed_to_evaluate": 0,
            "reason": None,
        }
        reasons = []
        if name == "ode_rotation":
            skipped = has_closed & ~ran & exhausted
            entry["not_applicable"] = int(np.count_nonzero(skipped))
            missing -= entry["not_applicable"]
            if skipped.any():
                periods = table["period"].to_numpy()[skipped]
                reasons.append(
                    f"the integration did not complete one period within "
                    f"{_checks.ODE_MAX_STEPS:,} steps at {entry['not_applicable']} "
                    f"initial condition(s) (closed-form period up to "
                    f"{float(np.max(periods)):.4g} / |w0|, a nearly symmetric body or a "
                    "spin near the separatrix)"
                )
        if missing:
            entry["failed_to_evaluate"] = missing
            reasons.append(f"no value (not finite) at {missing} initial condition(s)")
            passed = False
        if on_separatrix:
            reasons.append(
                f"{on_separatrix} initial condition(s) on the separatrix have no closed form"
            )
        entry["reason"] = "; ".join(reasons) or None
        if entry["max_abs_error"] is not None and not entry["max_abs_error"] <= tolerance:
            passed = False
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
        "passed": bool(passed),
    }


def exact_motion_mpmath(moments, omega0, times, dps=40):
    """The exact motion evaluated in mpmath at ``dps`` digits (a reference).

    Same solution as :class:`orbits.Motion` (eqn:Omegas, eqn:eulerangles,
    eqn:fullphi) but with mpmath's ``ellipfun``, ``ellipf`` and ``ellippi``,
    the parameter ``m`` formed at high precision, and no use of this
    package's kernels.  Needs mpmath (``pip install orbits[test]``).

    Returns
    -------
    omega, euler, omega_space : ndarray
        Shapes (n, 3): body-frame omega, Euler angles (phi, theta, psi with
        psi in (-pi, pi]), space-frame omega.
    """
    try:
        import mpmath as mp
    except ImportError as error:  # pragma: no cover
        raise InputError("exact_motion_mpmath needs mpmath") from error
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
