"""Figure files: herpolhode sets of closed orbits and the paper's six figures.

Figures are built on :class:`matplotlib.figure.Figure` with the Agg canvas
(headless; no ``pyplot`` state), saved atomically, and deterministic: the
same inputs and library versions give the same bytes (no timestamps in
SVG or PDF metadata, a fixed SVG hash salt).
"""

import math
from pathlib import Path

import matplotlib as mpl
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from . import plotting
from .atomic import atomic_path
from .bodies import Body
from .errors import InputError
from .search import closed_orbits

FORMATS = ("png", "svg", "pdf")
DPI = 150
_METADATA = {"png": {"Software": None}, "svg": {"Date": None},
             "pdf": {"CreationDate": None, "ModDate": None}}


def new_figure(width=6.4, height=4.8):
    """A figure with an Agg canvas (headless)."""
    figure = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(figure)
    return figure


def save_figure(figure, stem, formats=("png", "svg")):
    """Save ``figure`` as ``stem.<format>`` for each format, atomically.

    Returns the list of paths written.
    """
    written = []
    for fmt in formats:
        if fmt not in FORMATS:
            raise InputError(f"unknown figure format {fmt!r}; use {', '.join(FORMATS)}")
        path = Path(f"{stem}.{fmt}")
        with mpl.rc_context({"svg.hashsalt": "orbits", "svg.fonttype": "path"}):
            with atomic_path(path) as temporary:
                figure.savefig(temporary, format=fmt, dpi=DPI,
                               metadata=_METADATA[fmt])
        written.append(path)
    return written


def _stem(row):
    multiple = f"n{row.n:03d}" if row.q == 1 else f"p{row.n:03d}q{row.q}"
    return f"herpolhode_{row.branch}_{multiple}"


def _paper_order(orbits):
    """Fig. 6's order: left to right in theta (SAM n up, then LAM n down)."""
    return orbits.sort_values("dtheta", kind="stable").reset_index(drop=True)


def herpolhode_set(body, n_max, out_dir, *, q_max=1, formats=("png", "svg"),
                   progress=None, orbits=None):
    """One figure per closed orbit of ``body`` and a contact sheet.

    Parameters
    ----------
    body : Body
    n_max, q_max : int
        As :func:`orbits.closed_orbits`.
    out_dir : path
        Existing directory for the files.
    formats : sequence of str
        Any of ``png``, ``svg``, ``pdf``.
    progress : callable, optional
        Called with 1 after each figure.
    orbits : DataFrame, optional
        The catalog to draw (computed if omitted).

    Returns
    -------
    list of Path
        The files written (per orbit ``herpolhode_<branch>_n<NNN>`` or
        ``..._p<NNN>q<Q>``, then ``contact_sheet``).
    """
    out_dir = _directory(out_dir)
    if orbits is None:
        orbits = closed_orbits(body, n_max=n_max, q_max=q_max)
    orbits = _paper_order(orbits)
    name = body.name or "body"
    written = []
    for row in orbits.itertuples():
        figure = new_figure(5.2, 5.4)
        ax = figure.add_subplot()
        plotting.plot_herpolhode(ax, body, dtheta=row.dtheta, periods=row.q)
        ax.set_title(plotting.orbit_label(row, name), fontsize="small")
        written += save_figure(figure, out_dir / _stem(row), formats)
        if progress is not None:
            progress(1)
    if len(orbits):
        written += save_figure(contact_sheet(body, orbits), out_dir / "contact_sheet",
                               formats)
    if progress is not None:
        progress(1)
    return written


def contact_sheet(body, orbits, columns=None):
    """All closed herpolhodes of a body in one grid, in Fig. 6's order."""
    orbits = _paper_order(orbits)
    count = len(orbits)
    columns = columns or max(1, min(8, math.ceil(math.sqrt(count * 1.5))))
    rows = math.ceil(count / columns)
    figure = new_figure(2.0 * columns, 2.15 * rows + 0.6)
    grid = figure.subplots(rows, columns, squeeze=False)
    for ax in grid.ravel():
        ax.set_axis_off()
    for ax, row in zip(grid.ravel(), orbits.itertuples()):
        plotting.plot_herpolhode(ax, body, dtheta=row.dtheta, periods=row.q,
                                 label_axes=False, linewidth=0.5)
        multiple = f"{row.n}" if row.q == 1 else f"{row.n}/{row.q}"
        ax.set_title(rf"{row.branch} $2\pi\cdot{multiple}$, $\theta$={row.theta:.5f}",
                     fontsize="x-small")
    figure.suptitle(f"Closed herpolhodes of {body.name or 'the body'} "
                    "(invariable plane; left to right in theta)", fontsize="medium")
    return figure


def _directory(out_dir):
    path = Path(out_dir)
    if not path.is_dir():
        raise InputError(f"output directory {path} does not exist")
    return path


# ------------------------------------------------------------- the paper
T_HANDLE_SPIN = dict(theta=0.5 * np.pi - 0.15, phi=0.5 * np.pi - 0.2)   # Fig. 3


def figure1():
    """Fig. 1: the T-handle (8, 4, 1) and its equivalent ellipsoid."""
    figure = new_figure(6.0, 5.6)
    ax = figure.add_subplot(projection="3d")
    drawn = plotting.plot_t_handle(ax, 8.0, 4.0, 1.0)
    a, b, c = drawn["semi_axes"]
    ax.set_title("Fig. 1: T-handle $l_1$ = 8, $l_2$ = 4, $w$ = 1 and the equivalent ellipsoid\n"
                 f"(a, b, c) = ({a:.5f}, {b:.5f}, {c:.6f}), shrunk by 1/4", fontsize="small")
    return figure


def figure2(grid=None, resolution=300):
    """Fig. 2: the body-space map with contours of the minimum total phase."""
    figure = new_figure(8.2, 4.6)
    ax = figure.add_subplot()
    plotting.plot_body_space(ax, grid, resolution=resolution)
    ax.set_title("Fig. 2: physical bodies ($|I| = 1$) and their minimum total phase",
                 fontsize="small")
    return figure


def figure3():
    """Fig. 3: (a) momentum sphere and Binet ellipsoid, (b) omega(t), T-handle spin."""
    figure = new_figure(11.0, 4.8)
    left = figure.add_subplot(1, 2, 1, projection="3d")
    right = figure.add_subplot(1, 2, 2)
    body = Body.preset("t-handle")
    drawn = plotting.plot_binet(left, body, **T_HANDLE_SPIN)
    left.set_title(f"(a) $|M|$ = {drawn['momentum']:.6f} J s sphere and the Binet "
                   f"ellipsoid, E = {drawn['energy']:.6f} J", fontsize="small")
    plotting.plot_omega_components(right, body, **T_HANDLE_SPIN)
    right.set_title(r"(b) $\omega$ in the body, $\theta = \pi/2 - 0.15$, "
                    r"$\phi = \pi/2 - 0.2$", fontsize="small")
    figure.suptitle("Fig. 3: T-handle, I = (0.286827, 0.533256, 0.795844) J s$^2$",
                    fontsize="medium")
    return figure


def figure4():
    """Fig. 4: polhodes on the Binet ellipsoid coloured by Delta alpha mod 2 pi."""
    figure = new_figure(6.6, 5.8)
    ax = figure.add_subplot(projection="3d")
    plotting.plot_polhode_foliation(ax, Body.preset("t-handle"))
    ax.set_title("Fig. 4: T-handle polhodes, coloured by total phase mod $2\\pi$",
                 fontsize="small")
    return figure


def figure5():
    """Fig. 5: total, dynamic, geometric phase and period against theta."""
    figure = new_figure(7.0, 4.8)
    ax = figure.add_subplot()
    plotting.plot_phase_curves(ax, Body.preset("t-handle"))
    ax.set_title("Fig. 5: T-handle, phases and period against the spin's polar angle",
                 fontsize="small")
    return figure


def figure6(n_inset=3):
    """Fig. 6: total phase of the Fig. 6 body, 2 pi n levels, roots, herpolhode insets."""
    body = Body.preset("fig6")
    orbits = closed_orbits(body, n_max=8)
    figure = new_figure(9.0, 6.6)
    ax = figure.add_subplot()
    plotting.plot_total_phase(ax, body, orbits, n_levels=8)
    ax.set_title("Fig. 6: I = (0.26, 0.55, 0.793662) J s$^2$; closed herpolhodes at "
                 r"$\Delta\alpha = 2\pi n$", fontsize="small")
    insets = []
    shown = orbits[orbits["n"] <= n_inset + 1].sort_values("dtheta")
    slots = np.linspace(0.05, 0.80, len(shown))
    for x, row in zip(slots, shown.itertuples()):
        inset = ax.inset_axes([x, 0.55, 0.15, 0.28])
        plotting.plot_herpolhode(inset, body, dtheta=row.dtheta, label_axes=False,
                                 linewidth=0.5)
        inset.set_xticks([])
        inset.set_yticks([])
        inset.set_title(rf"{row.branch} $n$={row.n}" + "\n" + rf"$\theta$={row.theta:.4f}",
                        fontsize="xx-small")
        ax.annotate("", xy=(row.theta, row.total_phase), xytext=(x + 0.075, 0.55),
                    textcoords="axes fraction",
                    arrowprops=dict(arrowstyle="-", color="0.5", linewidth=0.5))
        insets.append((inset, row))
    figure.insets = insets
    return figure


PAPER_FIGURES = {"fig1": figure1, "fig2": figure2, "fig3": figure3, "fig4": figure4,
                 "fig5": figure5, "fig6": figure6}


def paper_figures(out_dir, *, formats=("png", "svg"), survey_grid=None, progress=None,
                  names=None):
    """Write the paper's figures as ``fig1`` ... ``fig6`` (or those in ``names``).

    ``survey_grid``: optional (i1, i2, minimum) for Fig. 2 (from a survey).
    """
    out_dir = _directory(out_dir)
    written = []
    for name in names or PAPER_FIGURES:
        build = PAPER_FIGURES[name]
        figure = build(survey_grid) if (name == "fig2" and survey_grid is not None) else build()
        written += save_figure(figure, out_dir / name, formats)
        if progress is not None:
            progress(1)
    return written
