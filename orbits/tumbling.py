"""Spins with a given total phase, or a given observed period ratio.

:func:`spins_with_total_phase` finds every initial spin (``phi = 0``,
``theta`` in [0, pi/2], both branches) whose total phase ``Delta alpha``
(eqn:GeometricPhase) equals any given value, not only ``2 pi p/q``: it runs
the closed-orbit search kernel (:mod:`orbits.core.search`) with that one
level.  :func:`spins_with_period_ratio` turns an observed ratio
``P_psi / P_phi`` of a tumbling body (see :meth:`orbits.Motion.tumbling_periods`)
into the total phase on each branch and solves for the spin.
"""

import math
import warnings

import numpy as np

from ._args import caller_stacklevel, positive_finite
from .bodies import unit_moments
from .cells import exact_number
from .errors import InputError
from .limits import plural

# the range of normal doubles
_TINY = float(np.finfo(float).tiny)
_HUGE = float(np.finfo(float).max)

TWO_PI = 2.0 * math.pi


# the search's smallest offset: roots nearer the separatrix are unresolved
_SMALLEST_OFFSET = 2.2250738585072014e-308


def _solve(moments, targets, what, reachable=None):
    """Roots for per-branch targets ``{"SAM": X or None, "LAM": X or None}``.

    ``what`` names the request in the errors.  Raises InputError when no
    spin has it: below the body's minimum on each branch, or (a different
    message) only closer to the separatrix than a double can hold.
    ``reachable(branch, low)`` states, in the request's own terms, what a
    branch whose smallest total phase is ``low`` can reach (default: the
    total phase itself).
    """
    from .core import search as _kernels
    from .search import UnresolvedOrbitsWarning, branch_minima, find_roots

    found = []
    unreached = 0
    info = None
    for branch, sign in (("SAM", 1), ("LAM", -1)):
        target = targets.get(branch)
        # Delta alpha > 2 pi on every spin of every body (orbits.search.searched)
        if target is None or target <= TWO_PI:
            continue
        branches, _, offsets, info = find_roots(moments, np.array([target]))
        found.append([_polished(moments, float(x), target) for x in offsets[branches == sign]])
        if not found[-1]:
            # the branch's minimum itself, to its rounding (at an end, the
            # limit eqn:alphamin1/2 is a few ulps from the phase computed
            # there): the search wants the level strictly inside; a target
            # equal to the minimum it reports was refused as below it
            low, at = branch_minima(info)[branch]
            if abs(target - low) <= 4.0 * math.ulp(target):
                found[-1] = [at]
        slot = _kernels.INFO_UNREACHED_SAM if sign == 1 else _kernels.INFO_UNREACHED_LAM
        unreached += int(info[slot])
    offsets = np.sort(np.concatenate(found)) if found else np.empty(0)
    if offsets.size == 0:
        if unreached:
            raise _too_near(moments, what, reachable)
        raise _no_spin(moments, what, reachable)
    if unreached:
        warnings.warn(
            f"{plural(unreached, 'spin')} with {what} "
            f"{'lies' if unreached == 1 else 'lie'} closer than "
            "|dtheta| = 2.2e-308 to the separatrix and cannot be stored in "
            "double precision; they are left out",
            UnresolvedOrbitsWarning,
            stacklevel=caller_stacklevel(),
        )
    return offsets


def _polished(moments, offset, target):
    """The root ``offset`` of ``Delta alpha(dtheta) = target`` refined to the
    doubles' resolution.

    The search stops within ``1e-10 target`` of the target (its catalog
    tolerance).  Here the spin is the answer itself, and a period ratio
    ``Delta alpha / 2 pi - 1`` near 0 (a thin rod's long axis) magnifies that
    residual: 2e-11 rad was a P_phi 7.6e-2 off on (1e-9, 1, 1 + 1e-9 - 1e-12).
    So the root is bracketed (``Delta alpha`` is monotone on each branch:
    rising towards the separatrix) and narrowed with Brent's method
    (:func:`scipy.optimize.brentq`) to ``4 eps`` relative; the better of the
    two roots is kept.  Steps never cross the separatrix or leave
    ``[-theta_c, pi/2 - theta_c]``.
    """
    from scipy.optimize import brentq

    from .core import phase_table as _table
    from .core.phase import body_constants
    from .phases import FOLD_LIMIT

    # the kernel of orbits.phases, which gives the table's residual column
    # (total_phase's SIMD kernels can differ by an ulp or two)
    i1, i2, i3 = (np.array([float(v)]) for v in moments)
    phi, angle = np.zeros(1), np.empty(1)
    columns = np.empty((len(_table.COLUMNS), 1))
    branch, status = np.empty(1, dtype=np.int8), np.empty(1, dtype=np.int8)
    total = _table.COLUMNS.index("total_phase")

    def gap(x):
        angle[0] = x
        _table.phases_columns(i1, i2, i3, phi, angle, True, FOLD_LIMIT, columns, branch, status)
        return columns[total, 0] - target if status[0] == 0 else math.nan

    here = gap(offset)
    if here == 0.0:
        return offset
    _, _, theta_c, co_theta_c, _, _, _ = body_constants(*(float(v) for v in moments), 0.0)
    sam = offset < 0.0
    # Delta alpha rises towards the separatrix (dtheta -> 0) on each branch
    towards_zero = here < 0.0
    end = -theta_c if sam else co_theta_c
    step = abs(offset) * 2.0**-40
    low, low_gap = offset, here
    for _ in range(80):
        if towards_zero:
            moved = low + (step if sam else -step)
            if abs(moved) < 0.5 * abs(low):  # at most halfway to the separatrix
                moved = 0.5 * low
        else:
            moved = low - step if sam else low + step
            if (moved < end) if sam else (moved > end):
                moved = end
        moved_gap = gap(moved)
        if moved_gap == 0.0:
            return moved
        if math.isnan(moved_gap):
            return offset
        if (moved_gap > 0.0) != (low_gap > 0.0):
            break
        if moved == end:
            return offset if abs(here) <= abs(low_gap) else low
        low, low_gap = moved, moved_gap
        step *= 2.0
    else:
        return offset
    try:
        root = brentq(gap, min(low, moved), max(low, moved), xtol=1e-320, rtol=4.0 * 2.0**-52)
    except (ValueError, RuntimeError):
        return offset
    return root if abs(gap(root)) < abs(here) else offset


def _table(moments, offsets, targets):
    from .phases import phases

    table = phases(moments, dtheta=offsets)
    goal = np.where(
        table["branch"].astype(str) == "SAM",
        targets.get("SAM") or np.nan,
        targets.get("LAM") or np.nan,
    )
    table["target"] = goal
    table["residual"] = table["total_phase"].to_numpy() - goal
    return table


def _total_phase_at_least(branch, low):
    return f"the total phase is at least {exact_number(low)} rad ({low / TWO_PI:.12g} turns)"


def _no_spin(moments, what, reachable=None):
    """InputError: no spin has ``what``; each branch's smallest total phase, stated
    through ``reachable`` (see :func:`_solve`)."""
    from .search import branch_minima, find_roots

    reachable = reachable or _total_phase_at_least
    _, _, _, info = find_roots(moments, np.empty(0))
    parts = [
        f"on {branch} {reachable(branch, low)}, at dtheta = {at:.6g}"
        for branch, (low, at) in branch_minima(info).items()
    ]
    return InputError(
        f"no spin of this body has {what}: {parts[0]}; {parts[1]}; each grows "
        "without bound towards the separatrix"
    )


def _too_near(moments, what, reachable=None):
    """InputError: every spin with ``what`` lies nearer the separatrix than a
    double holds; the largest value each branch reaches, in the request's terms."""
    from .phases import total_phase

    sam, lam = total_phase(moments, dtheta=[-_SMALLEST_OFFSET, _SMALLEST_OFFSET])
    if reachable is _ratio_at_least:
        largest = (
            f"P_psi/P_phi is {sam / TWO_PI + 1.0:.12g} on SAM and {lam / TWO_PI - 1.0:.12g} on LAM"
        )
    else:
        largest = f"the total phase is {sam:.6f} rad on SAM and {lam:.6f} rad on LAM"
    return InputError(
        f"every spin of this body with {what} lies closer than |dtheta| = "
        f"{_SMALLEST_OFFSET:.2g} rad to the separatrix, nearer than a double holds "
        f"to full precision (the smallest normal double): at that offset {largest}"
    )


def spins_with_total_phase(body_or_moments, total_phase):
    """Every spin (``phi = 0``, both branches) whose total phase is ``total_phase``.

    Parameters
    ----------
    body_or_moments : Body or array_like, shape (3,)
    total_phase : float
        ``Delta alpha`` in radians, any positive value (``2 pi p/q`` gives
        the closed orbits of :func:`orbits.closed_orbits`).

    Returns
    -------
    pandas.DataFrame
        The rows of :func:`orbits.phases` at every root, sorted by
        ``dtheta``, plus ``target`` and ``residual = total_phase - target``:
        the search's root (``|residual| <= 1e-10 target``) refined to the
        doubles' resolution, a few ulps of ``target`` (where the phase is
        flat, next to an axis, the ulps of ``dtheta`` set it).  A target
        within 4 ulps of a branch's smallest total phase (the minimum
        itself, e.g. :func:`orbits.phase_limits` at an end) gives the spin
        of that minimum (``theta = 0`` or ``pi/2`` at an end).

    Raises
    ------
    InputError
        ``total_phase`` not finite and positive, below the smallest
        total phase of the body (no spin has it: the message gives the
        minimum), or so large that every spin with it lies closer to the
        separatrix than ``|dtheta| = 2.2e-308``, the smallest normal double
        (the message gives the total phase at that offset on each branch:
        about 2,400 rad for the Fig. 6 body).

    Warns
    -----
    UnresolvedOrbitsWarning
        Roots closer to the separatrix than the smallest normal double.

    Notes
    -----
    On each branch :math:`\\Delta\\alpha` (Mecholsky's Eq. 20) grows like
    :math:`a\\ln(1/|\\theta - \\theta_c|) + b` towards the separatrix and
    tends to Eq. (28) or (29) at the axes, so a value above both limits has
    one spin on each branch, and a value between them one spin on one
    branch.

    Examples
    --------
    >>> import numpy as np, orbits
    >>> spins = orbits.spins_with_total_phase(orbits.Body.preset("fig6"), 2 * np.pi * 3)
    >>> list(spins["branch"]), [round(t, 4) for t in spins["theta"]]
    (['SAM', 'LAM'], [1.0043, 1.0611])
    """
    moments, _ = unit_moments(body_or_moments)
    if moments.shape != (3,):
        raise InputError("spins_with_total_phase takes one body")
    target = positive_finite("total_phase", total_phase)
    described = f"total phase {exact_number(target)} rad"
    offsets = _solve(moments, {"SAM": target, "LAM": target}, described)
    return _table(moments, offsets, {"SAM": target, "LAM": target})


def spins_with_period_ratio(body_or_moments, ratio):
    """Every spin whose tumbling period ratio ``P_psi / P_phi`` is ``ratio``.

    With :meth:`orbits.Motion.tumbling_periods`, the ratio is
    ``Delta alpha / 2 pi + 1`` on SAM and ``Delta alpha / 2 pi - 1`` on LAM,
    so the spin is found as :func:`spins_with_total_phase` of
    ``2 pi (ratio - 1)`` on SAM and ``2 pi (ratio + 1)`` on LAM.  The time
    scale (``|omega0|``) then follows from either period:
    ``|omega0| = T(|omega0| = 1) / P_psi``.

    Parameters
    ----------
    body_or_moments : Body or array_like, shape (3,)
        One body (moments in any order and scale).
    ratio : float
        ``P_psi / P_phi``, positive and finite (dimensionless).

    Returns
    -------
    pandas.DataFrame
        As :func:`spins_with_total_phase`, with ``target`` the total phase
        solved for on each row's branch.

    Warns
    -----
    UnresolvedOrbitsWarning
        Roots closer to the separatrix than the smallest normal double, or
        LAM rows whose ratio ``Delta alpha / 2 pi - 1`` cancels to fewer
        digits than :data:`SPIN_VECTOR_RTOL` (a ratio near 0: a thin rod's
        long axis; the message gives the relative accuracy).

    Notes
    -----
    With the precession period :math:`P_\\phi` and the rotation period
    :math:`P_\\psi = T` of :meth:`orbits.Motion.tumbling_periods`,

    .. math::

        \\frac{P_\\psi}{P_\\phi} = \\frac{\\Delta\\alpha}{2\\pi} + 1 \\;\\text{(SAM)},
        \\qquad
        \\frac{P_\\psi}{P_\\phi} = \\frac{\\Delta\\alpha}{2\\pi} - 1 \\;\\text{(LAM)} .

    Examples
    --------
    4179 Toutatis (Hudson & Ostro 1995: :math:`P_\\psi` = 5.41 d,
    :math:`P_\\phi` = 7.35 d, a ratio below 1) can only be on LAM:

    >>> import orbits
    >>> toutatis = orbits.Body.from_semi_axes(2.30, 1.20, 0.96)
    >>> list(orbits.spins_with_period_ratio(toutatis, 5.41 / 7.35)["branch"])
    ['LAM']
    """
    table = _ratio_table(body_or_moments, ratio)
    _warn_cancelled(table, float(ratio), "P_psi/P_phi")
    return table


def _warn_cancelled(table, ratio, quantity):
    """Warn where ``P_psi/P_phi = Delta alpha / 2 pi - 1`` on the LAM rows of
    ``table`` is less accurate than :data:`SPIN_VECTOR_RTOL`: the root's
    residual and a few ulps of ``Delta alpha`` (``RATIO_ULPS``), divided by
    the ratio.  ``quantity`` names what rests on that ratio."""
    from .search import UnresolvedOrbitsWarning

    errors = []
    for branch, residual in zip(table["branch"].astype(str), table["residual"].to_numpy()):
        if branch == "LAM":
            error = (
                RATIO_ULPS * np.finfo(float).eps * (ratio + 1.0) + abs(residual) / TWO_PI
            ) / ratio
            if not error <= SPIN_VECTOR_RTOL:
                errors.append(error)
    if errors:
        warnings.warn(
            f"{quantity} of {plural(len(errors), 'LAM row')} rests on P_psi / P_phi = "
            "Delta alpha / 2 pi - 1 with Delta alpha so near 2 pi (a thin rod's long "
            f"axis) that the difference keeps it only to about {max(errors):.1g} "
            "(relative); the spin's total phase and P_psi are accurate",
            UnresolvedOrbitsWarning,
            stacklevel=caller_stacklevel(),
        )


def _ratio_table(body_or_moments, ratio):
    """:func:`spins_with_period_ratio` without its warning of a cancelling ratio."""
    moments, _ = unit_moments(body_or_moments)
    if moments.shape != (3,):
        raise InputError("spins_with_period_ratio takes one body")
    ratio = positive_finite("ratio", ratio)
    targets = {
        "SAM": TWO_PI * (ratio - 1.0) if ratio > 1.0 else None,
        "LAM": TWO_PI * (ratio + 1.0),
    }
    offsets = _solve(
        moments, targets, f"period ratio P_psi/P_phi = {exact_number(ratio)}", _ratio_at_least
    )
    return _table(moments, offsets, targets)


def _ratio_at_least(branch, low):
    """The smallest ``P_psi/P_phi`` of a branch whose smallest total phase is ``low``."""
    turns = low / TWO_PI
    return f"P_psi/P_phi is at least {turns + 1.0 if branch == 'SAM' else turns - 1.0:.12g}"


def spins_with_periods(body_or_moments, p_psi, p_phi):
    """Every spin of a tumbling body with the observed periods ``P_psi`` and ``P_phi``.

    The convention of Pravec et al. (2005, Icarus 173, 108) and
    :meth:`orbits.Motion.tumbling_periods`: ``P_psi`` the rotation period
    (the period T of eqn:TK), ``P_phi`` the mean precession period of the
    short (SAM) or long (LAM) axis about L.  The ratio fixes the orbit
    (:func:`spins_with_period_ratio`); ``P_psi`` then fixes the time scale,
    ``|omega0| = T(|omega0| = 1) / P_psi``.

    Parameters
    ----------
    body_or_moments : Body or array_like, shape (3,)
        The moments in any unit and scale (asteroids: ratios, e.g.
        ``(0.61, 0.965, 1)``).
    p_psi, p_phi : float
        The periods, in any one time unit: every result is in that unit.

    Returns
    -------
    pandas.DataFrame
        One row per spin, sorted by ``dtheta``: ``branch``, ``axis``
        (``"short"``/``"long"``), ``P_psi`` and ``P_phi`` recomputed from
        the spin (:meth:`~orbits.Motion.tumbling_periods`), ``P_about_L``
        (``2 pi T / Delta alpha``), ``E_over_E0`` (Pravec's
        ``E/E0 = 2 E I3 / M^2 = I3/D``, 1 for a spin about the short axis,
        ``I3/I2`` on the separatrix), ``theta`` and ``dtheta`` (radians,
        ``phi = 0``), ``w1, w2, w3`` (the starting spin in the principal
        axes, radians per time unit), ``energy``, ``momentum`` (in the
        moments' unit and that time unit), ``D`` and ``total_phase``.
        Every column but ``w1, w2, w3`` and ``theta`` is of the orbit of
        ``dtheta``; those are doubles, which next to the separatrix round
        the orbit (a spin vector resolves ``dtheta`` only to ~1e-16): where
        started from them the periods would be more than
        :data:`SPIN_VECTOR_RTOL` off, an
        :class:`~orbits.UnresolvedOrbitsWarning` says so.

    Raises
    ------
    InputError
        A period not finite and positive, no spin with that ratio, or a
        ``P_psi`` whose spin (``|omega0|``, its energy or momentum) does not
        fit a normal double: the periods (or moments) need other units.
    """
    import pandas as pd

    from .motion import Motion, as_body
    from .search import UnresolvedOrbitsWarning

    body = as_body(body_or_moments)
    p_psi = positive_finite("P_psi", p_psi)
    p_phi = positive_finite("P_phi", p_phi)
    ratio = p_psi / p_phi
    if not 0.0 < ratio < math.inf:
        raise InputError(
            f"P_psi / P_phi = {p_psi!r} / {p_phi!r} does not fit a double: give the "
            "periods in one time unit (their ratio is what fixes the orbit)"
        )
    table = _ratio_table(body, ratio)
    rows, loose = [], []
    i3 = float(body.moments[2])
    for dtheta, theta in zip(table["dtheta"].to_numpy(), table["theta"].to_numpy()):
        unit = Motion.from_spin(body, dtheta=float(dtheta))
        speed = unit.period / p_psi
        # |omega0| = T(1) / P_psi, the energy ~ |omega|^2 I3 and the momentum
        # ~ |omega| I3 of the spin must all be normal doubles
        scales = (speed, speed * speed * i3, speed * i3)
        if not all(_TINY <= value <= _HUGE for value in scales):
            raise InputError(
                f"P_psi = {p_psi!r} needs |omega0| = {speed:.3g} rad per time unit, "
                "whose energy or momentum with these moments does not fit a double: "
                "give the periods (or the moments) in other units"
            )
        motion = Motion.from_spin(body, dtheta=float(dtheta), speed=speed)
        periods = motion.tumbling_periods()
        rounded = _rounded_spin(body, motion, periods)
        if rounded is not None:
            loose.append(rounded)
        rows.append(
            {
                "branch": motion.branch,
                "axis": periods.axis,
                "P_psi": periods.rotation,
                "P_phi": periods.precession,
                "P_about_L": periods.about_momentum,
                "E_over_E0": i3 / motion.D,
                "theta": float(theta),
                "dtheta": float(dtheta),
                "w1": float(motion.omega0[0]),
                "w2": float(motion.omega0[1]),
                "w3": float(motion.omega0[2]),
                "energy": motion.energy,
                "momentum": motion.momentum,
                "D": motion.D,
                "total_phase": motion.total_phase(),
            }
        )
    _warn_cancelled(table, ratio, "P_phi")
    if loose:
        branch, off = max(loose, key=lambda item: item[1])
        warnings.warn(
            f"the spin vector w1, w2, w3 (and theta) of {plural(len(loose), 'row')} "
            f"round the orbit (dtheta so near the separatrix that a double spin does "
            f"not hold it): started from w, the periods are up to {off:.2g} "
            f"(relative) off ({branch}); the periods, E_over_E0 and dtheta are the "
            "orbit's: start from dtheta (Motion.from_spin(body, dtheta=..., speed=...))",
            UnresolvedOrbitsWarning,
            stacklevel=caller_stacklevel(),
        )
    return pd.DataFrame(rows)


# the spin vector of spins_with_periods must give its periods to this
# (relative) accuracy, or a warning says it does not hold the orbit
SPIN_VECTOR_RTOL = 1e-9
# the ulps of Delta alpha that P_psi / P_phi = Delta alpha / 2 pi - 1 inherits
# on LAM (measured: at most 0.6 eps / ratio on thin rods, ratios 1e-8 to 1e-11)
RATIO_ULPS = 4.0


def _rounded_spin(body, motion, periods):
    """``(branch, relative error)`` when the double ``motion.omega0``, started
    from as given, has periods more than SPIN_VECTOR_RTOL off; else None."""
    from .errors import OrbitsError
    from .motion import Motion

    try:
        again = Motion(body, motion.omega0).tumbling_periods()
        off = max(
            abs(again.rotation / periods.rotation - 1.0),
            abs(again.precession / periods.precession - 1.0),
        )
    except OrbitsError:  # the rounded vector lies on the separatrix itself
        off = math.inf
    return (motion.branch, off) if not off <= SPIN_VECTOR_RTOL else None
