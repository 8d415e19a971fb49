"""Figure files: herpolhode sets of closed orbits and the paper's six figures.

Figures are built on :class:`matplotlib.figure.Figure` with the Agg canvas
(headless; no ``pyplot`` state), saved atomically, and deterministic: the
same inputs and library versions give the same bytes (no timestamps in
SVG or PDF metadata, a fixed SVG hash salt).
"""

import math
import re
from contextlib import contextmanager
from pathlib import Path

import matplotlib as mpl
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from . import plotting
from ._args import integer, path_argument
from .atomic import file_set, refuse_link, write_bytes_under
from .bodies import Body
from .cells import literal_text
from .errors import InputError, OrbitsError
from .limits import AGG_MAX_PIXELS, MAX_SECONDS, about_duration, format_bytes, memory_budget
from .search import closed_orbits

FORMATS = ("png", "svg", "pdf")
DPI = 150
_METADATA = {
    "png": {"Software": None},
    "svg": {"Date": None},
    "pdf": {"CreationDate": None, "ModDate": None},
}
# a fixed SVG hash salt and text as paths (the same bytes everywhere); a
# line of more than 10^5 samples (a herpolhode of hundreds of turns) is
# rasterized in pieces of that many, else Agg's cell limit refuses it
_RC = {"svg.hashsalt": "orbits", "svg.fonttype": "path", "agg.path.chunksize": 100_000}


def new_figure(width=6.4, height=4.8):
    """A figure with an Agg canvas (headless)."""
    figure = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(figure)
    return figure


def save_figure(figure, stem, formats=("png", "svg")):
    """Save ``figure`` as ``stem.<format>`` for each format: all of them or none.

    Every format is checked before anything is written, and the files are
    moved into place together (:func:`orbits.atomic.file_set`): an error or
    a stop leaves none of them.  The layout is computed once, at
    :data:`DPI`, before the first file and kept for all: each file's bytes
    depend on the figure and its format only, not on the other formats or
    their order.

    Parameters
    ----------
    figure : matplotlib.figure.Figure
    stem : path
        The files' path without the extension; its directory must exist.
    formats : str or sequence of str
        Any of ``png``, ``svg``, ``pdf`` (each written once).

    Returns
    -------
    list of Path
        The paths written, in the order of ``formats``.

    Raises
    ------
    InputError
        An unknown or no format, or a target that cannot be written.
    """
    formats = _formats(formats)
    stem = Path(path_argument("stem", stem))
    if stem.name in ("", ".", ".."):
        raise InputError(
            f"stem {str(stem)!r} names a directory; give the files' path without "
            "the extension (e.g. figures/orbit)"
        )
    names = [f"{stem.name}.{fmt}" for fmt in formats]
    with file_set(stem.parent, names) as stage:
        for name, data in zip(names, figure_bytes(figure, formats)):
            write_bytes_under(stage, name, data)
    return [stem.parent / name for name in names]


def figure_bytes(figure, formats):
    """The files of ``figure`` in each of ``formats`` (known ones), as bytes.

    The layout is computed once, at :data:`DPI`, before the first and kept
    for all (:func:`save_figure`).
    """
    import io

    files = []
    with _fixed_layout(figure), mpl.rc_context(_RC):
        for fmt in formats:
            buffer = io.BytesIO()
            figure.savefig(buffer, format=fmt, dpi=DPI, metadata=_METADATA[fmt])
            files.append(buffer.getvalue())
    return files


def _stage_figure(figure, out_dir, stage, stem, formats):
    """Write ``figure`` as ``stem.<format>`` into a set's ``stage`` in ``out_dir``.

    Through descriptors from ``out_dir`` down (:func:`orbits.atomic.write_bytes_under`):
    a stage swapped for a link while the set is drawn is refused.
    """
    formats = _formats(formats)
    for fmt, data in zip(formats, figure_bytes(figure, formats)):
        write_bytes_under(out_dir, Path(stage.name) / f"{stem}.{fmt}", data)


def _formats(formats):
    """``formats`` as a tuple of known formats, each once (a str is one format)."""
    if isinstance(formats, str):
        formats = (formats,)
    try:
        formats = tuple(dict.fromkeys(formats))
    except TypeError:
        raise InputError(
            f"formats must be a sequence of {', '.join(FORMATS)}, got {formats!r}"
        ) from None
    for fmt in formats:
        if fmt not in FORMATS:
            raise InputError(f"unknown figure format {fmt!r}; use {', '.join(FORMATS)}")
    if not formats:
        raise InputError(f"formats is empty; give at least one of {', '.join(FORMATS)}")
    return formats


@contextmanager
def _fixed_layout(figure):
    """Run the figure's layout once at :data:`DPI`, and keep it while the files are saved.

    A layout engine moves the axes a little on every draw (constrained
    layout: by ~0.4 pt between successive saves), so that without this a
    file's bytes depended on the formats saved before it.
    """
    engine = figure.get_layout_engine()
    if engine is None:
        yield
        return
    dpi = figure.dpi
    figure.set_dpi(DPI)
    try:
        figure.draw_without_rendering()
    finally:
        figure.set_dpi(dpi)
    figure.set_layout_engine("none")
    try:
        yield
    finally:
        figure.set_layout_engine(engine)


def _stem(row):
    multiple = f"n{row.n:03d}" if row.q == 1 else f"p{row.n:03d}q{row.q}"
    return f"herpolhode_{row.branch}_{multiple}"


def figure_files(stems, formats=("png", "svg")):
    """``stem.format`` for each stem, in every format (each format once).

    Raises
    ------
    InputError
        An unknown or no format.
    """
    formats = _formats(formats)
    return [f"{stem}.{fmt}" for stem in stems for fmt in formats]


def set_file_names(orbits, formats=("png", "svg")):
    """The files :func:`herpolhode_set` writes for the closed orbits ``orbits``.

    One ``herpolhode_<branch>_n<NNN>`` (or ``..._p<NNN>q<Q>``) per orbit in
    the paper's order, then ``contact_sheet``, each in every format (each
    format once); none for no orbits.
    """
    stems = [_stem(row) for row in _paper_order(orbits).itertuples()]
    if stems:
        stems.append("contact_sheet")
    return figure_files(stems, formats)


def _paper_order(orbits):
    """Fig. 6's order: left to right in theta (SAM n up, then LAM n down)."""
    return orbits.sort_values("dtheta", kind="stable").reset_index(drop=True)


def herpolhode_set(
    body, n_max, out_dir, *, q_max=1, formats=("png", "svg"), progress=None, orbits=None
):
    """One figure per closed orbit of ``body`` and a contact sheet.

    Each curve is drawn over the time in which it closes (the catalog's
    ``closes_after``: half a period for odd ``n``), with its start (dot),
    direction (arrow), the L axis (+) and its bounding circles r_min and
    r_max (dashed); all figures of a set share one scale.

    Parameters
    ----------
    body : Body
    n_max, q_max : int
        As :func:`orbits.closed_orbits`.
    out_dir : path
        Existing directory for the files, holding no figures of another
        set (``herpolhode_*`` or ``contact_sheet`` names this set does not
        write, which would stay beside it): refused, nothing removed.
    formats : sequence of str
        Any of ``png``, ``svg``, ``pdf``.
    progress : callable, optional
        Called with 1 after each figure.
    orbits : DataFrame, optional
        The catalog to draw (computed if omitted): rows of ``body``, within
        ``n_max`` and ``q_max`` (:func:`check_orbits_of`).

    Returns
    -------
    list of Path
        The files written (per orbit ``herpolhode_<branch>_n<NNN>`` or
        ``..._p<NNN>q<Q>``, then ``contact_sheet``).
    """
    out_dir = _directory(out_dir)
    if orbits is None:
        orbits = closed_orbits(body, n_max=n_max, q_max=q_max)
    else:
        check_orbits_of(body, orbits, n_max, q_max)
    orbits = _paper_order(orbits)
    check_figure_set(len(orbits), formats, turns=drawn_turns(orbits))
    name = body.name or "body"
    files = set_file_names(orbits, formats)
    _refuse_another_set(out_dir, files)
    # all or none: a stop or an error leaves the directory as it was
    with file_set(out_dir, files) as stage:
        radii = [plotting.herpolhode_radii(body, dtheta=row.dtheta) for row in orbits.itertuples()]
        limit = _common_limit(radii) if radii else None
        for row, bounds in zip(orbits.itertuples(), radii):
            figure = closed_herpolhode_figure(body, row, name, limit=limit, radii=bounds)
            _stage_figure(figure, out_dir, stage, _stem(row), formats)
            if progress is not None:
                progress(1)
        if len(orbits):
            _stage_figure(contact_sheet(body, orbits), out_dir, stage, "contact_sheet", formats)
        if progress is not None:
            progress(1)
    return [out_dir / name for name in files]


def check_orbits_of(body, orbits, n_max=None, q_max=None):
    """Refuse catalog rows that are no closed orbit of ``body``, or beyond ``n_max``, ``q_max``.

    A row is drawn from its ``dtheta`` and the body given: a row of another
    body was drawn as an orbit of this one under its title (a t-handle
    figure titled ``Delta alpha = 2 pi 2`` showed a spin of 2.15 turns
    that does not close; an audit).  The body's total phase at each row's
    ``dtheta`` (``phi = 0``) must be the row's ``2 pi n/q`` within the
    catalog's own tolerance (:data:`orbits.search.RESIDUAL_TOLERANCE` of
    it): the same body built another way (point masses in another order,
    lengths in other units), whose moments differ in the last digits, is
    accepted.  With ``n_max``/``q_max`` (:func:`herpolhode_set`), a row of
    level ``n/q`` above ``n_max`` or ``q`` above ``q_max`` is refused, not
    drawn.

    ``orbits``: a DataFrame of catalog rows, or one row (a named tuple of
    ``itertuples`` or a Series), with ``n``, ``q`` and ``dtheta``.
    """
    from .phases import total_phase
    from .search import RESIDUAL_TOLERANCE

    try:
        n, q, dtheta = (
            np.atleast_1d(np.asarray(_field(orbits, name), dtype=float))
            for name in ("n", "q", "dtheta")
        )
    except (AttributeError, KeyError, TypeError, ValueError):
        raise InputError(
            "catalog rows need their n, q and dtheta columns (orbits.closed_orbits)"
        ) from None
    target = 2.0 * math.pi * n / q
    try:
        phase = np.asarray(total_phase(body, dtheta=dtheta), dtype=float)
    except OrbitsError as error:  # a dtheta past an axis of this body
        raise InputError(
            f"catalog rows that are no closed orbits of the body drawn ({error}); "
            "rows of another body? draw them with that body"
        ) from None
    with np.errstate(all="ignore"):
        miss = np.abs(phase - target)
        off = ~(miss <= RESIDUAL_TOLERANCE * target * (1.0 + 1e-6) + 4.0 * np.spacing(target))
    if off.any():
        k = np.flatnonzero(off)[0]
        raise InputError(
            f"a catalog row (n/q = {n[k]:.0f}/{q[k]:.0f}, dtheta = {float(dtheta[k])!r}) is "
            "no closed orbit of the body drawn: its total phase there is "
            f"{float(phase[k])!r} rad, not 2 pi n/q = {float(target[k])!r}; a row of another "
            "body? draw it with that body"
        )
    if n_max is None:
        return
    n_max, q_max = integer("n_max", n_max, minimum=1), integer("q_max", q_max, minimum=1)
    beyond = (n > n_max * q) | (q > q_max)
    if beyond.any():
        k = np.flatnonzero(beyond)[0]
        raise InputError(
            f"orbits holds the level n/q = {n[k]:.0f}/{q[k]:.0f}, beyond n_max = {n_max}, "
            f"q_max = {q_max}: give the n_max and q_max of the catalog, or only its rows "
            "within them"
        )


def _field(rows, name):
    """Column ``name`` of a DataFrame, or the field of one row."""
    return rows[name] if hasattr(rows, "columns") else getattr(rows, name)


def closed_herpolhode_figure(body, row, name=None, *, limit=None, radii=None):
    """One closed orbit's herpolhode figure (as written by :func:`herpolhode_set`)."""
    figure = new_figure(5.2, 5.9)
    ax = figure.add_subplot()
    draw_closed_herpolhode(ax, body, row, limit=limit, radii=radii)
    ax.set_title(
        plotting.orbit_label(row, name or body.name or "body"), fontsize="small", wrap=True
    )
    _marks_legend(figure)
    return figure


def _periods_text(row):
    """``T/2``, ``3T/2``...: the time a row's herpolhode closes in
    (:func:`orbits.plotting.closing_periods`: ``closes_after``, else q)."""
    periods = plotting.closing_periods(row)
    head = "" if periods.numerator == 1 else f"{periods.numerator}"
    return f"{head}T/{periods.denominator}" if periods.denominator > 1 else f"{head}T"


def _common_limit(radii):
    """Half-width of the common square view: the largest r_max plus a margin."""
    return 1.1 * max(r_max for _, r_max in radii)


def draw_closed_herpolhode(
    ax, body, row, *, limit=None, radii=None, label_axes=True, centre_label=True, **line
):
    """A catalog row's herpolhode over the time it closes in, with its marks.

    Returns the dict of :func:`orbits.plotting.mark_herpolhode` plus
    ``curve`` (Line2D) and ``periods`` (the duration drawn, in T).
    """
    check_orbits_of(body, row)
    periods = plotting.drawn_periods(row)
    curve = plotting.plot_herpolhode(
        ax, body, dtheta=row.dtheta, periods=periods, label_axes=label_axes, **line
    )
    radii = radii or plotting.herpolhode_radii(body, dtheta=row.dtheta)
    marks = plotting.mark_herpolhode(ax, curve, radii, centre_label=centre_label)
    limit = limit or _common_limit([radii])
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlim(-limit, limit)
    ax.set_ylim(-limit, limit)
    marks.update(curve=curve, periods=periods)
    return marks


def _marks_legend(figure, fontsize="x-small"):
    """A legend of the herpolhode marks under the figure."""
    from matplotlib.lines import Line2D

    handles = [
        Line2D(
            [],
            [],
            color="tab:purple",
            marker="o",
            markersize=4,
            linestyle="none",
            label="start (t = 0)",
        ),
        Line2D(
            [],
            [],
            color="tab:purple",
            marker=r"$\rightarrow$",
            markersize=9,
            linestyle="none",
            label="direction",
        ),
        Line2D(
            [],
            [],
            color="black",
            marker="+",
            markersize=6,
            linestyle="none",
            label="centre: the L axis",
        ),
        Line2D(
            [],
            [],
            color="0.55",
            linestyle=(0, (4, 3)),
            linewidth=0.8,
            label=r"$r_{min}$, $r_{max}$",
        ),
    ]
    return figure.legend(
        handles=handles,
        loc="outside lower center",
        ncols=4,
        fontsize=fontsize,
        frameon=False,
        handlelength=1.6,
        columnspacing=1.0,
    )


def _sheet_columns(count):
    return max(1, min(8, math.ceil(math.sqrt(count * 1.5))))


# the narrowest contact sheet (in) that holds its title and the legend of
# the marks in one line each (a sheet of one or two orbits was cut at the sides)
_SHEET_MIN_WIDTH = 6.4


def _sheet_size(count, columns):
    """Width and height (in) of a contact sheet of ``count`` panels in ``columns``."""
    return max(2.0 * columns, _SHEET_MIN_WIDTH), 2.2 * math.ceil(count / columns) + 1.0


# measured here (2-core VM, 2026-11-24): herpolhode_set of fig6 with n_max = 6
# (10 orbits and the contact sheet) took 1.2 s a figure and format
_SECONDS_PER_FIGURE = 1.2
# and for long curves (2-core VM, 2026-11-25), per sample of a drawn curve:
# computing it and drawing it in its figure and on the contact sheet, a
# format; and held by the contact sheet, which keeps every curve
_SECONDS_PER_POINT = 2e-6
_BYTES_PER_POINT = 120


def drawn_turns(orbits):
    """The turns of each closed orbit's herpolhode as drawn.

    ``|Delta alpha| / 2 pi`` a period, over the periods it closes in
    (:func:`orbits.plotting.drawn_periods`), for each row of ``orbits``.
    """
    return [
        abs(row.total_phase) / plotting.TWO_PI * plotting.drawn_periods(row)
        for row in orbits.itertuples()
    ]


def figure_set_estimate(count, formats, turns=()):
    """Rough memory (bytes) and time (s) of :func:`herpolhode_set` for ``count`` orbits.

    The contact sheet dominates the memory: 2 x 2.2 in a panel, 8 columns,
    at :data:`DPI`, a few buffers of 4 bytes a pixel, and every curve's
    samples (:func:`orbits.plotting.herpolhode_points` of each of
    ``turns``, from :func:`drawn_turns`).
    """
    width, height = _sheet_size(max(count, 1), _sheet_columns(max(count, 1)))
    pixels = (width * DPI) * (height * DPI)
    points = float(sum(plotting.herpolhode_points(turn) for turn in turns))
    memory = 3 * 4.0 * pixels + points * _BYTES_PER_POINT
    formats = max(1, len(formats))
    seconds = (count + 1) * formats * _SECONDS_PER_FIGURE + points * formats * _SECONDS_PER_POINT
    return memory, seconds


def check_figure_set(count, formats, advice="lower n_max or q_max", turns=()):
    """Refuse a figure set that matplotlib cannot draw or that would take a day.

    The contact sheet of every orbit must stay below Agg's 65535 pixels a
    side (at most 1584 orbits at :data:`DPI` = 150); no curve may make more
    than :data:`orbits.plotting.MAX_TURNS` turns (``turns``, from
    :func:`drawn_turns`); memory and time as :func:`figure_set_estimate`.
    ``advice`` ends the message (the command line names its options).

    Returns
    -------
    memory, seconds : float

    Raises
    ------
    InputError
    """
    formats = _formats(formats)
    height = _sheet_size(max(count, 1), _sheet_columns(max(count, 1)))[1] * DPI
    most = int((AGG_MAX_PIXELS / DPI - 1.0) / 2.2) * 8
    if height > AGG_MAX_PIXELS:
        raise InputError(
            f"the contact sheet of {count} closed orbits would be {height:.0f} pixels tall, "
            f"more than the {AGG_MAX_PIXELS} matplotlib can draw (at most {most} orbits); "
            f"{advice}"
        )
    if len(turns):
        plotting.check_turns(max(turns), "the longest closed herpolhode", advice)
    memory, seconds = figure_set_estimate(count, formats, turns)
    if memory > memory_budget():
        raise InputError(
            f"the figures of {count} closed orbits would need {format_bytes(memory)} of "
            f"memory, more than the {format_bytes(memory_budget())} allowed; {advice}"
        )
    if seconds > MAX_SECONDS:
        raise InputError(
            f"the figures of {count} closed orbits would take {about_duration(seconds)}; {advice}"
        )
    return memory, seconds


def contact_sheet(body, orbits, columns=None):
    """All closed herpolhodes of a body in one grid, in Fig. 6's order.

    One common scale (shared axes, |omega0| = 1 rad/s); each curve drawn
    over the time in which it closes, with start, direction, L axis and
    its r_min, r_max circles; a title with theta, or theta - theta_c in
    scientific notation when theta rounds to theta_c.

    Parameters
    ----------
    body : Body
    orbits : DataFrame
        Catalog rows (:func:`orbits.closed_orbits`), at least one.
    columns : int, optional
        Panels a row (default: up to 8, about 1.2 sqrt(count)); the sheet
        must stay within the 65535 pixels a side Agg draws at :data:`DPI`.

    Raises
    ------
    InputError
        No orbit, ``columns`` not a positive integer, or a sheet too large.
    """
    orbits = _paper_order(orbits)
    count = len(orbits)
    if count == 0:
        raise InputError("the contact sheet needs at least one closed orbit")
    check_orbits_of(body, orbits)
    if columns is None:
        columns = _sheet_columns(count)
    columns = integer("columns", columns, minimum=1)
    width, height = _sheet_size(count, columns)
    if max(width, height) * DPI > AGG_MAX_PIXELS:
        raise InputError(
            f"a contact sheet of {count} orbits in columns={columns} would be "
            f"{width * DPI:.0f} x {height * DPI:.0f} pixels, more than the {AGG_MAX_PIXELS} "
            "a side matplotlib can draw; give fewer columns"
            + ("" if height * DPI <= AGG_MAX_PIXELS else " or fewer orbits")
        )
    rows = math.ceil(count / columns)
    figure = new_figure(width, height)
    grid = figure.subplots(rows, columns, squeeze=False, sharex=True, sharey=True)
    radii = [plotting.herpolhode_radii(body, dtheta=row.dtheta) for row in orbits.itertuples()]
    limit = _common_limit(radii)
    for ax in grid.ravel()[count:]:
        ax.set_axis_off()
    for ax, row, bounds in zip(grid.ravel(), orbits.itertuples(), radii):
        draw_closed_herpolhode(
            ax,
            body,
            row,
            limit=limit,
            radii=bounds,
            label_axes=False,
            centre_label=False,
            linewidth=0.6,
        )
        multiple = f"{row.n}" if row.q == 1 else f"{row.n}/{row.q}"
        half = f" ({_periods_text(row)})" if plotting.drawn_periods(row) != 1.0 else ""
        ax.set_title(
            rf"{row.branch} $2\pi\cdot{multiple}${half}"
            + "\n"
            + plotting.theta_text(row.theta, row.dtheta),
            fontsize="x-small",
        )
        ax.tick_params(labelsize="xx-small")
    for column in range(columns):
        lowest = (count - 1 - column) // columns  # last drawn row of the column
        if lowest >= 0:
            grid[lowest, column].set_xlabel(r"$\omega_x$ (rad/s)", fontsize="x-small")
            grid[lowest, column].xaxis.set_tick_params(labelbottom=True)
    for ax in grid[:, 0]:
        ax.set_ylabel(r"$\omega_y$ (rad/s)", fontsize="x-small")
    figure.suptitle(
        f"Closed herpolhodes of {literal_text(body.name or 'the body')} in the invariable plane\n"
        r"one scale ($|\omega_0|$ = 1 rad/s), left to right in $\theta$; "
        "each drawn until it closes",
        fontsize="medium",
        wrap=True,
    )
    _marks_legend(figure, fontsize="small")
    figure.get_layout_engine().set(w_pad=0.15, h_pad=0.08)  # inches: clear of the edges
    figure.limit = limit
    return figure


# the names herpolhode_set writes (set_file_names)
_SET_FILE = re.compile(
    r"(herpolhode_(SAM|LAM)_(n[0-9]{3,}|p[0-9]{3,}q[0-9]+)|contact_sheet)\.(png|svg|pdf)"
)


def _refuse_another_set(out_dir, files):
    """Refuse a directory holding figures of another set (a set's names not in ``files``).

    A second run replaced only its own names: a directory of n <= 3 and
    p/q figures in three formats, run again with n <= 2 in PNG, kept the
    old p/q figures and SVG/PDF contact sheet beside the new PNG one (an
    audit).  Nothing is removed; the user chooses.
    """
    import os

    wanted = set(files)
    try:
        with os.scandir(out_dir) as entries:
            stale = sorted(
                entry.name
                for entry in entries
                if _SET_FILE.fullmatch(entry.name) and entry.name not in wanted
            )
    except OSError as error:
        raise InputError(f"cannot read {out_dir}: {error.strerror or error}") from None
    if stale:
        shown = ", ".join(stale[:3]) + (f" and {len(stale) - 3} more" if len(stale) > 3 else "")
        raise InputError(
            f"{out_dir} holds figures of another set ({shown}) that this one would not "
            "replace, leaving a mixed set: write into an empty directory, or remove them"
        )


def _directory(out_dir):
    """An existing directory for a figure set, not a link (nothing is written through one)."""
    path = Path(path_argument("out_dir", out_dir))
    refuse_link(path)
    try:
        if not path.is_dir():
            if path.exists():
                raise InputError(f"output directory {path} is not a directory")
            raise InputError(f"output directory {path} does not exist")
    except OSError as error:  # a name too long for the file system
        raise InputError(f"cannot write into {path}: {error.strerror or error}") from None
    return path


# ------------------------------------------------------------- the paper
T_HANDLE_SPIN = dict(theta=0.5 * np.pi - 0.15, phi=0.5 * np.pi - 0.2)  # Fig. 3


def figure1():
    """Fig. 1: the T-handle (8, 4, 1) and its equivalent ellipsoid.

    (a) the T-handle; (b) the equivalent ellipsoid at full size, on the same
    scale, with the T's outline: the paper's 1/4 shrink hid it inside the T.
    """
    figure = new_figure(10.0, 3.9)
    # constrained layout does not see the 3-D z labels: keep a right margin for them
    figure.get_layout_engine().set(rect=(0.0, 0.0, 0.965, 1.0))
    left = figure.add_subplot(1, 2, 1, projection="3d")
    right = figure.add_subplot(1, 2, 2, projection="3d")
    plotting.plot_t_handle(left, 8.0, 4.0, 1.0, ellipsoid=False)
    drawn = plotting.plot_t_handle(right, 8.0, 4.0, 1.0, shrink=1.0, bars="outline")
    a, b, c = drawn["semi_axes"]
    left.set_title("(a) T-handle $l_1$ = 8, $l_2$ = 4, $w$ = 1 (length units)", fontsize="small")
    right.set_title(
        f"(b) equivalent solid ellipsoid, full size (T outlined)\n"
        f"(a, b, c) = ({a:.5f}, {b:.5f}, {c:.6f})",
        fontsize="small",
    )
    figure.suptitle(
        "Fig. 1: two bodies with the same principal moments of inertia", fontsize="medium"
    )
    return figure


def figure2(grid=None, resolution=300):
    """Fig. 2: the body-space map with contours of the minimum total phase."""
    figure = new_figure(8.2, 4.6)
    ax = figure.add_subplot()
    plotting.plot_body_space(ax, grid, resolution=resolution)
    ax.set_title(
        "Fig. 2: physical bodies ($|I| = 1$) and their minimum total phase", fontsize="small"
    )
    return figure


def figure3():
    """Fig. 3: (a) momentum sphere and Binet ellipsoid, (b) omega(t), T-handle spin."""
    figure = new_figure(11.0, 4.8)
    left = figure.add_subplot(1, 2, 1, projection="3d")
    right = figure.add_subplot(1, 2, 2)
    body = Body.preset("t-handle")
    drawn = plotting.plot_binet(left, body, **T_HANDLE_SPIN)
    # five ticks a side, small: the default seven overlap on the slanted M1 axis
    for axis in (left.xaxis, left.yaxis, left.zaxis):
        axis.set_major_locator(mpl.ticker.FixedLocator([-0.6, -0.3, 0.0, 0.3, 0.6]))
    left.tick_params(labelsize="small")
    for axis in (left.xaxis, left.yaxis, left.zaxis):
        axis.labelpad = 8
    left.set_title(
        f"(a) $|M|$ = {drawn['momentum']:.6f} J s sphere and the Binet "
        f"ellipsoid, E = {drawn['energy']:.6f} J",
        fontsize="small",
    )
    plotting.plot_omega_components(right, body, **T_HANDLE_SPIN)
    right.set_title(
        r"(b) $\omega$ in the body, $\theta = \pi/2 - 0.15$, "
        r"$\phi = \pi/2 - 0.2$",
        fontsize="small",
    )
    figure.suptitle(
        "Fig. 3: T-handle, I = (0.286827, 0.533256, 0.795844) J s$^2$", fontsize="medium"
    )
    figure.get_layout_engine().set(w_pad=0.25, h_pad=0.1)  # inches: clear of the edges
    return figure


def figure4():
    """Fig. 4: polhodes on the Binet ellipsoid coloured by Delta alpha mod 2 pi."""
    figure = new_figure(6.6, 5.4)
    ax = figure.add_subplot(projection="3d")
    plotting.plot_polhode_foliation(ax, Body.preset("t-handle"))
    ax.set_title(
        "Fig. 4: T-handle polhodes on the Binet ellipsoid ($E$ = 1/2 J),\n"
        "coloured by total phase mod $2\\pi$; far side faint",
        fontsize="small",
    )
    return figure


def figure5():
    """Fig. 5: total, dynamic, geometric phase and period against theta."""
    figure = new_figure(7.0, 4.8)
    ax = figure.add_subplot()
    plotting.plot_phase_curves(ax, Body.preset("t-handle"))
    ax.set_title(
        "Fig. 5: T-handle, phases and period against the spin's polar angle", fontsize="small"
    )
    return figure


def figure6(n_inset=3):
    """Fig. 6: total phase of the Fig. 6 body, 2 pi n levels, roots, herpolhode insets.

    The herpolhodes of the orbits with ``n <= n_inset + 1`` stand in a row
    above the plot, in the dots' left-to-right order, joined to their dots
    by leader lines that do not cross; the levels are named on the right
    axis and the legend sits under the plot, so nothing covers the curve,
    the level names or the spike at theta_c.

    Parameters
    ----------
    n_inset : int
        1 to 5 (default 3, the paper's insets; beyond 5 the 2 (n_inset + 1)
        insets' titles overlap in the row above the plot).

    Raises
    ------
    InputError
        ``n_inset`` not an integer from 1 to 5.
    """
    from matplotlib.patches import ConnectionPatch

    n_inset = integer("n_inset", n_inset, minimum=1, maximum=5)
    body = Body.preset("fig6")
    orbits = closed_orbits(body, n_max=8)
    shown = orbits[orbits["n"] <= n_inset + 1].sort_values("theta").reset_index(drop=True)
    count = len(shown)
    figure = new_figure(9.0, 8.0)
    grid = figure.add_gridspec(2, count, height_ratios=(1.0, 3.2))
    ax = figure.add_subplot(grid[1, :])
    drawn = plotting.plot_total_phase(ax, body, orbits, n_levels=8, legend=False)
    ax.set_title("")
    radii = [plotting.herpolhode_radii(body, dtheta=row.dtheta) for row in shown.itertuples()]
    limit = _common_limit(radii)
    insets, leaders = [], []
    for k, (row, bounds) in enumerate(zip(shown.itertuples(), radii)):
        inset = figure.add_subplot(grid[0, k])
        draw_closed_herpolhode(
            inset,
            body,
            row,
            limit=limit,
            radii=bounds,
            label_axes=False,
            centre_label=False,
            linewidth=0.6,
        )
        inset.set_xticks([])
        inset.set_yticks([])
        half = f", {_periods_text(row)}" if plotting.drawn_periods(row) != row.q else ""
        inset.set_title(
            rf"{row.branch} $n$={row.n}{half}" + "\n" + rf"$\theta$={row.theta:.4f}",
            fontsize="x-small",
        )
        leader = ConnectionPatch(
            xyA=(0.5, 0.0),
            coordsA=inset.transAxes,
            xyB=(row.theta, row.total_phase),
            coordsB=ax.transData,
            color="0.55",
            linewidth=0.6,
            zorder=1,
        )
        figure.add_artist(leader)
        insets.append((inset, row))
        leaders.append(leader)
    theta_c = float(plotting.critical_angle(body))
    ax.annotate(
        rf"$\theta_c$ = {theta_c:.5f}",
        (theta_c, 0.0),
        xytext=(4, 4),
        textcoords="offset points",
        fontsize="small",
        color="0.35",
    )
    ax.legend(
        handles=[drawn["curve"], drawn["roots"]],
        loc="upper center",
        bbox_to_anchor=(0.5, -0.11),
        ncols=2,
        fontsize="small",
        frameon=False,
    )
    figure.suptitle(
        "Fig. 6: I = (0.26, 0.55, 0.793662) J s$^2$; closed herpolhodes at "
        r"$\Delta\alpha = 2\pi n$ (one scale; odd $n$ close after T/2)",
        fontsize="medium",
    )
    figure.insets = insets
    figure.inset_axes_list = [inset for inset, _ in insets]
    figure.leaders = leaders
    figure.main_axes = ax
    return figure


PAPER_FIGURES = {
    "fig1": figure1,
    "fig2": figure2,
    "fig3": figure3,
    "fig4": figure4,
    "fig5": figure5,
    "fig6": figure6,
}


def paper_figures(out_dir, *, formats=("png", "svg"), survey_grid=None, progress=None, names=None):
    """Write the paper's figures as ``fig1`` ... ``fig6`` (or those in ``names``).

    ``survey_grid``: optional (i1, i2, minimum) for Fig. 2 (from a survey).

    Raises
    ------
    InputError
        A name not in :data:`PAPER_FIGURES`, an unknown format, or a
        directory that does not exist or cannot be written.
    """
    out_dir = _directory(out_dir)
    names = [names] if isinstance(names, str) else list(names or PAPER_FIGURES)
    unknown = [name for name in names if not isinstance(name, str) or name not in PAPER_FIGURES]
    if unknown:
        raise InputError(f"unknown paper figure {unknown[0]!r}; use {', '.join(PAPER_FIGURES)}")
    files = figure_files(names, formats)
    with file_set(out_dir, files) as stage:  # all or none
        for name in names:
            build = PAPER_FIGURES[name]
            figure = (
                build(survey_grid) if (name == "fig2" and survey_grid is not None) else build()
            )
            _stage_figure(figure, out_dir, stage, name, formats)
            if progress is not None:
                progress(1)
    return [out_dir / name for name in files]
