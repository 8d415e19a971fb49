"""``orbits verify``: the paper's exhaustive check of the closed form, three ways."""

from ..errors import InputError
from ..limits import format_bytes, memory_budget
from .shared import (
    BODY_SELECTORS,
    EXIT_CHECK_FAILED,
    Parser,
    add_body_options,
    announce,
    body_from_args,
    finite,
    positive_int,
    progress_bar,
)

# measured here: 64,460 initial conditions in 1.5 s; the table holds ~20
# float columns and the integrations keep a few more per condition
_VERIFY_SECONDS_PER_CONDITION = 3e-5
_VERIFY_BYTES_PER_CONDITION = 2000


def _cmd_verify(args):
    import json

    if not args.tolerance > 0:
        raise InputError(
            f"--tolerance must be a positive number of radians, got {args.tolerance:g}"
        )
    if args.table:
        from ..atomic import ensure_writable

        ensure_writable(args.table)
    one = any(getattr(args, name, None) is not None for name in BODY_SELECTORS)
    body = body_from_args(args) if one else None
    n_bodies = 1 if one else args.bodies
    total = n_bodies * args.angles
    memory = total * _VERIFY_BYTES_PER_CONDITION
    if memory > memory_budget():
        raise InputError(
            f"verify with {n_bodies} bodies x {args.angles} angles = "
            f"{total} initial conditions would need about {format_bytes(memory)} "
            f"of memory, more than the {format_bytes(memory_budget())} allowed "
            "(half of this machine's)"
        )
    announce("verify", total * _VERIFY_SECONDS_PER_CONDITION, memory)
    # imports SciPy (seconds on a cold start): after the estimate
    from ..checks import verify, verify_body

    with progress_bar(total, "verify", None if not args.no_progress else False) as bar:
        if one:
            report = verify_body(body, args.angles, tolerance=args.tolerance, progress=bar.update)
        else:
            report = verify(
                args.bodies, args.angles, tolerance=args.tolerance, progress=bar.update
            )
    summary = report.summary
    if one:
        summary["body"] = body.name or repr(body)
        summary["moments"] = [float(v) for v in body.moments]
    if args.json:
        # strict JSON: a value that cannot exist is null with a reason, never NaN
        print(json.dumps(summary, indent=2, allow_nan=False))
    else:
        what = f"body {summary['body']}" if one else f"{args.bodies} bodies"
        print(
            f"orbits verify: {summary['initial_conditions']} initial conditions "
            f"({what} x {args.angles} angles), tolerance "
            f"{args.tolerance:g} rad"
        )
        print(f"{'check':<16} {'max |discrepancy| (rad)':>24}  result")
        notes = []
        for name, label in (
            ("montgomery", "(b) Montgomery"),
            ("ode_rotation", "(a) ODE rotation"),
            ("exact_motion", "(c) exact motion"),
        ):
            check = summary["checks"][name]
            value = check["max_abs_error"]
            if value is None:
                shown, verdict = "n/a", "n/a" if check["not_applicable"] else "FAIL"
            else:
                shown = f"{value:.3e}"
                verdict = "ok" if value <= args.tolerance else "FAIL"
                if check["failed_to_evaluate"]:
                    verdict = "FAIL"
                elif check["not_applicable"]:
                    verdict += " (partly n/a)"
            print(f"{label:<16} {shown:>24}  {verdict}")
            if check["reason"]:
                notes.append(f"{label}: {check['reason']}")
        period = summary["ode_period_max_abs_error"]
        print("ODE period vs eqn:TK: max |dT| = " + ("n/a" if period is None else f"{period:.3e}"))
        resolution = summary["phase_resolution"]
        if resolution is not None and resolution > args.tolerance / 4:
            notes.append(
                f"the phases reach {summary['max_abs_phase']:.3g} rad, where doubles are "
                f"{resolution:.3g} rad apart: no check can agree more closely than "
                "a few times that"
            )
        for note in notes:
            print(f"note: {note}")
    if args.table:
        from ..atomic import write_csv_atomic

        write_csv_atomic(report.table, args.table)
    return 0 if report.passed else EXIT_CHECK_FAILED


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "verify",
        help="check the closed form three independent ways",
        description="The paper's exhaustive check: bodies spread evenly over "
        "the region of physical bodies times angles in "
        "0 < theta < pi/2 (phi = 0).  For each initial condition "
        "the closed-form total phase (eqn:GeometricPhase) is "
        "compared with (a) the rotation about M after one period "
        "of Euler's equations integrated numerically (DOP853, "
        "rtol 1e-12), (b) Montgomery's 2ET/M - Omega by quadrature "
        "along the polhode, and (c) phi(T) of the exact motion.  "
        "Exits with 1 if any discrepancy exceeds the tolerance.  "
        "The defaults give the paper's 6446 initial conditions.",
    )
    parser.add_argument(
        "--bodies", type=positive_int, default=293, help="number of bodies (default 293)"
    )
    group = parser.add_argument_group(
        "your own body (optional)",
        "Instead of the region sample, check one body given by any of the body "
        "options of 'orbits phase' (e.g. --moments, --box ... --mass M, --mesh F)",
    )
    # the body options without --bodies (which is the count here)
    sub = Parser(add_help=False)
    add_body_options(sub)
    for action in sub._actions:
        if action.dest in BODY_SELECTORS or action.dest in (
            "mass",
            "density",
            "constants_unit",
            "defect",
            "name",
        ):
            action.required = False
            group._add_action(action)
    parser.add_argument(
        "--angles",
        type=positive_int,
        default=22,
        help="number of angles theta_j = (j + 1/2) pi / (2 K) (default 22)",
    )
    parser.add_argument(
        "--tolerance",
        type=finite,
        default=1e-9,
        help="largest allowed discrepancy, radians (default 1e-9)",
    )
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.add_argument(
        "--table",
        metavar="FILE.csv",
        help="also write every initial condition and its discrepancies to this CSV",
    )
    parser.add_argument(
        "--no-progress", action="store_true", help="no progress bar even on a terminal"
    )
    parser.set_defaults(run=_cmd_verify)
