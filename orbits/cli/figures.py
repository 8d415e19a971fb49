"""``orbits figures``: closed herpolhodes of a body, the paper's figures, Fig. 2 of a survey."""

import math
import sys

from ..errors import InputError
from ..limits import check_search_bounds, plural
from .shared import (
    BODY_SELECTORS,
    add_body_options,
    announce,
    body_from_args,
    positive_int,
    progress_bar,
)


def _output_directory(path, names, made):
    """Create (or check) the output directory and every file to be written in it.

    Done before the long part, so that a bad target is one line at once.
    The directories made for it are added to ``made`` as they are made
    (:func:`orbits.atomic.make_directories`), for the caller to remove
    after an error or a stop.
    """
    import os
    from pathlib import Path

    from ..atomic import check_targets, make_directories, refuse_link

    if str(path) == "-":
        raise InputError(
            "orbits figures writes a directory of files; --out - (standard output) "
            "cannot take them: give a directory"
        )
    directory = Path(path)
    refuse_link(directory)
    if directory.exists() and not directory.is_dir():
        raise InputError(f"output path {directory} exists and is not a directory")
    try:
        make_directories(directory, made)
    except OSError as error:
        blocking = next((p for p in directory.parents if p.exists() and not p.is_dir()), None)
        if blocking is not None:
            raise InputError(
                f"cannot create output directory {directory}: {blocking} is not a directory"
            ) from None
        raise InputError(f"cannot create output directory {directory}: {error.strerror}") from None
    if not directory.is_dir():
        raise InputError(f"output path {directory} is not a directory")
    if not os.access(directory, os.W_OK | os.X_OK):
        raise InputError(f"cannot write into output directory {directory}: it is not writable")
    check_targets(directory, names)
    return directory


def _refuse_long_curves(body, n_max):
    """Refuse, before the search, an ``n_max`` whose orbits no figure can draw.

    The orbit at the largest even ``n <= n_max`` closes after one period:
    its herpolhode makes ``n`` turns, drawn only up to
    :data:`orbits.plotting.MAX_TURNS` (p/q orbits are checked after the
    search, by :func:`orbits.figures.check_figure_set`).
    """
    from ..plotting import MAX_TURNS, check_turns
    from ..search import minimum_phase

    even = n_max // 2 * 2
    if even > MAX_TURNS and minimum_phase(body)[0] <= math.tau * even:
        check_turns(even, f"the closed herpolhode at n = {even}", "lower --n-max")


def _cmd_figures(args):
    from ..atomic import remove_directories

    # the directories made for --out: after an error or a stop they are
    # removed again (those still empty: a set is written whole or not at all)
    made = []
    try:
        return _figures(args, made)
    except BaseException:
        remove_directories(made)
        raise


def _figures(args, made):
    import time

    from .. import figures
    from .._args import path_argument

    selectors = [
        args.paper,
        args.survey is not None,
        any(getattr(args, name) is not None for name in BODY_SELECTORS),
    ]
    if sum(selectors) != 1:
        options = ", ".join("--" + name.replace("_", "-") for name in BODY_SELECTORS)
        raise InputError(
            f"orbits figures: give exactly one of a body ({options}), --paper or --survey DIR"
        )
    # every input is checked before the output directory is created
    path_argument("--out", args.out)
    start = time.perf_counter()
    if args.paper or args.survey is not None:
        grid = None
        if args.survey is not None:
            from ..survey import survey_grid

            grid = survey_grid(path_argument("--survey", args.survey))
        names = ["fig2"] if args.survey is not None else list(figures.PAPER_FIGURES)
        out = _output_directory(args.out, figures.figure_files(names, args.formats), made)
        with progress_bar(len(names), "figures", unit="figure") as bar:
            written = figures.paper_figures(
                out, formats=args.formats, survey_grid=grid, progress=bar.update, names=names
            )
    else:
        if args.n_max is None:
            raise InputError("orbits figures: --n-max is required with a body")
        body = body_from_args(args)
        from ..search import closed_orbits

        memory, seconds = check_search_bounds(args.n_max, args.q_max, 1, "the figures' search")
        _refuse_long_curves(body, args.n_max)
        announce("figures", seconds, memory)
        orbits_table = closed_orbits(body, n_max=args.n_max, q_max=args.q_max)
        if len(orbits_table) == 0:
            # the search's minimum (an end, where every probe fell: no full scan)
            low = min(value for value, _ in orbits_table.attrs["minimum_phase"].values())
            raise InputError(
                f"orbits figures: this body has no closed orbit with n <= {args.n_max}"
                + (f" (q <= {args.q_max})" if args.q_max > 1 else "")
                + f", nothing to draw: its smallest total phase is {low / math.tau:.4g} "
                "turns; raise --n-max"
            )
        # drawing is the long part: estimated (and refused) before any file
        memory, seconds = figures.check_figure_set(
            len(orbits_table),
            args.formats,
            "lower --n-max or --q-max",
            turns=figures.drawn_turns(orbits_table),
        )
        out = _output_directory(args.out, figures.set_file_names(orbits_table, args.formats), made)
        announce("figures", seconds, memory)
        with progress_bar(len(orbits_table) + 1, "figures", unit="figure") as bar:
            written = figures.herpolhode_set(
                body,
                args.n_max,
                out,
                q_max=args.q_max,
                formats=args.formats,
                progress=bar.update,
                orbits=orbits_table,
            )
    print(
        f"orbits figures: {plural(len(written), 'file')} written to {out} in "
        f"{time.perf_counter() - start:.1f} s",
        file=sys.stderr,
    )
    return 0


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "figures",
        help="draw closed herpolhodes, or the paper's six figures",
        description="With a body: one figure per closed orbit (each n, both "
        "branches, p/q orbits with --q-max), each drawn over the "
        "time its herpolhode closes in (the catalog's closes_after: "
        "T/2 for odd n, q/2 periods when p and q are odd, else q) "
        "in the invariable plane, plus a contact "
        "sheet of them all in the paper's Fig. 6 order.  With "
        "--paper: Figs. 1-6 of the paper.  With --survey DIR: "
        "Fig. 2 from a survey directory.  Files are written "
        "atomically and deterministically (headless).",
    )
    group = add_body_options(parser)
    for action in group._group_actions:
        action.required = False
    parser._mutually_exclusive_groups[-1].required = False
    parser.add_argument("--paper", action="store_true", help="draw the paper's six figures")
    parser.add_argument(
        "--survey",
        metavar="DIR",
        help="draw Fig. 2 from the survey in DIR (orbits survey --resolution; "
        "a --bodies survey has no grid to draw)",
    )
    parser.add_argument(
        "--n-max",
        type=positive_int,
        help="with a body (required there): largest multiple n (or p/q) of 2 pi",
    )
    parser.add_argument(
        "--q-max",
        type=positive_int,
        default=1,
        help="with a body: also p/q orbits closing after up to Q periods (default 1)",
    )
    parser.add_argument(
        "--formats",
        nargs="+",
        default=["png", "svg"],
        choices=["png", "svg", "pdf"],
        help="file formats (default: png svg)",
    )
    parser.add_argument(
        "--out", required=True, metavar="DIR", help="output directory (created if missing)"
    )
    parser.set_defaults(run=_cmd_figures)
