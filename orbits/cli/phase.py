"""``orbits phase``: closed-form phases of one body at given spins.

Spins by polar angle (``--theta``/``--dtheta`` with ``--phi``), as an
angular-velocity vector (``--omega``, physical units) or found from a
total phase or a tumbling period ratio; printed as a table or CSV.
"""

import argparse
import math
import sys

from ..errors import InputError
from ..units import OMEGA_UNITS, REVOLUTIONS_NOTE, TIME_UNITS
from .shared import add_body_options, angle_argument, body_from_args, finite, offset_argument


def _cmd_phase(args):
    import numpy as np

    # numpy's overflow warnings would add lines to stderr; a non-finite result
    # is refused by _print_table instead (never a silent inf or nan)
    with np.errstate(all="ignore"):
        return _phase_table(args)


def _phase_table(args):
    if args.time_unit is not None and args.periods is None:
        raise InputError("orbits phase: --time-unit applies to --periods")
    body = body_from_args(args)
    if getattr(args, "name", None) is not None:
        args.label = body.name  # --name: the first row (a first column in CSV)
    if args.omega is not None:
        table = _omega_table(body, args)
        return _print_table(
            table,
            args.csv,
            _omega_units(args, _moment_unit(args)),
            _flip_note(table),
            getattr(args, "label", None),
        )
    if args.periods is not None:
        return _periods_table(body, args)
    if args.total_phase is not None or args.period_ratio is not None:
        from .. import tumbling

        if args.total_phase is not None:
            table = tumbling.spins_with_total_phase(body, angle_argument(args.total_phase, args))
        else:
            table = tumbling.spins_with_period_ratio(body, args.period_ratio)
        return _print_table(table, args.csv, NORMALISED_UNITS, label=getattr(args, "label", None))
    from ..phases import phases

    theta = None if args.theta is None else [angle_argument(v, args) for v in args.theta]
    dtheta = None if args.dtheta is None else [offset_argument(v, args) for v in args.dtheta]
    table = phases(body, theta, angle_argument(args.phi, args), dtheta=dtheta)
    return _print_table(table, args.csv, NORMALISED_UNITS, label=getattr(args, "label", None))


# units of the printed rows (text tables; with --csv a first "# units:" line)
PRINCIPAL = "principal axes I1<I2<I3"
NORMALISED_UNITS = {
    **dict.fromkeys(["I1", "I2", "I3", "D"], "|I|=1"),
    **dict.fromkeys(["energy", "momentum"], "|I|=|w0|=1"),
    **dict.fromkeys(
        [
            "theta",
            "dtheta",
            "phi",
            "theta_crit",
            "dynamic_phase",
            "total_phase",
            "geometric_phase",
            "target",
            "residual",
        ],
        "rad",
    ),
    "m": "1",
    "period": "1/|w0|",
}
REAL_BODIES = ("box", "cylinder", "point_masses", "mesh", "rotational_constants")


def _moment_unit(args):
    """kg m^2 for the bodies built from masses and lengths (kg, m), else the moments' own."""
    real = any(getattr(args, name, None) is not None for name in REAL_BODIES)
    return "kg m^2" if real else "I"


def _omega_units(args, moment):
    joule = moment == "kg m^2"
    return {
        **dict.fromkeys(["I1", "I2", "I3", "D"], moment),
        **dict.fromkeys(["w1", "w2", "w3"], f"rad/s, {PRINCIPAL}"),
        "D_normalised": "|I|=1",
        "energy": "J" if joule else "I rad^2/s^2",
        "momentum": "J s" if joule else "I rad/s",
        "m": "1",
        **dict.fromkeys(["period", "precession_period", "rotation_period"], "s"),
        "period_ratio": "1",
        **dict.fromkeys(["dynamic_phase", "total_phase", "geometric_phase"], "rad"),
    }


def _flip_note(table):
    """Near the intermediate axis, the flip: omega's I2 part reverses every T/2."""
    row = table.iloc[0]
    components = [abs(float(row[name])) for name in ("w1", "w2", "w3")]
    half = 0.5 * float(row["period"])
    if components.count(0.0) == 2:  # along I1 or I3 (along I2 is refused: the separatrix)
        axis = "I1" if components[0] else "I3"
        return [f"steady spin about {axis}: omega stays along {axis} (no polhode, no flip)"]
    if components[1] < max(components):
        return [
            f"omega's I2 component reverses every T/2 = {half:.6g} s "
            "(far from the intermediate axis: no flip is seen)"
        ]
    return [
        f"spin about the intermediate axis I2: the body flips (I2 turns over, the "
        f"tennis-racket flip) every T/2 = {half:.6g} s"
    ]


def _periods_table(body, args):
    """``--periods P_PSI P_PHI``: the tumbling spins with those periods (Pravec et al. 2005)."""
    from ..tumbling import spins_with_periods
    from ..units import time_factor

    unit = args.time_unit or "s"
    time_factor(unit)  # a known unit (argparse checked it too)
    table = spins_with_periods(body, *args.periods)
    moment = _moment_unit(args)
    units = {
        "branch": "-",
        "axis": "-",
        **dict.fromkeys(["P_psi", "P_phi", "P_about_L"], unit),
        "E_over_E0": "1",
        **dict.fromkeys(["theta", "dtheta", "total_phase"], "rad"),
        **dict.fromkeys(["w1", "w2", "w3"], f"rad/{unit}, {PRINCIPAL}"),
        "energy": f"{moment} rad^2/{unit}^2",
        "momentum": f"{moment} rad/{unit}",
        "D": moment,
    }
    count = len(table)
    notes = [
        f"{count} {'spin' if count == 1 else 'spins'} with P_psi = {args.periods[0]:g} {unit} "
        f"and P_phi = {args.periods[1]:g} {unit} (Pravec et al. 2005: P_psi the rotation, "
        "P_phi the precession period of the short (SAM) or long (LAM) axis about L; "
        "E_over_E0 = 2 E I3 / M^2; theta at phi = 0)"
    ]
    return _print_table(table, args.csv, units, notes, getattr(args, "label", None))


def _omega_table(body, args):
    """One row for a spin given as a vector: physical outputs and D = M^2/(2E).

    omega is given along the caller's axes (the order of --moments, x y z of
    --box, a b c of --rotational-constants, ...) in --units, turned to the
    principal frame with Body.frame.
    With moments in kg m^2 the energy is in J, |L| in J s and the periods
    in s; ``D_normalised = D/|I|`` is the ``D`` of the orbit's catalog row.
    """
    import numpy as np
    import pandas as pd

    from ..motion import Motion
    from ..phases import spin_phases

    omega = np.array(args.omega) * OMEGA_UNITS[args.units]
    motion = Motion.from_omega(body, omega, axes="body")
    principal = motion.omega0
    periods = motion.tumbling_periods()
    total = motion.total_phase()
    # 2ET/M on the unit scale (2 E T overflowed for moments near 1e308), and
    # Omega in its closed form: dynamic - total cancels near the sphere
    row = spin_phases(body, principal).iloc[0]
    dynamic, geometric = float(row["dynamic_phase"]), float(row["geometric_phase"])
    i1, i2, i3 = body.moments
    return pd.DataFrame(
        {
            "I1": [i1],
            "I2": [i2],
            "I3": [i3],
            "w1": [principal[0]],
            "w2": [principal[1]],
            "w3": [principal[2]],
            "branch": [motion.branch],
            "D": [motion.D],
            # the catalog's D (|I| = 1): the row of this orbit in a catalog
            # D / |I| at the unit scale (exact powers of two): |I| itself
            # over- or underflows for moments beyond 1e+-154
            "D_normalised": [
                math.ldexp(motion.D, -body.exponent) / float(np.linalg.norm(body.unit_moments))
            ],
            "energy": [motion.energy],
            "momentum": [motion.momentum],
            "m": [motion.m],
            "period": [motion.period],
            "precession_period": [periods.precession],
            "rotation_period": [periods.rotation],
            "period_ratio": [periods.ratio],
            "dynamic_phase": [dynamic],
            "total_phase": [total],
            "geometric_phase": [geometric],
        }
    )


def format_value(value):
    """A table cell: floats at full precision, shortest round-trip form.

    ``repr`` of a float is the shortest string that reads back to the same
    double, in scientific notation for small and large magnitudes, so
    ``1e-300`` prints as ``1e-300`` (not ``0.0``).
    """
    if isinstance(value, float) or type(value).__name__ in ("float64", "float32"):
        return repr(float(value))
    return str(value)


def _print_table(table, csv, units=None, notes=(), label=None):
    import numpy as np

    numbers = table.select_dtypes("number")
    bad = [
        name
        for name in numbers.columns
        if not np.all(np.isfinite(numbers[name].to_numpy(dtype=float)))
    ]
    if bad:
        raise InputError(
            f"the result is not finite ({', '.join(bad[:4])}): the inputs "
            "are beyond the range of double precision; rescale the moments "
            "or the spin"
        )
    table = table.copy()
    floats = table.select_dtypes("float").columns
    table[floats] = table[floats] + 0.0  # -0.0 (e.g. Omega of a steady spin) prints as 0.0
    if label is not None:
        if csv:  # as in a catalog: a cell a spreadsheet would run gets a '
            from ..cells import neutralize

            label = neutralize(label)
        else:  # one line of the table: control characters as escapes
            label = "".join(c if c.isprintable() else repr(c)[1:-1] for c in label)
        table.insert(0, "name", label)
    units = units or {}
    if csv:
        # units and frames on one comment line first, as a catalog's header
        # (read with pandas.read_csv(..., comment="#"))
        stated = [f"{name} [{units[name]}]" for name in table.columns if name in units]
        if stated:
            print(f"# units: {'; '.join(stated)}")
        table.to_csv(sys.stdout, index=False, float_format="%.17g")
        return 0
    rows = table.T
    width = max(len(str(name)) for name in rows.index)
    labels = {name: f"[{units.get(name, '-')}]" for name in rows.index}
    unit_width = max(len(label) for label in labels.values())
    for name, values in rows.iterrows():
        cells = "  ".join(f"{format_value(v):>24}" for v in values)
        print(f"{str(name):<{width}}  {labels[name]:<{unit_width}}  {cells}")
    for note in notes:
        print(note)
    return 0


def _positive_period(text):
    value = finite(text)
    if value <= 0.0:
        raise argparse.ArgumentTypeError(f"a period must be positive, got {text!r}")
    return value


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "phase",
        help="closed-form phases of one body at given spins",
        description="Energy, momentum, period and the dynamic, geometric and "
        "total phase (eqn:GeometricPhase) of one body.  With --theta or "
        "--dtheta: for |I| = 1 and a unit initial spin omega0 = (sin t cos p, "
        "sin t sin p, cos t) in the principal frame, angles in radians.  With "
        "--omega: the body's own moments and that spin, in physical units.  "
        "With --total-phase, --period-ratio or --periods: every spin that has "
        "them.",
    )
    add_body_options(parser)
    angle = parser.add_mutually_exclusive_group(required=True)
    angle.add_argument(
        "--theta",
        nargs="+",
        type=finite,
        help="polar angle(s) of omega0 from the I3 axis, radians within one "
        "turn [-2 pi, 2 pi] (beyond it refused: --theta 60 means degrees, "
        "add --degrees); folded into [0, pi/2] by the top's symmetries",
    )
    angle.add_argument(
        "--dtheta",
        nargs="+",
        type=finite,
        help="offset(s) theta - theta_crit from the separatrix, radians, not folded: "
        "in [-theta_crit, pi/2 - theta_crit], nonzero (well conditioned down to "
        "|dtheta| = 2**-1074 x 10**12 = 4.941e-312; smaller subnormal offsets are refused)",
    )
    angle.add_argument(
        "--omega",
        nargs=3,
        type=finite,
        metavar=("W1", "W2", "W3"),
        help="the initial angular velocity as a vector along the "
        "body's own axes (the order of --moments, x y z of "
        "--box, a b c of --rotational-constants whatever the order typed "
        "...), in --units; prints physical E, |L|, "
        "periods and D = M^2/(2E)",
    )
    angle.add_argument(
        "--total-phase",
        type=finite,
        metavar="X",
        help="find every spin (phi = 0, both branches) whose total "
        "phase is X (radians, or degrees with --degrees)",
    )
    angle.add_argument(
        "--period-ratio",
        type=finite,
        metavar="R",
        help="find every spin whose tumbling period ratio "
        "P_psi/P_phi is R (Pravec et al. 2005 convention)",
    )
    angle.add_argument(
        "--periods",
        nargs=2,
        type=_positive_period,
        metavar=("P_PSI", "P_PHI"),
        help="find every spin of a tumbling body with rotation period P_psi and "
        "precession period P_phi (Pravec et al. 2005), in --time-unit; prints "
        "the periods back, E_over_E0 = 2 E I3/M^2 and the branch",
    )
    parser.add_argument(
        "--time-unit",
        choices=list(TIME_UNITS),
        help="unit of --periods and of the periods printed (default s)",
    )
    parser.add_argument(
        "--phi",
        type=finite,
        default=0.0,
        help="with --theta/--dtheta: azimuth of omega0 from the I1 axis, "
        "radians within [-2 pi, 2 pi] (default 0)",
    )
    parser.add_argument(
        "--units",
        choices=list(OMEGA_UNITS),
        default="rad/s",
        help="unit of --omega (default rad/s); " + REVOLUTIONS_NOTE,
    )
    parser.add_argument(
        "--degrees",
        action="store_true",
        help="--theta, --dtheta, --phi and --total-phase in degrees "
        "(angles then within [-360, 360])",
    )
    parser.add_argument("--csv", action="store_true", help="print CSV rows instead of a table")
    parser.set_defaults(run=_cmd_phase)
