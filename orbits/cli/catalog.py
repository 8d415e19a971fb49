"""``orbits catalog``: every closed orbit of one or many bodies, as a CSV file."""

import sys

from ..limits import check_search_bounds
from .shared import (
    EXIT_CHECK_FAILED,
    add_body_options,
    announce,
    bodies_from_args,
    command_line,
    positive_int,
    progress_bar,
)


def _check_out(path):
    """``--out`` for a file: '-' is standard output; else it must be writable."""
    if path == "-":
        return
    from ..atomic import ensure_writable

    ensure_writable(path)


def _cmd_catalog(args):
    import time
    import warnings

    from ..catalog import CLOSURE_TOLERANCE, catalog, write_catalog
    from ..search import UnresolvedOrbitsWarning

    _check_out(args.out)
    bodies, notes = bodies_from_args(args)
    memory, seconds = check_search_bounds(args.n_max, args.q_max, len(bodies), "the catalog")
    announce("catalog", seconds * (3 if args.verify else 1), memory)
    start = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UnresolvedOrbitsWarning)
        with progress_bar(
            len(bodies), "catalog", None if len(bodies) > 1 else False, unit="body"
        ) as bar:
            frame = catalog(
                bodies, n_max=args.n_max, q_max=args.q_max, verify=args.verify, progress=bar.update
            )
    write_catalog(frame, args.out, command=command_line(args.argv), notes=notes)
    for warning in caught:
        print(f"orbits: warning: {warning.message}", file=sys.stderr)
    elapsed = time.perf_counter() - start
    note = ""
    if args.verify:
        worst = float(frame["closure_error"].max()) if len(frame) else 0.0
        note = f"; largest closure error {worst:.2e} rad"
    print(
        f"orbits catalog: {len(frame)} closed orbits of {len(bodies)} "
        f"body(ies) written to {'standard output' if args.out == '-' else args.out} "
        f"in {elapsed:.2f} s{note}",
        file=sys.stderr,
    )
    if args.verify and len(frame) and frame["closure_error"].max() > CLOSURE_TOLERANCE:
        print(f"orbits: error: closure errors above {CLOSURE_TOLERANCE:g} rad", file=sys.stderr)
        return EXIT_CHECK_FAILED
    return 0


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "catalog",
        help="find every closed orbit of a body and write a CSV",
        description="Finds every initial spin (phi = 0, |omega0| = 1, theta in "
        "(0, pi/2), both branches) whose total phase is 2 pi p/q "
        "with p/q <= N and q <= Q: the body returns to its starting "
        "orientation after q periods and the herpolhode closes.  "
        "Writes one row per orbit (schema in the README); the file "
        "starts with '#' lines recording the version and this "
        "command, so read it with pandas.read_csv(path, "
        "comment='#').  The output is written atomically.",
    )
    add_body_options(parser, many=True)
    parser.add_argument(
        "--n-max", type=positive_int, required=True, help="largest multiple n (or p/q) of 2 pi"
    )
    parser.add_argument(
        "--q-max",
        type=positive_int,
        default=1,
        help="also orbits closing after up to Q periods, "
        "Delta alpha = 2 pi p/q (default 1: integers only)",
    )
    parser.add_argument(
        "--verify",
        action="store_true",
        help="add closure_error: an independent integration of "
        "each orbit over q periods (exit 1 if any exceeds "
        "1e-8 rad)",
    )
    parser.add_argument(
        "--out",
        required=True,
        metavar="FILE.csv",
        help="output CSV ('-': standard output); never a device, FIFO or socket",
    )
    parser.set_defaults(run=_cmd_catalog)
