"""``orbits verify``: the paper's exhaustive check of the closed form, three ways."""

from ..errors import InputError
from ..limits import (
    GAP_ROUNDING_FACTOR,
    ODE_ERROR_FACTOR,
    PHASE_ULPS,
    ROUTE_ULPS,
    VERIFY_ODE_RTOL,
    VERIFY_SECONDS_PER_CONDITION,
    check_verify_size,
)
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

# the words that end the summary's reason for rows on the separatrix
SEPARATRIX = "on the separatrix have no closed form"
_CHECK_LABELS = (
    ("montgomery", "(b) Montgomery"),
    ("ode_rotation", "(a) ODE rotation"),
    ("exact_motion", "(c) exact motion"),
    ("theta_orbit", "theta -> orbit"),
    ("closed_form_routes", "public routes"),
)


def _cmd_verify(args):
    import json

    if not args.tolerance > 0:
        raise InputError(
            f"--tolerance must be a positive number of radians, got {args.tolerance:g}"
        )
    if args.table is not None:
        from .._args import path_argument
        from ..atomic import ensure_writable

        if args.table == "-":
            # the summary (or its JSON) goes to standard output already
            raise InputError(
                "orbits verify: --table - would mix the table into the summary on "
                "standard output (and break --json): give --table a file"
            )
        ensure_writable(path_argument("--table", args.table), stdout_hint=False)
    one = any(getattr(args, name, None) is not None for name in BODY_SELECTORS)
    body = body_from_args(args) if one else None
    n_bodies = 1 if one else args.bodies
    total, memory = check_verify_size(n_bodies, args.angles)
    announce("verify", total * VERIFY_SECONDS_PER_CONDITION, memory)
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
        _print_summary(summary, args, one)
    if args.table is not None:
        from ..atomic import write_csv_atomic

        write_csv_atomic(report.table, args.table)
    return 0 if report.passed else EXIT_CHECK_FAILED


def _print_summary(summary, args, one):
    what = f"body {summary['body']}" if one else f"{args.bodies} bodies"
    print(
        f"orbits verify: {summary['initial_conditions']} initial conditions "
        f"({what} x {args.angles} angles), tolerance {args.tolerance:g} rad "
        f"(or {summary['phase_ulps']} ulps of the phase where that is larger)"
    )
    print(f"{'check':<16} {'max |discrepancy| (rad)':>24} {'ulps':>8}  result")
    notes = []
    for name, label in _CHECK_LABELS:
        check = summary["checks"][name]
        value = check["max_abs_error"]
        if value is None:
            shown, ulps = "n/a", ""
            verdict = "n/a" if check["not_applicable"] and check["passed"] else "FAIL"
        else:
            count = check["max_ulps"]
            shown, ulps = f"{value:.3e}", f"{count:.0f}" if count < 1e6 else f"{count:.1e}"
            verdict = "ok" if check["passed"] else "FAIL"
            if check["passed"] and check["not_applicable"]:
                verdict += " (partly n/a)"
        print(f"{label:<16} {shown:>24} {ulps:>8}  {verdict}")
        # the separatrix rows are noted once, below
        reasons = [
            part for part in (check["reason"] or "").split("; ") if part and SEPARATRIX not in part
        ]
        if reasons:
            notes.append(f"{label}: {'; '.join(reasons)}")
    period = summary["ode_period_max_abs_error"]
    print("ODE period vs eqn:TK: max |dT| = " + ("n/a" if period is None else f"{period:.3e}"))
    if summary["on_separatrix"]:
        notes.append(
            f"{summary['on_separatrix']} initial condition(s) on the separatrix (or within "
            "the rounding error of theta_c) have no closed form: verify fails there "
            "(branch 'separatrix' in --table)"
        )
    allowance = summary["largest_allowance"]
    if allowance is not None and allowance > args.tolerance:
        notes.append(
            f"the phases reach {summary['max_abs_phase']:.3g} rad, where doubles are "
            f"{summary['phase_resolution']:.3g} rad apart: there a discrepancy up to "
            f"{summary['phase_ulps']} of those spacings ({allowance:.3g} rad) passes"
        )
    ode = summary["checks"]["ode_rotation"]
    if ode.get("within_integrator_error_only"):
        notes.append(
            f"(a) ODE rotation: {ode['within_integrator_error_only']} discrepancy(ies) beyond "
            f"the tolerance are within the integrator's own error, "
            f"{summary['ode_error_factor']:g} x rtol ({summary['ode_rtol']:g}) x |w0| T "
            f"(T the period it found; its error grows with the turns integrated), or, "
            f"next to the separatrix, {summary['gap_rounding_factor']:g} x eps / g x "
            f"|d Delta alpha / d ln g| (what a rounding of the state moves the phase by; "
            f"g the relative gap), here up to {ode['largest_allowance']:.3g} rad; the "
            f"largest discrepancy is {ode['max_fraction_of_allowance']:.2g} of its allowance"
        )
    notes.append(
        f"theta -> orbit: the closed form of the exact theta (total_phase, phases) "
        f"against that of the double omega0 the checks start from, within "
        f"{summary['route_ulps']} ulps or, next to the separatrix, what the rounding "
        f"of omega0 moves the phase by"
    )
    notes.append(
        f"public routes: orbits.total_phase (both SIMD kernels), orbits.phases "
        f"('orbits phase') and orbits.spin_phases against the scalar closed form of "
        f"the same orbit, within {summary['route_ulps']} ulps whatever the tolerance"
    )
    for note in notes:
        print(f"note: {note}")
    print("result: " + ("ok" if summary["passed"] else "FAIL"))


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
        f"rtol {VERIFY_ODE_RTOL:g}), (b) Montgomery's 2ET/M - Omega by quadrature "
        "along the polhode, and (c) phi(T) of the exact motion; "
        "that the closed form of the exact theta (the orbit orbits.total_phase "
        "and orbits.phases take) agrees with that of the double omega0 the "
        f"checks start from (theta -> orbit: {ROUTE_ULPS} ulps, or the rounding of "
        "omega0 next to the separatrix); and "
        "that the closed form as orbits.total_phase, orbits.phases ('orbits "
        f"phase') and orbits.spin_phases compute it agrees with it to {ROUTE_ULPS} "
        "ulps.  Exits with 1 if any discrepancy exceeds the tolerance (or "
        f"{PHASE_ULPS} spacings of doubles at the phase, where that is larger: "
        "near the sphere the phases reach 1e9 rad, where doubles are 1e-7 apart; "
        f"for (a) also {ODE_ERROR_FACTOR:g} x rtol x |w0| T, its integrator's own "
        "error, which grows with the period T it integrates, and next to the "
        f"separatrix {GAP_ROUNDING_FACTOR:g} x eps / g x |d Delta alpha / d ln g|, "
        "what a rounding of the state moves the phase by, g the relative gap), "
        "if a check gives no value, or if an angle lies on the separatrix.  "
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
        help="largest allowed discrepancy, radians (default 1e-9); a discrepancy "
        f"within {PHASE_ULPS} spacings of doubles at the phase passes too, and for "
        f"check (a) one within {ODE_ERROR_FACTOR:g} x rtol x |w0| T (its integrator's error) "
        f"or, next to the separatrix, {GAP_ROUNDING_FACTOR:g} x eps / g x |d Delta alpha / "
        "d ln g| (the rounding of its state)",
    )
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.add_argument(
        "--table",
        metavar="FILE.csv",
        help="also write every initial condition and its discrepancies to this CSV "
        "file (not '-': the summary is on standard output; branch 'separatrix' marks "
        "an angle with no closed form)",
    )
    parser.add_argument(
        "--no-progress", action="store_true", help="no progress bar even on a terminal"
    )
    parser.set_defaults(run=_cmd_verify)
