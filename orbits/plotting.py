"""Plotting primitives: each draws one kind of figure into a given Axes.

These functions take a matplotlib ``Axes`` (3-D ones where noted) so that
users can compose their own figures; :mod:`orbits.figures` assembles them
into files.  They never call ``pyplot`` and need no display.

Conventions as everywhere in ``orbits``: ``|I| = 1``, ``|omega0| = 1``,
angles in radians, the herpolhode drawn in the invariable plane (space
frame, z along the angular momentum).  :func:`plot_herpolhode`,
:func:`plot_omega_components` and :func:`plot_binet` also take a
:class:`orbits.Motion` in place of ``body`` (and no angles): they then draw
that motion with its moments and spin as given, so a body in kg m^2 spun
in rad/s is drawn in s, rad/s and J s (the axis labels).
"""

import math

import numpy as np

from ._args import flag, given_besides, integer, positive_finite, real_array, real_scalar
from .bodies import REGION_BOX, Body, region_moments
from .cells import literal_text
from .errors import InputError
from .limits import check_resolution
from .motion import MAX_POINTS, Motion, as_body, herpolhode, polhode
from .phases import critical_angle, phase_limits, phases, total_phase

TWO_PI = 2.0 * np.pi
# the paper's line styles (Fig. 3b, Fig. 5)
STYLES = {
    "total": dict(color="tab:red", linestyle="-"),
    "dynamic": dict(color="tab:green", linestyle=":"),
    "geometric": dict(color="tab:blue", linestyle="-."),
    "period": dict(color="black", linestyle="--"),
}


# samples a turn of a drawn herpolhode: 600, fewer beyond CURVE_POINTS samples
# (3333 turns), never fewer than 100: a turn's chord then stays within
# 1 - cos(pi/100) = 5e-4 of its radius (0.15 pixel at the 300 pixels of
# r_max in a single figure at 150 dpi), and the turns of so long a curve lie
# far closer together than a pixel
SAMPLES_PER_TURN = 600
MIN_SAMPLES_PER_TURN = 100
CURVE_POINTS = 2_000_000
# the most turns a drawn herpolhode may make: MAX_POINTS samples at the least
MAX_TURNS = (MAX_POINTS - 1) // MIN_SAMPLES_PER_TURN


def herpolhode_points(n, q=1):
    """Samples enough to draw a herpolhode of ``n`` turns over ``q`` periods.

    :data:`SAMPLES_PER_TURN` a turn up to :data:`CURVE_POINTS` samples;
    a longer curve keeps that many, but never fewer than
    :data:`MIN_SAMPLES_PER_TURN` a turn; at least 2001.  It may exceed
    :data:`orbits.motion.MAX_POINTS` (more than :data:`MAX_TURNS` turns):
    callers refuse such a curve (:func:`check_turns`).
    """
    turns = n * q
    wanted = min(SAMPLES_PER_TURN * turns, max(CURVE_POINTS, MIN_SAMPLES_PER_TURN * turns))
    return int(max(2001, wanted + 1))


def check_turns(turns, what="this herpolhode", advice="lower periods"):
    """Refuse a herpolhode of more than :data:`MAX_TURNS` turns (samples beyond MAX_POINTS).

    Raises
    ------
    InputError
        Naming ``what`` and ending with ``advice`` (the caller's option).
    """
    # herpolhode_points(turns) <= MAX_POINTS; also refuses NaN and inf
    if not MIN_SAMPLES_PER_TURN * turns + 1 <= MAX_POINTS:
        raise InputError(
            f"{what} makes about {turns:.4g} turns, more than the {MAX_TURNS} a drawn "
            f"curve may have ({MAX_POINTS} samples, {MIN_SAMPLES_PER_TURN} a turn); {advice}"
        )


def _end_time(periods, period):
    """The end of a time axis of ``periods`` periods ``period``, or an InputError."""
    end = periods * period
    if not math.isfinite(end):
        raise InputError(f"periods = {periods!r} periods overflow the time axis")
    return end


def _no_angles_with_motion(theta, dtheta, phi, where):
    """Refuse angles given with a :class:`orbits.Motion`, which has its own spin
    (they were ignored: ``plot_herpolhode(ax, motion, 1.2)`` drew the motion's
    theta = 0.5 curve; an audit)."""
    given = given_besides(theta=(theta, None), dtheta=(dtheta, None), phi=(phi, 0.0))
    if given:
        raise InputError(
            f"{where}: {' and '.join(given)} given with a Motion, which has its own spin; "
            "give the body and the angles, or the Motion alone"
        )


def plot_herpolhode(
    ax, body, theta=None, *, dtheta=None, phi=0.0, periods=1, points=None, label_axes=True, **line
):
    """Draw a herpolhode (space-frame omega in the invariable plane).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    body, theta, dtheta, phi : as :func:`orbits.herpolhode`
        Or ``body`` a :class:`orbits.Motion` (no angles): its own spin.
    periods : float
        Periods to draw, positive (a closed orbit's herpolhode closes
        after its catalog's ``closes_after``: 1/2 for odd n, q/2 when p
        and q are odd, else q).
    points : int, optional
        Samples; by default enough for the curve's turns.
    label_axes : bool
        Label the axes omega_x, omega_y and set an equal aspect ratio.
    **line
        Passed to ``ax.plot``.

    Returns
    -------
    matplotlib.lines.Line2D
        Its data are the curve: ``line.get_xydata()``.

    Raises
    ------
    InputError
        ``periods`` not positive and finite, ``points`` not an integer from
        2 to :data:`orbits.motion.MAX_POINTS`, (``points`` omitted) a
        curve of more than :data:`MAX_TURNS` turns, or ``theta``,
        ``dtheta`` or a non-zero ``phi`` with a :class:`orbits.Motion`.
    """
    periods = positive_finite("periods", periods)
    if points is not None:
        points = integer("points", points, minimum=2, maximum=MAX_POINTS)
    if isinstance(body, Motion):
        _no_angles_with_motion(theta, dtheta, phi, "plot_herpolhode")
        if points is None:
            turns = abs(body.total_phase()) / TWO_PI * periods
            check_turns(turns, f"the herpolhode over periods={periods:g}", "lower periods")
            points = herpolhode_points(turns)
        omega = body.omega_space(np.linspace(0.0, _end_time(periods, body.period), points))
    else:
        if points is None:
            turns = abs(float(total_phase(body, theta, dtheta=dtheta, phi=phi))) / TWO_PI
            check_turns(
                turns * periods, f"the herpolhode over periods={periods:g}", "lower periods"
            )
            points = herpolhode_points(turns, periods)
        _, omega = herpolhode(body, theta, dtheta=dtheta, phi=phi, periods=periods, points=points)
    style = dict(color="tab:purple", linewidth=0.8)
    style.update(line)
    (curve,) = ax.plot(omega[:, 0], omega[:, 1], **style)
    ax.set_aspect("equal", adjustable="datalim")
    if label_axes:
        ax.set_xlabel(r"$\omega_x$ (rad/s, invariable plane)")
        ax.set_ylabel(r"$\omega_y$ (rad/s)")
    return curve


def herpolhode_radii(body, theta=None, *, dtheta=None, phi=0.0):
    """The radii of the two circles that bound a herpolhode, ``|omega0| = 1``.

    In the invariable plane the herpolhode point is at distance
    ``r = sqrt(|omega|^2 - (2E/M)^2)`` from the L axis (``omega . M/M = 2E/M``
    is constant).  ``|omega|^2 = sum M_k^2 / I_k^2`` is extreme where the
    polhode crosses a principal plane (one ``M_k = 0``; those crossings are
    the turning points of the Jacobi functions, eqns. Omegas): ``M_1 = 0``
    or ``M_2 = 0`` on SAM (the polhode circles I3), ``M_2 = 0`` or
    ``M_3 = 0`` on LAM (it circles I1).  With ``M_k = 0`` the other two
    follow from the invariants ``M_i^2 + M_j^2 = M^2`` (eqn:MM) and
    ``M_i^2/I_i + M_j^2/I_j = 2E`` (eqn:EM).  The herpolhode touches both
    circles (Landau & Lifshitz, Mechanics, Sec. 37).

    Parameters
    ----------
    body, theta, dtheta, phi : as :func:`orbits.herpolhode`

    Returns
    -------
    r_min, r_max : float
        In rad/s for ``|omega0| = 1``.  ``r = |omega x M| / M`` at the
        crossing, with ``|omega x M| = |omega_i omega_j (I_j - I_i)|``: no
        difference of nearly equal numbers, also for a near-spherical body.
    """
    motion = Motion.from_spin(as_body(body), theta, dtheta=dtheta, phi=phi)
    i1, i2, i3 = motion.body.unit_moments.tolist()
    m1, m2, m3 = (motion.body.unit_moments * motion.omega0).tolist()  # M(0), principal axes
    # M_k^2 at the crossings, in sums of positive terms (eqn:MM, eqn:EM):
    # the moment differences are exact, so nothing cancels for a
    # near-spherical body, and the crossing next to the I2 axis (M_k^2 ~
    # M^2 - 2 E I2 -> 0 at the separatrix) goes through the factored 1 - k^2
    m_sq = m1 * m1 + m2 * m2 + m3 * m3
    crossing_2 = (  # M_2 = 0, on both branches: (M_1^2, M_3^2)
        m1 * m1 + m2 * m2 * (i3 - i2) * i1 / (i2 * (i3 - i1)),
        m3 * m3 + m2 * m2 * (i2 - i1) * i3 / (i2 * (i3 - i1)),
    )
    if motion.branch == "SAM":  # M_1 = 0 next to I2: M_3^2 = (M^2 - 2E I2) I3/(I3 - I2)
        above = m2 * m2 * (i2 - i1) / i2 + m3 * m3 * (i3 - i1) / i3  # M^2 - 2 E I1
        small = motion.one_minus_m * above * i3 / (i3 - i1)
        middle = m2 * m2 + m1 * m1 * (i3 - i1) * i2 / (i1 * (i3 - i2))  # M_2^2
        crossings = (crossing_2, (middle, small))
        pairs = ((i1, i3), (i2, i3))
    else:  # M_3 = 0 next to I2: M_1^2 = (2E I2 - M^2) I1/(I2 - I1)
        below = m1 * m1 * (i3 - i1) / i1 + m2 * m2 * (i3 - i2) / i2  # 2 E I3 - M^2
        small = motion.one_minus_m * below * i1 / (i3 - i1)
        middle = m2 * m2 + m3 * m3 * (i3 - i1) * i2 / (i3 * (i2 - i1))  # M_2^2
        crossings = (crossing_2, (small, middle))
        pairs = ((i1, i3), (i1, i2))
    radii = []
    for (mi2, mj2), (a, b) in zip(crossings, pairs):
        # r = |omega x M| / M = |omega_i omega_j (I_j - I_i)| / M, omega_k = M_k / I_k
        r = (
            math.sqrt(max(mi2, 0.0))
            * math.sqrt(max(mj2, 0.0))
            * (b - a)
            / (a * b * math.sqrt(m_sq))
        )
        radii.append(r)
    return min(radii), max(radii)


def mark_herpolhode(ax, curve, radii, *, arrow_length=0.18, color=None, centre_label=True):
    """Start marker, direction arrow, the L axis and the bounding circles.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    curve : Line2D
        A herpolhode drawn by :func:`plot_herpolhode`.
    radii : (float, float)
        ``r_min, r_max`` from :func:`herpolhode_radii`: drawn dashed.
    arrow_length : float
        The arrow follows the curve from its start for this fraction of
        ``r_max`` (arc length), pointing along the motion.
    centre_label : bool
        Write "L" by the centre mark.

    Returns
    -------
    dict
        ``start`` (Line2D marker at t = 0), ``arrow`` (Annotation from the
        start along the curve), ``centre`` (Line2D at the origin: the L
        axis), ``circles`` (two Circle patches, r_min and r_max).
    """
    centre_label = flag("centre_label", centre_label)  # before anything is drawn
    from matplotlib.patches import Circle

    color = color or curve.get_color()
    xy = curve.get_xydata()
    circles = []
    for radius in radii:
        circle = Circle(
            (0.0, 0.0),
            radius,
            fill=False,
            linestyle=(0, (4, 3)),
            linewidth=0.6,
            edgecolor="0.55",
            zorder=1,
        )
        ax.add_patch(circle)
        circles.append(circle)
    (centre,) = ax.plot(
        [0.0],
        [0.0],
        marker="+",
        color="black",
        markersize=6,
        markeredgewidth=0.9,
        linestyle="none",
        zorder=3,
    )
    if centre_label:
        ax.annotate("L", (0.0, 0.0), xytext=(3, 3), textcoords="offset points", fontsize="x-small")
    (start,) = ax.plot(
        xy[:1, 0], xy[:1, 1], marker="o", color=color, markersize=4, linestyle="none", zorder=4
    )
    steps = np.hypot(*np.diff(xy, axis=0).T)
    travelled = np.concatenate([[0.0], np.cumsum(steps)])
    end = int(np.searchsorted(travelled, arrow_length * max(radii[1], 1e-300)))
    end = min(max(end, 1), len(xy) - 1)
    arrow = ax.annotate(
        "",
        xy=tuple(xy[end]),
        xytext=tuple(xy[0]),
        arrowprops=dict(
            arrowstyle="-|>", color=color, linewidth=1.0, mutation_scale=9, shrinkA=0, shrinkB=0
        ),
        zorder=4,
    )
    return {"start": start, "arrow": arrow, "centre": centre, "circles": circles}


def closing_periods(row):
    """Periods after which a catalog row's herpolhode closes, a Fraction
    (``closes_after``; q where the row has none or NaN)."""
    from fractions import Fraction

    value = getattr(row, "closes_after", None)
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return Fraction(int(row.q))
    return Fraction(str(value))


def drawn_periods(row):
    """Periods over which a catalog row's herpolhode closes, a float
    (:func:`closing_periods`)."""
    return float(closing_periods(row))


def theta_text(theta, dtheta, precision=5):
    """``theta = ...``, or ``theta - theta_c`` in scientific notation when theta
    rounds to theta_c at ``precision`` decimals (so near-separatrix rows differ)."""
    theta_c = theta - dtheta
    if round(theta, precision) == round(theta_c, precision):
        return rf"$\theta-\theta_c$ = {dtheta:.3e}"
    return rf"$\theta$ = {theta:.{precision}f}"


def orbit_label(row, body_name=None, precision=6):
    """A figure title for a catalog row: multiple, branch, theta, body, closure."""
    multiple = f"{row.n}" if row.q == 1 else f"{row.n}/{row.q}"
    name = f"{literal_text(body_name)}: " if body_name else ""
    text = (
        rf"{name}$\Delta\alpha = 2\pi\cdot{multiple}$, {row.branch}, "
        rf"$\theta$ = {row.theta:.{precision}f}"
        + "\n"
        + rf"$\theta-\theta_c$ = {row.dtheta:.3e} rad"
    )
    closes = closing_periods(row)
    if closes != 1:  # T/2 for odd n; q/2 or q periods for p/q
        text += f"; closes after {closes} T (drawn once)"
    return text


def plot_phase_curves(ax, body, *, points=1500, period_axis=True):
    """Total, dynamic and geometric phase against theta (Fig. 5).

    The period goes on a twin y axis (dashed black); the critical angle is
    a gray vertical line.  Each curve is broken (a NaN point) at theta_c,
    where the geometric phase jumps: no segment joins the two branches.

    Parameters
    ----------
    points : int
        Samples of theta, from 4 to :data:`MAX_THETA_POINTS`.

    Returns
    -------
    dict
        The lines by name (``total``, ``dynamic``, ``geometric``,
        ``period``) and the twin axes under ``period_axes``.
    """
    period_axis = flag("period_axis", period_axis)  # before anything is drawn
    points = _theta_points(points)
    body = as_body(body)
    theta_c = critical_angle(body)
    grid = _theta_grid(theta_c, points)
    table = phases(body, grid)
    split = int(np.searchsorted(grid, theta_c))
    theta = np.insert(grid, split, np.nan)

    def broken(column):
        return np.insert(np.asarray(table[column], dtype=float), split, np.nan)

    lines = {}
    for name, column, label in (
        ("total", "total_phase", r"total $\Delta\alpha$"),
        ("dynamic", "dynamic_phase", r"dynamic $2ET/M$"),
        ("geometric", "geometric_phase", r"geometric $\Omega$"),
    ):
        (lines[name],) = ax.plot(theta, broken(column), label=label, **STYLES[name])
    ax.axvline(theta_c, color="0.6", linewidth=1.0)
    ax.set_xlabel(r"polar angle of $\omega_0$ from the body $z$ axis, $\theta$ (rad)")
    ax.set_ylabel("phase (rad)")
    ax.set_xlim(0.0, 0.5 * np.pi)
    top = float(np.nanpercentile(table["dynamic_phase"], 90))
    ax.set_ylim(min(0.0, float(table["geometric_phase"].min())) - 1.0, top)
    handles = list(lines.values())
    if period_axis:
        twin = ax.twinx()
        (lines["period"],) = twin.plot(
            theta, broken("period"), label="period $T$", **STYLES["period"]
        )
        twin.set_ylabel(r"period $T$ (s, for $|\omega_0| = 1$ rad/s)")
        twin.set_ylim(0.0, float(np.nanpercentile(table["period"], 90)))
        lines["period_axes"] = twin
        handles.append(lines["period"])
    ax.legend(handles=handles, loc="upper left", fontsize="small")
    return lines


# the most samples of theta in a phase plot: the grid clusters at theta_c as
# s^3 (s = 2/points at the nearest sample), which must stay clear of its
# rounding error (4 ulp, ~1e-15 relative): s^3 = 8e-15 at 10^5 samples
MAX_THETA_POINTS = 100_000


def _theta_points(points):
    """``points`` of a phase plot: an integer from 4 to :data:`MAX_THETA_POINTS`."""
    return integer("points", points, minimum=4, maximum=MAX_THETA_POINTS)


def _theta_grid(theta_c, points):
    """Theta over [0, pi/2], clustered (cubically) at theta_c, never on it."""
    s = np.linspace(0.0, 1.0, points // 2)[1:]
    left = theta_c * (1.0 - s**3)
    right = theta_c + (0.5 * np.pi - theta_c) * s**3
    grid = np.unique(np.concatenate([left, right]))
    return grid[grid != theta_c]


# the most levels 2 pi n drawn (a line and a named tick each: ~30 s for 1000)
MAX_LEVELS = 1000


def plot_total_phase(ax, body, orbits=None, *, n_levels=None, points=2000, legend=True):
    """Total phase against theta with the 2 pi n levels and roots (Fig. 6).

    Parameters
    ----------
    orbits : DataFrame, optional
        Catalog rows (:func:`orbits.closed_orbits`) to mark as dots.
    n_levels : int, optional
        Draw the levels 2 pi n for n up to this, at most
        :data:`MAX_LEVELS` (default: those in view).
    points : int
        Samples of theta, from 4 to :data:`MAX_THETA_POINTS`.

    Returns
    -------
    dict
        ``curve`` (Line2D), ``levels`` (list of Line2D), ``roots``
        (PathCollection or None), ``level_axis`` (the right-hand axis that
        names the levels).
    """
    legend = flag("legend", legend)  # before anything is drawn
    points = _theta_points(points)
    if n_levels is not None:
        n_levels = integer("n_levels", n_levels, minimum=1, maximum=MAX_LEVELS)
    body = as_body(body)
    theta_c = critical_angle(body)
    theta = _theta_grid(theta_c, points)
    values = total_phase(body, theta)
    (curve,) = ax.plot(
        theta, values, label=r"total phase $\Delta\alpha(\theta)$", **STYLES["total"]
    )
    top = 2 * np.pi * (n_levels + 0.5) if n_levels else float(np.percentile(values, 85))
    ax.set_ylim(0.0, top)
    ax.set_xlim(0.0, 0.5 * np.pi)
    levels = []
    count = int(top / TWO_PI)
    for n in range(1, count + 1):
        levels.append(ax.axhline(TWO_PI * n, color="0.75", linewidth=0.6, zorder=0))
    # the levels are named on a right-hand axis, outside the data (nothing covers them)
    named = ax.secondary_yaxis("right")
    named.set_yticks(
        TWO_PI * np.arange(1, count + 1), [rf"$2\pi\cdot{n}$" for n in range(1, count + 1)]
    )
    named.tick_params(labelsize="small", colors="0.3")
    ax.axvline(theta_c, color="0.6", linewidth=1.0)
    roots = None
    if orbits is not None and len(orbits):
        shown = orbits[orbits["total_phase"] <= top]
        roots = ax.scatter(
            shown["theta"],
            shown["total_phase"],
            s=14,
            color="black",
            zorder=3,
            label=r"closed orbits, $\Delta\alpha = 2\pi n$",
        )
    ax.set_xlabel(r"polar angle of $\omega_0$ from the body $z$ axis, $\theta$ (rad)")
    ax.set_ylabel(r"total phase $\Delta\alpha$ (rad)")
    if legend:
        ax.legend(loc="upper left", fontsize="small")
    return {"curve": curve, "levels": levels, "roots": roots, "level_axis": named}


def body_space_grid(resolution=300):
    """The minimum total phase on a grid over the body region (Fig. 2 data).

    Returns
    -------
    i1, i2 : ndarray (N, N)
        Grid of the paper's I1-I2 plane (``|I| = 1``).
    minimum : ndarray (N, N)
        The minimum of Delta alpha over all spins (phi = 0) of each body,
        from the closed-orbit scan (:func:`orbits.minimum_phase`); NaN
        outside the region.
    """
    from .search import minimum_phase

    (lo1, hi1), (lo2, hi2) = REGION_BOX
    axis1 = np.linspace(lo1, hi1, resolution)
    axis2 = np.linspace(lo2, hi2, resolution)
    i1, i2 = np.meshgrid(axis1, axis2, indexing="xy")
    moments, inside = region_moments(i1, i2)
    minimum = np.full(i1.shape, np.nan)
    for index in zip(*np.nonzero(inside)):
        minimum[index] = minimum_phase(moments[index])[0]
    return i1, i2, minimum


def region_boundaries(samples=400):
    """The prolate, oblate and flat boundary curves of the body region.

    Returns a dict of name -> (I1, I2) arrays (the paper's Sec. II.A).
    """
    rod_to_sphere = np.linspace(0.0, 1.0 / np.sqrt(3.0), samples)
    disk_to_sphere = np.linspace(1.0 / np.sqrt(6.0), 1.0 / np.sqrt(3.0), samples)
    rod_to_disk = np.linspace(0.0, 1.0 / np.sqrt(6.0), samples)
    return {
        "prolate": (rod_to_sphere, np.sqrt((1.0 - rod_to_sphere**2) / 2.0)),
        "oblate": (disk_to_sphere, disk_to_sphere),
        "flat": (rod_to_disk, 0.5 * (np.sqrt(2.0 - 3.0 * rod_to_disk**2) - rod_to_disk)),
    }


def kink_locus(samples=400):
    """Where the two limits (eqns alphamin1, alphamin2) are equal.

    ``I1 I2 / ((I3-I2)(I3-I1)) = I2 I3 / ((I2-I1)(I3-I1))`` reduces to
    ``I1 (I2 - I1) = I3 (I3 - I2)``, i.e. ``theta_c = pi/4``.  Returns
    (I1, I2) arrays of the curve inside the region.
    """
    from scipy.optimize import brentq

    points = []
    for value in np.linspace(1e-4, 1.0 / np.sqrt(3.0) - 1e-6, samples):

        def gap(i2):
            i3 = np.sqrt(max(1.0 - value**2 - i2**2, 0.0))
            return value * (i2 - value) - i3 * (i3 - i2)

        lo = max(value, 0.5 * (np.sqrt(2.0 - 3.0 * value**2) - value))
        hi = np.sqrt((1.0 - value**2) / 2.0)
        if lo < hi and gap(lo) * gap(hi) < 0:
            points.append((value, brentq(gap, lo, hi, xtol=1e-14)))
    points = np.array(points)
    return points[:, 0], points[:, 1]


DEFAULT_CONTOURS = TWO_PI * np.array([1.02, 1.05, 1.1, 1.2, 1.35, 1.5, 2.0, 3.0, 5.0])


def plot_body_space(ax, grid=None, *, resolution=300, levels=None, colorbar=True):
    """The body-space map of Fig. 2.

    Parameters
    ----------
    grid : tuple (i1, i2, minimum), optional
        From :func:`body_space_grid` or a survey; computed if omitted.
    resolution : int
        Grid points a side when ``grid`` is omitted, from 2 up to what
        :func:`orbits.limits.check_resolution` allows.
    levels : array_like, optional
        Contour levels of the minimum total phase (rad): finite, increasing,
        each above ``2 pi`` (the smallest minimum); default
        :data:`DEFAULT_CONTOURS`.  Empty: the map without contours.

    Returns
    -------
    dict
        ``contours`` (ContourSet), ``boundaries`` (dict of Line2D), ``kink``
        (Line2D), ``filled`` (the filled ContourSet), ``colorbar``.
    """
    colorbar = flag("colorbar", colorbar)  # before anything is drawn
    if grid is None:
        grid = body_space_grid(check_resolution(resolution))
    i1, i2, minimum = grid
    if levels is None:
        levels = DEFAULT_CONTOURS
    else:
        levels = np.atleast_1d(real_array("levels", levels))
        if levels.ndim != 1 or not (
            np.all(np.isfinite(levels)) and np.all(levels > TWO_PI) and np.all(np.diff(levels) > 0)
        ):
            raise InputError(
                "levels must be finite, increasing and above 2 pi (6.283185...; the "
                f"smallest minimum total phase), got {levels.tolist()}"
            )
    # above the top level: the colour bar's "over" triangle (a band up to a
    # fixed 8 2 pi, clipped there, painted bodies far above it, up to
    # 200 2 pi near the sphere, in that band's colour and left the triangle
    # unused); the clip only keeps infinities out of contourf
    filled = ax.contourf(
        i1,
        i2,
        np.minimum(minimum, 2.0 * (levels[-1] if levels.size else TWO_PI)),
        levels=np.concatenate([[TWO_PI], levels]) if levels.size else [TWO_PI, 2.0 * TWO_PI],
        cmap="viridis",
        extend="max",
    )
    contours = ax.contour(i1, i2, minimum, levels=levels, colors="white", linewidths=0.7)
    ax.clabel(contours, fmt=lambda v: rf"{v / TWO_PI:.2f}$\cdot 2\pi$", fontsize="xx-small")
    boundaries = {}
    for name, (x, y) in region_boundaries().items():
        (boundaries[name],) = ax.plot(x, y, color="tab:red", linewidth=1.5)
    label_at = {"prolate": (0.2, 0.697), "oblate": (0.47, 0.45), "flat": (0.12, 0.6)}
    for name, (x, y) in label_at.items():
        ax.annotate(name, (x, y), color="tab:red", fontsize="small", va="bottom")
    x, y = kink_locus()
    (kink,) = ax.plot(
        x,
        y,
        color="white",
        linestyle="--",
        linewidth=1.0,
        label=r"kinks: $\Delta\alpha_{\theta\to0} = \Delta\alpha_{\theta\to\pi/2}$",
    )
    ax.set_xlabel(r"$I_1\,/\,|I|$")
    ax.set_ylabel(r"$I_2\,/\,|I|$")
    ax.set_aspect("equal")
    (lo1, hi1), (lo2, hi2) = REGION_BOX
    ax.set_xlim(lo1, hi1 + 0.01)
    ax.set_ylim(lo2 - 0.01, hi2 + 0.025)
    ax.legend(loc="lower right", fontsize="x-small", facecolor="0.3", labelcolor="white")
    bar = None
    if colorbar:
        bar = ax.figure.colorbar(filled, ax=ax, shrink=0.75)
        bar.set_ticks(levels)
        bar.set_ticklabels([rf"{v / TWO_PI:.2f}$\cdot 2\pi$" for v in levels])
        bar.set_label(r"minimum total phase over all spins, $\min_\theta \Delta\alpha$ (rad)")
    return {
        "contours": contours,
        "filled": filled,
        "boundaries": boundaries,
        "kink": kink,
        "colorbar": bar,
    }


def _ellipsoid_surface(semi_axes, center=(0.0, 0.0, 0.0), resolution=40):
    u = np.linspace(0.0, 2.0 * np.pi, resolution)
    v = np.linspace(0.0, np.pi, resolution // 2)
    x = semi_axes[0] * np.outer(np.cos(u), np.sin(v)) + center[0]
    y = semi_axes[1] * np.outer(np.sin(u), np.sin(v)) + center[1]
    z = semi_axes[2] * np.outer(np.ones_like(u), np.cos(v)) + center[2]
    return x, y, z


def box_faces(lo, hi):
    """The six faces of the axis-aligned box with corners ``lo`` and ``hi``, as (4, 3) arrays."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    corners = np.array(
        [
            [x0, y0, z0],
            [x1, y0, z0],
            [x1, y1, z0],
            [x0, y1, z0],
            [x0, y0, z1],
            [x1, y0, z1],
            [x1, y1, z1],
            [x0, y1, z1],
        ]
    )
    faces = [[0, 1, 2, 3], [4, 5, 6, 7], [0, 1, 5, 4], [2, 3, 7, 6], [1, 2, 6, 5], [0, 3, 7, 4]]
    return [corners[f] for f in faces]


def plot_t_handle(ax3d, l1=8.0, l2=4.0, w=1.0, *, shrink=0.25, bars="solid", ellipsoid=True):
    """The T-handle and its equivalent ellipsoid, in 3-D (Fig. 1).

    The cross piece lies along x, the shaft along y (from the cross piece's
    edge), both of square section w; the ellipsoid with the same principal
    moments (semi-axes from :meth:`Body.equivalent_ellipsoid`) is drawn at
    the centre of mass, shrunk by ``shrink`` (the paper: 1/4).

    Parameters
    ----------
    l1, l2, w : float
        Lengths of the cross piece and the shaft, and the section's side
        (positive, as :meth:`Body.t_handle`).
    shrink : float
        Scale of the drawn ellipsoid, positive.
    bars : {"solid", "outline"}
        Shaded bars, or their edges only (to show the ellipsoid inside).
    ellipsoid : bool
        Draw the equivalent ellipsoid.

    Returns
    -------
    dict
        ``bars`` (Poly3DCollection), ``boxes`` (the two bars' corner
        pairs), ``ellipsoid`` (surface) and ``semi_axes`` (the unshrunk
        a, b, c).
    """
    ellipsoid = flag("ellipsoid", ellipsoid)  # before anything is drawn
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    if not isinstance(bars, str) or bars not in ("solid", "outline"):
        raise InputError(f"bars must be 'solid' or 'outline', got {bars!r}")
    shrink = positive_finite("shrink", shrink)
    # checks l1, l2, w (positive, finite) before they are used
    semi = Body.t_handle(l1, l2, w).equivalent_ellipsoid()
    l1, l2, w = (real_scalar(name, value) for name, value in (("l1", l1), ("l2", l2), ("w", w)))
    total = l1 + l2
    com_y = (l2 / total) * 0.5 * (w + l2)
    boxes = [
        ((-l1 / 2, -w / 2 - com_y, -w / 2), (l1 / 2, w / 2 - com_y, w / 2)),
        ((-w / 2, w / 2 - com_y, -w / 2), (w / 2, w / 2 + l2 - com_y, w / 2)),
    ]
    faces = box_faces(*boxes[0]) + box_faces(*boxes[1])
    if bars == "outline":
        drawn = Poly3DCollection(
            faces, facecolor=(0, 0, 0, 0), edgecolor="darkgreen", linewidths=0.6
        )
    else:
        drawn = Poly3DCollection(
            faces, facecolor="tab:green", edgecolor="darkgreen", alpha=0.35, linewidths=0.8
        )
    ax3d.add_collection3d(drawn)
    surface = None
    if ellipsoid:
        x, y, z = _ellipsoid_surface(np.array(semi) * shrink, resolution=60)
        surface = ax3d.plot_surface(
            x, y, z, color="tab:orange", alpha=0.55, linewidth=0, shade=True
        )
    ax3d.view_init(elev=30, azim=-58)
    # the box fits the larger of the T and the drawn ellipsoid, z kept to scale
    span_x = 0.52 * max(l1, 2.0 * shrink * semi[0] if ellipsoid else 0.0)
    span_y = 0.52 * max(l2 + w, 2.0 * shrink * semi[1] if ellipsoid else 0.0)
    span = max(span_x, span_y)
    span_z = 0.52 * max(w, 2.0 * shrink * semi[2] if ellipsoid else 0.0, 0.25 * span)
    ax3d.set_xlim(-span, span)
    ax3d.set_ylim(-span, span)
    ax3d.set_zlim(-span_z, span_z)
    ax3d.set_box_aspect((1, 1, span_z / span), zoom=1.1)
    ax3d.set_zticks([-0.5, 0.0, 0.5])
    ax3d.set_xlabel("x ($I_1$ axis)", labelpad=2)
    ax3d.set_ylabel("y ($I_2$ axis)", labelpad=2)
    ax3d.set_zlabel("z ($I_3$)", labelpad=-2)
    ax3d.tick_params(labelsize="x-small", pad=0)
    return {"bars": drawn, "boxes": boxes, "ellipsoid": surface, "semi_axes": semi}


def _momentum_axes(ax3d, limit):
    """Cube limits, equal aspect and labels of angular-momentum space."""
    for setter in (ax3d.set_xlim, ax3d.set_ylim, ax3d.set_zlim):
        setter(-limit, limit)
    ax3d.set_box_aspect((1, 1, 1))
    ax3d.set_xlabel("$M_1$ (J s)")
    ax3d.set_ylabel("$M_2$ (J s)")
    ax3d.set_zlabel("$M_3$ (J s)")


def plot_binet(ax3d, body, theta=None, *, dtheta=None, phi=0.0):
    """The momentum sphere meeting the Binet ellipsoid, and the polhode (Fig. 3a).

    Both surfaces in angular-momentum space for the given spin (``|I| = 1``,
    ``|omega0| = 1``; or ``body`` a :class:`orbits.Motion`, as given): the
    sphere ``|M| = M`` and the ellipsoid
    ``M1^2/I1 + M2^2/I2 + M3^2/I3 = 2E``; their intersection is the polhode.

    Returns
    -------
    dict
        ``sphere``, ``ellipsoid`` (surfaces), ``polhode`` (Line3D) and
        ``energy``, ``momentum``.
    """
    if isinstance(body, Motion):
        _no_angles_with_motion(theta, dtheta, phi, "plot_binet")
        # the motion as given: moments in kg m^2 and rad/s give J and J s
        unit = body.body.moments
        row = body
        momentum = body.angular_momentum(np.linspace(0.0, body.period, 1500))
    else:
        unit = as_body(body).normalized_moments
        row = phases(unit, theta, phi, dtheta=dtheta).iloc[0]
        _, momentum = polhode(unit, theta, dtheta=dtheta, phi=phi, points=1500)
    x, y, z = _ellipsoid_surface([row.momentum] * 3, resolution=50)
    sphere = ax3d.plot_surface(x, y, z, color="tab:blue", alpha=0.25, linewidth=0)
    semi = np.sqrt(2.0 * row.energy * unit)
    x, y, z = _ellipsoid_surface(semi, resolution=50)
    ellipsoid = ax3d.plot_surface(x, y, z, color="gold", alpha=0.35, linewidth=0)
    (curve,) = ax3d.plot(
        momentum[:, 0],
        momentum[:, 1],
        momentum[:, 2],
        color="black",
        linewidth=1.5,
        label="polhode",
    )
    _momentum_axes(ax3d, 1.05 * semi.max())
    return {
        "sphere": sphere,
        "ellipsoid": ellipsoid,
        "polhode": curve,
        "energy": row.energy,
        "momentum": row.momentum,
    }


def plot_omega_components(ax, body, theta=None, *, dtheta=None, phi=0.0, periods=2.0, points=3001):
    """The body-frame components of omega against time, period marked (Fig. 3b).

    ``body`` may be a :class:`orbits.Motion` (no angles): its spin as given.
    ``periods`` (positive) periods drawn with ``points`` samples (2 to
    :data:`orbits.motion.MAX_POINTS`).

    Returns
    -------
    dict
        ``lines`` (three Line2D: x solid red, y dashed green, z dot-dashed
        blue, as the paper), ``period`` (the gray vertical line's x) and
        ``period_axis`` (the top axis whose one tick names T).
    """
    periods = positive_finite("periods", periods)
    points = integer("points", points, minimum=2, maximum=MAX_POINTS)
    if isinstance(body, Motion):
        _no_angles_with_motion(theta, dtheta, phi, "plot_omega_components")
        motion = body
    else:
        motion = Motion.from_spin(as_body(body), theta, dtheta=dtheta, phi=phi)
    t = np.linspace(0.0, _end_time(periods, motion.period), points)
    omega = motion.omega(t)
    styles = (
        dict(color="tab:red", linestyle="-"),
        dict(color="tab:green", linestyle="--"),
        dict(color="tab:blue", linestyle="-."),
    )
    lines = [
        ax.plot(t, omega[:, k], label=rf"$\omega_{axis}$ ({name})", **style)[0]
        for k, (axis, name, style) in enumerate(
            zip("xyz", ("smallest $I$", "intermediate $I$", "largest $I$"), styles)
        )
    ]
    ax.axvline(motion.period, color="0.6", linewidth=1.2)
    # the period is named by a tick on a top axis: outside the data (the curves
    # fill the box) and away from the time axis
    marker = ax.secondary_xaxis("top")
    marker.set_xticks([motion.period], [f"T = {motion.period:.4f} s"])
    marker.tick_params(labelsize="small", colors="0.35")
    ax.set_xlabel("time t (s)")
    ax.set_ylabel(r"body angular velocity $\omega_i$ (rad/s)")
    ax.set_xlim(0.0, t[-1])
    # the legend goes under the axes: the curves fill the whole box
    ax.legend(
        loc="upper center", bbox_to_anchor=(0.5, -0.14), ncols=3, fontsize="x-small", frameon=False
    )
    return {"lines": lines, "period": motion.period, "period_axis": marker}


# the most polhodes in a foliation (each drawn as up to four lines of 600 samples)
MAX_POLHODES = 1000


def plot_polhode_foliation(
    ax3d, body, *, count=28, energy=0.5, cmap="twilight", elev=22.0, azim=-62.0
):
    """The Binet ellipsoid foliated by polhodes coloured by Delta alpha mod 2 pi (Fig. 4).

    Polhodes for ``count`` spins over both branches, each scaled to the
    same energy (the phase does not depend on ``|omega|``), drawn with
    their mirror images so that they cover the ellipsoid.  Depth cue: the
    parts on the far side of the ellipsoid (outward normal ``M / I``
    pointing away from the viewer at ``elev``, ``azim``) are drawn thin
    and faint.  The 3-D box is replaced by the three principal axes.

    Parameters
    ----------
    count : int
        Spins drawn, half on each branch: 2 to :data:`MAX_POLHODES`.
    energy : float
        The energy ``E`` all polhodes are scaled to (J), positive.
    cmap : str
        A matplotlib colormap's name.

    Returns
    -------
    dict
        ``polhodes`` (list of (Line3D, phase mod 2 pi); near and far parts
        are separate lines, gaps as NaN), ``colorbar``, ``ellipsoid``,
        ``view`` (unit vector towards the viewer).
    """
    import matplotlib as mpl

    count = integer("count", count, minimum=2, maximum=MAX_POLHODES)
    energy = positive_finite("energy", energy)
    try:
        colormap = mpl.colormaps[cmap]
    except (KeyError, TypeError):
        raise InputError(f"cmap {cmap!r} is not the name of a matplotlib colormap") from None
    body = as_body(body)
    unit = body.normalized_moments
    theta_c = critical_angle(unit)
    thetas = np.concatenate(
        [
            np.linspace(0.04, 0.985, count // 2) * theta_c,
            theta_c + np.linspace(0.015, 0.96, count // 2) * (0.5 * np.pi - theta_c),
        ]
    )
    table = phases(unit, thetas)
    norm = mpl.colors.Normalize(0.0, TWO_PI)
    semi = np.sqrt(2.0 * energy * unit)
    ax3d.view_init(elev=elev, azim=azim)
    e, a = np.radians(elev), np.radians(azim)
    view = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    x, y, z = _ellipsoid_surface(semi, resolution=50)
    ellipsoid = ax3d.plot_surface(x, y, z, color="0.62", alpha=0.4, linewidth=0)
    drawn = []
    for theta, row in zip(thetas, table.itertuples()):
        _, momentum = polhode(unit, theta, points=600)
        momentum *= np.sqrt(energy / row.energy)
        phase = row.total_phase % TWO_PI
        color = colormap(norm(phase))
        for flip in (1.0, -1.0):
            mirrored = momentum.copy()
            if row.branch == "SAM":
                mirrored[:, 2] *= flip
            else:
                mirrored[:, 0] *= flip
            near = (mirrored / semi**2) @ view > 0.0
            for side, width, alpha in ((near, 1.3, 1.0), (~near, 0.5, 0.22)):
                if not side.any():
                    continue
                # keep one neighbour on each side so that the pieces join
                shown = side | np.roll(side, 1) | np.roll(side, -1)
                piece = np.where(shown[:, None], mirrored, np.nan)
                (line,) = ax3d.plot(
                    *piece.T,
                    color=color,
                    linewidth=width,
                    alpha=alpha,
                    zorder=3 if alpha == 1.0 else 1,
                )
                drawn.append((line, phase))
    for k, name in enumerate(("$M_1$ (J s)", "$M_2$ (J s)", "$M_3$ (J s)")):
        tip = np.zeros(3)
        tip[k] = 1.3 * semi[k]
        ax3d.plot(*np.stack([-tip, tip]).T, color="0.3", linewidth=0.7)
        ax3d.text(*(1.08 * tip), name, fontsize="small", color="0.2")
    bar = ax3d.figure.colorbar(
        mpl.cm.ScalarMappable(norm=norm, cmap=colormap), ax=ax3d, shrink=0.7, pad=0.02
    )
    bar.set_label(r"total phase $\Delta\alpha$ mod $2\pi$ (rad)")
    bar.set_ticks([0, np.pi / 2, np.pi, 1.5 * np.pi, TWO_PI])
    bar.set_ticklabels(["0", r"$\pi/2$", r"$\pi$", r"$3\pi/2$", r"$2\pi$"])
    reach = 1.3 * semi
    ax3d.set_xlim(-reach[0], reach[0])
    ax3d.set_ylim(-reach[1], reach[1])
    ax3d.set_zlim(-reach[2], reach[2])
    ax3d.set_box_aspect(tuple(reach), zoom=1.25)
    ax3d.set_xlabel("$M_1$ (J s)")
    ax3d.set_ylabel("$M_2$ (J s)")
    ax3d.set_zlabel("$M_3$ (J s)")
    ax3d.set_axis_off()
    return {"polhodes": drawn, "colorbar": bar, "ellipsoid": ellipsoid, "view": view}


def limits_field(i1, i2):
    """min(eqn:alphamin1, eqn:alphamin2) on a grid (NaN outside the region)."""
    moments, inside = region_moments(i1, i2)
    out = np.full(np.shape(i1), np.nan)
    if inside.any():
        lim = phase_limits(moments[inside])
        out[inside] = np.minimum(lim.theta_zero, lim.theta_half_pi)
    return out
