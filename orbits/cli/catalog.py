"""``orbits catalog``: every closed orbit of one or many bodies, as a CSV file."""

import sys

from ..errors import InputError
from ..limits import check_search_bounds, plural
from ..units import OMEGA_UNITS, REVOLUTIONS_NOTE
from .shared import (
    EXIT_CHECK_FAILED,
    add_body_options,
    announce,
    bodies_from_args,
    command_line,
    finite,
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

    import numpy as np

    from .._args import held_warnings
    from ..catalog import CLOSURE_TOLERANCE, catalog, write_catalog

    _check_out(args.out)
    if args.nearest is not None or args.omega is not None:
        return _nearest(args)
    if args.n_max is None:
        raise InputError("orbits catalog: give --n-max N (or --omega W1 W2 W3 with --nearest K)")
    bodies, notes = bodies_from_args(args)
    memory, seconds = check_search_bounds(args.n_max, args.q_max, len(bodies), "the catalog")
    announce("catalog", seconds * (3 if args.verify else 1), memory)
    start = time.perf_counter()
    with held_warnings() as caught:  # told after the catalog is written
        with progress_bar(
            len(bodies), "catalog", None if len(bodies) > 1 else False, unit="body"
        ) as bar:
            frame = catalog(
                bodies, n_max=args.n_max, q_max=args.q_max, verify=args.verify, progress=bar.update
            )
    write_catalog(frame, args.out, command=command_line(args.argv), notes=notes)
    for message, _ in caught:
        print(f"orbits: warning: {message}", file=sys.stderr)
    elapsed = time.perf_counter() - start
    note = ""
    if args.verify and len(frame):
        worst = float(frame["closure_error"].max())
        note = f"; largest closure error {worst:.2e} rad"
    elif args.verify:
        note = "; no orbit to verify"
    print(
        f"orbits catalog: {plural(len(frame), 'closed orbit')} of "
        f"{plural(len(bodies), 'body', 'bodies')} written to "
        f"{'standard output' if args.out == '-' else args.out} "
        f"in {elapsed:.2f} s{note}",
        file=sys.stderr,
    )
    if args.verify and len(frame):
        from ..checks import closure_error_budget

        # the check's own error, where it exceeds the tolerance (thin rods)
        allowed = np.maximum(
            CLOSURE_TOLERANCE,
            closure_error_budget(
                frame[["I1", "I2", "I3"]].to_numpy(),
                frame["dtheta"].to_numpy(),
                frame["q"].to_numpy(),
            ),
        )
        errors = frame["closure_error"].to_numpy()
        beyond = ~(errors <= allowed)
        within_own = int(np.count_nonzero(~beyond & (errors > CLOSURE_TOLERANCE)))
        if within_own:
            print(
                f"orbits: note: {plural(within_own, 'closure error')} above "
                f"{CLOSURE_TOLERANCE:g} rad within the check's own error (up to "
                f"{float(allowed.max()):.2g} rad: rtol x I3/I1 x q, a thin body)",
                file=sys.stderr,
            )
        if beyond.any():
            print(
                f"orbits: error: {plural(int(beyond.sum()), 'closure error')} above "
                f"{CLOSURE_TOLERANCE:g} rad (and the check's own error)",
                file=sys.stderr,
            )
            return EXIT_CHECK_FAILED
    return 0


def _nearest(args):
    """``--omega`` with ``--nearest K``: the K closed orbits nearest a real spin."""
    import time

    from ..catalog import nearest_orbits, write_catalog

    if args.omega is None or args.nearest is None:
        raise InputError("orbits catalog: --nearest K and --omega W1 W2 W3 go together")
    for option, value in (("--n-max", args.n_max), ("--bodies", getattr(args, "bodies", None))):
        if value is not None:
            raise InputError(f"orbits catalog: {option} does not apply with --nearest")
    if args.verify:
        raise InputError("orbits catalog: --verify does not apply with --nearest")
    (body,), notes = bodies_from_args(args)
    start = time.perf_counter()
    frame = nearest_orbits(body, args.omega, args.nearest, args.q_max, units=args.units)
    spin = frame.attrs
    notes = [
        *notes,
        f"nearest closed orbits of the spin omega = ({', '.join(f'{v:g}' for v in args.omega)})"
        f" {args.units} in the body's own axes: {spin['branch']}, total phase "
        f"{spin['total_phase']:.12g} rad, |L| = {spin['momentum']:.12g} (moments' unit x rad/s)",
        "ranked by branch (the spin's first), then |total_phase - the spin's|; "
        f"omega_x, omega_y, omega_z: the orbit's starting spin at that |L|, body's own axes, "
        f"{args.units}; period_s: its period in s",
    ]
    write_catalog(frame, args.out, command=command_line(args.argv), notes=notes)
    count = len(frame)
    print(
        f"orbits catalog: the {count} closed {'orbit' if count == 1 else 'orbits'} nearest "
        f"the spin ({spin['branch']}, total phase {spin['total_phase']:.6g} rad) written to "
        f"{'standard output' if args.out == '-' else args.out} "
        f"in {time.perf_counter() - start:.2f} s",
        file=sys.stderr,
    )
    return 0


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "catalog",
        help="find every closed orbit of a body and write a CSV",
        description="Finds every initial spin (phi = 0, |omega0| = 1, theta in "
        "(0, pi/2), both branches) whose total phase is 2 pi p/q "
        "with p/q <= N and q <= Q: the body returns to its starting "
        "orientation after q periods and the herpolhode closes.  "
        "Writes one row per orbit (schema: docs/catalog.md); the file "
        "starts with '#' lines recording the version and this "
        "command, so read it with orbits.read_catalog(path), or with "
        "pandas.read_csv(path, comment='#') (pandas 2.x: add "
        "float_precision='round_trip' to read the floats back bit for bit).  "
        "With --nearest the rows are ranked by nearness, not sorted by theta, "
        "and four columns are added.  The output is written atomically.",
    )
    add_body_options(parser, many=True)
    parser.add_argument(
        "--n-max",
        type=positive_int,
        help="largest multiple n (or p/q) of 2 pi (required, except with --nearest)",
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
        "each orbit (over q periods; closer than 1e-3 rad to theta_crit, "
        "a quarter period from its closest approach to I2) "
        "(exit 1 if any exceeds 1e-8 rad)",
    )
    nearest = parser.add_argument_group("nearest closed orbits of a real spin")
    nearest.add_argument(
        "--omega",
        nargs=3,
        type=finite,
        metavar=("W1", "W2", "W3"),
        help="a real spin along the body's own axes (x y z of --box, the order "
        "of --moments, the input frame of --point-masses/--mesh), in --units; "
        "with --nearest",
    )
    nearest.add_argument(
        "--units",
        choices=list(OMEGA_UNITS),
        default="rad/s",
        help="unit of --omega and of the omega_x/y/z columns (default rad/s); " + REVOLUTIONS_NOTE,
    )
    nearest.add_argument(
        "--nearest",
        type=positive_int,
        metavar="K",
        help="write the K closed orbits nearest the --omega spin (its branch "
        "first, then by |total phase - the spin's|), each started at the "
        "spin's |L| near its direction, with columns omega_x, omega_y, "
        "omega_z (in --units) and period_s (s)",
    )
    parser.add_argument(
        "--out",
        required=True,
        metavar="FILE.csv",
        help="output CSV ('-': standard output); never a device, FIFO or socket",
    )
    parser.set_defaults(run=_cmd_catalog)
