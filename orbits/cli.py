"""The ``orbits`` command line.

Every failure the user can cause (a bad argument, non-physical moments, an
unwritable path, a damaged input file, a size beyond the machine) ends with
exit code 2 and one line on stderr, never a traceback.  Ctrl-C (exit 130),
SIGTERM (143) and SIGHUP (129) end with one line and leave no partial
output: the handlers turn the signals into exceptions, so every atomic
write removes its temporary file.
"""

import argparse
import math
import re
import sys

from ._version import __version__
from .bodies import PRESETS, Body
from .errors import InputError, OrbitsError

EXIT_CHECK_FAILED = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line error message (no usage dump).

    It also reads ``-1e-300`` (and ``-inf``) as a number: argparse's own
    pattern for negative numbers has no exponent, so ``--dtheta -1e-300``
    would fail, and ``-inf`` must reach the finiteness check.
    """

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(
            r"^-((\d+\.?\d*|\.\d+)([eE][-+]?\d+)?|inf|infinity|nan)$", re.IGNORECASE
        )

    def error(self, message):
        raise InputError(f"{self.prog}: {message}")


def _finite(text):
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"not a finite number: {text!r}")
    return value


def _moment(text):
    """A moment typed in decimal: refused where the double would not be it.

    Below the smallest normal double (2.2e-308) a decimal is stored with
    fewer than 53 bits (``1e-320`` becomes ``9.99988671826831e-321``), so the
    body computed would silently differ from the one typed.
    """
    value = _finite(text)
    if 0.0 < abs(value) < sys.float_info.min:
        raise argparse.ArgumentTypeError(
            f"{text!r} is below the smallest normal double (2.2e-308) and would be "
            "stored with reduced precision; give the moments in larger units"
        )
    return value


def _positive_int(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {value}")
    return value


def add_body_options(parser, many=False):
    """The body selectors shared by the subcommands (exactly one is required)."""
    group = parser.add_argument_group(
        "body (exactly one)",
        "Moments may be in any order and any scale; they are sorted so that "
        "I1 < I2 < I3 (the paper's labels).",
    )
    exclusive = group.add_mutually_exclusive_group(required=True)
    exclusive.add_argument(
        "--moments",
        nargs=3,
        type=_moment,
        metavar=("I1", "I2", "I3"),
        help="principal moments of inertia",
    )
    exclusive.add_argument(
        "--t-handle",
        nargs=3,
        type=_finite,
        metavar=("L1", "L2", "W"),
        help="the paper's T-handle of unit mass: cross piece "
        "L1, shaft L2, square section W (eqn:IsforT)",
    )
    exclusive.add_argument(
        "--ellipsoid",
        nargs=2,
        type=_finite,
        metavar=("B", "C"),
        help="the paper's unit-norm body from ellipsoid semi-axes b, c (eqn:isforellipsoid)",
    )
    exclusive.add_argument(
        "--preset",
        choices=sorted(PRESETS),
        help="t-handle: the paper's (8, 4, 1) handle; fig6: I = (0.26, 0.55, 0.793662)",
    )
    if many:
        exclusive.add_argument(
            "--bodies",
            metavar="FILE.csv",
            help="many bodies: a CSV with columns I1, I2, I3 and optionally name",
        )
        group.add_argument(
            "--skip-invalid",
            action="store_true",
            help="with --bodies: skip invalid rows (listed on stderr "
            "and in the output) instead of stopping",
        )
    group.add_argument(
        "--name", help="name of the single body (catalog and figure labels); not with --bodies"
    )
    _add_real_body_options(group, exclusive)
    return group


# Body selectors of add_body_options (argparse dest names), for commands
# whose body is optional.
BODY_SELECTORS = (
    "moments",
    "t_handle",
    "ellipsoid",
    "preset",
    "box",
    "cylinder",
    "point_masses",
    "mesh",
    "rotational_constants",
)


def _add_real_body_options(group, exclusive):
    """Real bodies in real units (kg, m, kg m^2) and their modifiers."""
    exclusive.add_argument(
        "--box",
        nargs=3,
        type=_finite,
        metavar=("A", "B", "C"),
        help="uniform solid box with edges A, B, C along x, y, z (with --mass; Body.box)",
    )
    exclusive.add_argument(
        "--cylinder",
        nargs="+",
        type=_finite,
        metavar="R L [RY]",
        help="uniform solid cylinder along z: radius R (along x), "
        "length L, optional second semi-axis RY of an "
        "elliptic section (a circular one is a symmetric "
        "top); with --mass (Body.cylinder)",
    )
    exclusive.add_argument(
        "--point-masses",
        metavar="FILE.csv",
        help="rigid point masses: a CSV with columns mass, x, y, "
        "z, about the centre of mass (Body.from_point_masses)",
    )
    exclusive.add_argument(
        "--mesh",
        metavar="FILE",
        help="uniform solid bounded by a closed STL/OBJ mesh, "
        "with --density (Body.from_mesh; needs orbits[mesh])",
    )
    exclusive.add_argument(
        "--rotational-constants",
        nargs=3,
        type=_finite,
        metavar=("A", "B", "C"),
        help="a molecule from its rotational constants, in --unit "
        "(Body.from_rotational_constants)",
    )
    group.add_argument(
        "--mass", type=_finite, default=1.0, help="mass for --box and --cylinder (default 1)"
    )
    group.add_argument(
        "--density", type=_finite, default=1.0, help="density for --mesh (default 1)"
    )
    group.add_argument(
        "--unit",
        choices=["cm-1", "MHz", "GHz"],
        default="cm-1",
        help="unit of --rotational-constants (default cm-1)",
    )
    group.add_argument(
        "--defect",
        choices=["error", "flatten"],
        default="error",
        help="a positive inertial defect of --rotational-constants: "
        "refuse (default) or put the body on the flat edge",
    )


def _point_masses_from_csv(path):
    import numpy as np
    import pandas as pd

    try:
        from .atomic import csv_float_options

        table = pd.read_csv(path, comment="#", **csv_float_options())
    except (OSError, ValueError) as error:
        raise InputError(f"cannot read point masses from {path}: {error}") from None
    missing = {"mass", "x", "y", "z"} - set(table.columns)
    if missing:
        raise InputError(
            f"{path}: point-mass CSV needs columns mass, x, y, z; "
            f"missing {', '.join(sorted(missing))}"
        )
    try:
        values = table[["mass", "x", "y", "z"]].to_numpy(dtype=float)
    except ValueError:
        raise InputError(f"{path}: mass, x, y, z must be numbers") from None
    return values[:, 0], np.ascontiguousarray(values[:, 1:])


def _real_body_from_args(args):
    """The body of a real-body option, or None if none was given."""
    name = getattr(args, "name", None)
    if getattr(args, "box", None) is not None:
        return Body.box(
            *args.box, args.mass, name=name or "box({:g}, {:g}, {:g})".format(*args.box)
        )
    if getattr(args, "cylinder", None) is not None:
        if len(args.cylinder) not in (2, 3):
            raise InputError("--cylinder takes R L or R L RY")
        radius, length, *rest = args.cylinder
        return Body.cylinder(
            radius,
            length,
            args.mass,
            radius_y=rest[0] if rest else None,
            name=name or "cylinder(" + ", ".join(f"{v:g}" for v in args.cylinder) + ")",
        )
    if getattr(args, "point_masses", None) is not None:
        masses, positions = _point_masses_from_csv(args.point_masses)
        return Body.from_point_masses(masses, positions, name=name or args.point_masses)
    if getattr(args, "mesh", None) is not None:
        return Body.from_mesh(args.mesh, density=args.density, name=name or args.mesh)
    if getattr(args, "rotational_constants", None) is not None:
        import warnings

        from .bodies import InertialDefectWarning

        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", InertialDefectWarning)
            body = Body.from_rotational_constants(
                *args.rotational_constants,
                unit=args.unit,
                defect=args.defect,
                name=name
                or "rotational-constants({:g}, {:g}, {:g})".format(*args.rotational_constants),
            )
        for warning in caught:
            print(f"orbits: warning: {warning.message}", file=sys.stderr)
        return body
    return None


def body_from_args(args):
    """The :class:`Body` selected by :func:`add_body_options` options."""
    try:
        body = _real_body_from_args(args)
        if body is None:
            body = _named_body_from_args(args)
    except (OverflowError, FloatingPointError, ZeroDivisionError):
        raise InputError(
            "the body's moments overflow a double: use smaller lengths or moments"
        ) from None
    name = getattr(args, "name", None)
    if name is not None:
        if not name.strip():
            raise InputError("--name must not be empty")
        body.name = name
    return body


def _named_body_from_args(args):
    if args.moments is not None:
        return Body(args.moments, name="moments({:g}, {:g}, {:g})".format(*args.moments))
    if args.t_handle is not None:
        return Body.t_handle(
            *args.t_handle, name="t-handle({:g}, {:g}, {:g})".format(*args.t_handle)
        )
    if args.ellipsoid is not None:
        return Body.ellipsoid(
            *args.ellipsoid, name="ellipsoid({:g}, {:g})".format(*args.ellipsoid)
        )
    return Body.preset(args.preset)


# ---------------------------------------------------------------- phase
def _cmd_phase(args):
    import numpy as np

    # numpy's overflow warnings would add lines to stderr; a non-finite result
    # is refused by _print_table instead (never a silent inf or nan)
    with np.errstate(all="ignore"):
        return _phase_table(args)


def _phase_table(args):
    body = body_from_args(args)
    if args.omega is not None:
        return _print_table(_omega_table(body, args), args.csv)
    if args.total_phase is not None or args.period_ratio is not None:
        from . import tumbling

        if args.total_phase is not None:
            table = tumbling.spins_with_total_phase(body, _angle(args.total_phase, args))
        else:
            table = tumbling.spins_with_period_ratio(body, args.period_ratio)
        return _print_table(table, args.csv)
    from .phases import phases

    theta = None if args.theta is None else [_angle(v, args) for v in args.theta]
    dtheta = None if args.dtheta is None else [_angle(v, args) for v in args.dtheta]
    table = phases(body, theta, _angle(args.phi, args), dtheta=dtheta)
    return _print_table(table, args.csv)


# angular-velocity units -> rad/s
OMEGA_UNITS = {
    "rad/s": 1.0,
    "deg/s": math.pi / 180.0,
    "rpm": 2.0 * math.pi / 60.0,
    "Hz": 2.0 * math.pi,
}


def _angle(value, args):
    """An angle of the command line in radians (``--degrees`` converts)."""
    return math.radians(value) if getattr(args, "degrees", False) else value


def _omega_table(body, args):
    """One row for a spin given as a vector: physical outputs and D = M^2/(2E).

    omega is given along the caller's axes (the order of --moments, x y z of
    --box, ...) in --units, turned to the principal frame with Body.frame.
    With moments in kg m^2 the energy is in J, |L| in J s and the periods
    in s; ``D_normalised = D/|I|`` is the ``D`` of the orbit's catalog row.
    """
    import numpy as np
    import pandas as pd

    from .motion import Motion
    from .phases import spin_phases

    omega = np.array(args.omega) * OMEGA_UNITS[args.units]
    motion = Motion.from_omega(body, omega, axes="body")
    principal = motion.omega0
    periods = motion.tumbling_periods()
    total = motion.total_phase()
    dynamic = 2.0 * motion.energy * motion.period / motion.momentum
    # Omega in its closed form: dynamic - total cancels near the sphere
    geometric = float(spin_phases(body, principal)["geometric_phase"].iloc[0])
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
            "D_normalised": [motion.D / float(np.linalg.norm(body.moments))],
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


def _print_table(table, csv):
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
            "are beyond the range of double precision (e.g. moments below "
            "1e-150 or above 1e150, or a huge --omega); rescale them"
        )
    if csv:
        table.to_csv(sys.stdout, index=False, float_format="%.17g")
        return 0
    rows = table.T
    width = max(len(str(name)) for name in rows.index)
    for name, values in rows.iterrows():
        cells = "  ".join(f"{format_value(v):>24}" for v in values)
        print(f"{str(name):<{width}}  {cells}")
    return 0


def _add_phase(subparsers):
    parser = subparsers.add_parser(
        "phase",
        help="closed-form phases of one body at given spins",
        description="Energy, momentum, period and the dynamic, geometric and "
        "total phase (eqn:GeometricPhase) for |I| = 1 and a unit "
        "initial spin omega0 = (sin t cos p, sin t sin p, cos t) in "
        "the principal frame.  Angles in radians.",
    )
    add_body_options(parser)
    angle = parser.add_mutually_exclusive_group(required=True)
    angle.add_argument(
        "--theta",
        nargs="+",
        type=_finite,
        help="polar angle(s) of omega0 from the I3 axis (any value: folded "
        "into [0, pi/2] by the top's symmetries)",
    )
    angle.add_argument(
        "--dtheta",
        nargs="+",
        type=_finite,
        help="offset(s) theta - theta_crit from the separatrix (well conditioned down to 1e-300)",
    )
    angle.add_argument(
        "--omega",
        nargs=3,
        type=_finite,
        metavar=("W1", "W2", "W3"),
        help="the initial angular velocity as a vector along the "
        "body's own axes (the order of --moments, x y z of "
        "--box ...), in --units; prints physical E, |L|, "
        "periods and D = M^2/(2E)",
    )
    angle.add_argument(
        "--total-phase",
        type=_finite,
        metavar="X",
        help="find every spin (phi = 0, both branches) whose total "
        "phase is X (radians, or degrees with --degrees)",
    )
    angle.add_argument(
        "--period-ratio",
        type=_finite,
        metavar="R",
        help="find every spin whose tumbling period ratio "
        "P_psi/P_phi is R (Pravec et al. 2005 convention)",
    )
    parser.add_argument(
        "--phi", type=_finite, default=0.0, help="azimuth of omega0 from the I1 axis (default 0)"
    )
    parser.add_argument(
        "--units",
        choices=list(OMEGA_UNITS),
        default="rad/s",
        help="unit of --omega (default rad/s)",
    )
    parser.add_argument(
        "--degrees",
        action="store_true",
        help="--theta, --dtheta, --phi and --total-phase in degrees",
    )
    parser.add_argument("--csv", action="store_true", help="print CSV rows instead of a table")
    parser.set_defaults(run=_cmd_phase)


# ---------------------------------------------------------------- catalog
def command_line(argv):
    """The command as typed, for the provenance header of output files."""
    import shlex

    words = sys.argv[1:] if argv is None else list(argv)
    return "orbits " + " ".join(shlex.quote(word) for word in words)


def bodies_file_from_args(args):
    """The strictly read ``--bodies`` file; skipped rows reported on stderr."""
    from .catalog import read_bodies_csv

    if getattr(args, "name", None) is not None:
        raise InputError("--name names a single body; a --bodies file has a name column")
    import os

    try:
        size = os.path.getsize(args.bodies)
    except OSError:
        size = 0
    if size > 20 << 20 and sys.stderr.isatty():
        print(
            f"orbits: reading {args.bodies} ({size / 2**20:.0f} MiB)...",
            file=sys.stderr,
            flush=True,
        )
    table = read_bodies_csv(args.bodies, skip_invalid=args.skip_invalid)
    for _, message in table.skipped[:20]:
        print(f"orbits: warning: skipped {message}", file=sys.stderr)
    if len(table.skipped) > 20:
        print(
            f"orbits: warning: skipped {len(table.skipped) - 20} more invalid rows",
            file=sys.stderr,
        )
    return table


def bodies_from_args(args):
    """The bodies selected by the body options and header notes (skipped rows)."""
    if getattr(args, "bodies", None) is not None:
        table = bodies_file_from_args(args)
        return table.bodies(), table.skipped_note()
    if getattr(args, "skip_invalid", False):
        raise InputError("--skip-invalid applies to a --bodies file")
    return [body_from_args(args)], []


def _check_out(path):
    """``--out`` for a file: '-' is standard output; else it must be writable."""
    if path == "-":
        return
    from .atomic import ensure_writable

    ensure_writable(path)


def announce(command, seconds, memory):
    """One stderr line before a step estimated to take more than 2 s."""
    if seconds > 2:
        from .catalog import _bytes, _duration

        print(
            f"orbits {command}: estimated {_duration(seconds)}, up to {_bytes(memory)}"
            " of memory; working...",
            file=sys.stderr,
            flush=True,
        )


def _cmd_catalog(args):
    import time
    import warnings

    from .catalog import CLOSURE_TOLERANCE, catalog, check_search_bounds, write_catalog
    from .search import UnresolvedOrbitsWarning

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


def _add_catalog(subparsers):
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
        "--n-max", type=_positive_int, required=True, help="largest multiple n (or p/q) of 2 pi"
    )
    parser.add_argument(
        "--q-max",
        type=_positive_int,
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


# ---------------------------------------------------------------- figures
def _output_directory(path):
    from pathlib import Path

    directory = Path(path)
    if directory.exists() and not directory.is_dir():
        raise InputError(f"output path {directory} exists and is not a directory")
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise InputError(f"cannot create output directory {directory}: {error.strerror}") from None
    if not directory.is_dir():
        raise InputError(f"output path {directory} is not a directory")
    from .atomic import ensure_writable

    ensure_writable(directory / "probe")
    return directory


def _cmd_figures(args):
    import time

    from . import figures

    selectors = [
        args.paper,
        bool(args.survey),
        any(getattr(args, name) is not None for name in BODY_SELECTORS),
    ]
    if sum(selectors) != 1:
        raise InputError(
            "orbits figures: give exactly one of a body (--moments, "
            "--t-handle, --ellipsoid, --preset), --paper or --survey DIR"
        )
    # every input is checked before the output directory is created
    start = time.perf_counter()
    if args.paper or args.survey:
        grid = None
        if args.survey:
            from .survey import survey_grid

            grid = survey_grid(args.survey)
        out = _output_directory(args.out)
        names = ["fig2"] if args.survey else list(figures.PAPER_FIGURES)
        with progress_bar(len(names), "figures", unit="figure") as bar:
            written = figures.paper_figures(
                out, formats=args.formats, survey_grid=grid, progress=bar.update, names=names
            )
    else:
        if args.n_max is None:
            raise InputError("orbits figures: --n-max is required with a body")
        body = body_from_args(args)
        from .catalog import check_search_bounds
        from .search import closed_orbits

        check_search_bounds(args.n_max, args.q_max, 1, "the figures' search")
        orbits_table = closed_orbits(body, n_max=args.n_max, q_max=args.q_max)
        out = _output_directory(args.out)
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
        f"orbits figures: {len(written)} files written to {out} in "
        f"{time.perf_counter() - start:.1f} s",
        file=sys.stderr,
    )
    return 0


def _add_figures(subparsers):
    parser = subparsers.add_parser(
        "figures",
        help="draw closed herpolhodes, or the paper's six figures",
        description="With a body: one figure per closed orbit (each n, both "
        "branches, p/q orbits with --q-max; a p/q orbit is drawn "
        "over q periods) in the invariable plane, plus a contact "
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
        "--survey", metavar="DIR", help="draw Fig. 2 from the survey in DIR (orbits survey)"
    )
    parser.add_argument(
        "--n-max", type=_positive_int, help="with a body: largest multiple n (or p/q) of 2 pi"
    )
    parser.add_argument(
        "--q-max",
        type=_positive_int,
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


# ---------------------------------------------------------------- animate
def _cmd_animate(args):
    import time

    from . import animate

    body = body_from_args(args)
    spins = [
        args.theta is not None,
        args.dtheta is not None,
        args.n is not None,
        args.p is not None,
        args.flip is not None,
    ]
    if sum(spins) != 1:
        raise InputError(
            "orbits animate: give exactly one spin: --theta, --dtheta, --n, --p/--q or --flip"
        )
    if args.q is not None and args.p is None:
        raise InputError("orbits animate: --q needs --p")
    solid = args.solid
    if solid == "auto" and args.t_handle is not None:
        solid = ("t-handle",) + tuple(args.t_handle)
    start = time.perf_counter()
    if args.flip is not None:
        source = animate.flip_motion(body, offset=args.flip)
    elif args.n is not None or args.p is not None:
        source = animate.orbit_row(body, n=args.n, p=args.p, q=args.q or 1, branch=args.branch)
    else:
        from .motion import Motion

        source = Motion.from_spin(body, args.theta, dtheta=args.dtheta, phi=args.phi)
    title = None
    if args.flip is not None:
        title = (
            f"{body.name or 'body'}: the Dzhanibekov (tennis-racket) flip, spin "
            f"{args.flip:g} rad from the intermediate axis $I_2$, "
            f"T = {source.period:.4g} s"
        )
    drawn = animate.poinsot_animation(
        source,
        periods=args.periods,
        frames=args.frames,
        fps=args.fps,
        dpi=args.dpi,
        solid=solid,
        out=args.out,
        title=title,
        body=body if args.n is not None or args.p is not None else None,
    )
    print(
        f"orbits animate: {len(drawn.times)} frames over "
        f"{drawn.times[-1] / drawn.motion.period:.4g} periods written to {args.out} "
        f"in {time.perf_counter() - start:.1f} s",
        file=sys.stderr,
    )
    return 0


def _flip_offset(text):
    value = _finite(text)
    if not 0.0 < value < 0.25 * math.pi:
        raise argparse.ArgumentTypeError(f"must be in (0, pi/4), got {value}")
    return value


def _add_animate(subparsers):
    parser = subparsers.add_parser(
        "animate",
        help="animate Poinsot's construction for a body and spin (GIF/MP4)",
        description="Poinsot's construction in motion: in the space frame (L "
        "fixed, along z) the body as a solid, omega, L, the "
        "invariable plane, the inertia ellipsoid x.I.x = 1 rolling "
        "on it and the herpolhode being traced; in the body frame "
        "the polhode being traced.  The spin is given by its polar "
        "angle (--theta or --dtheta, with --phi), by a closed orbit "
        "of the catalog (--n, or --p and --q; --branch when both "
        "branches have it; drawn over q periods, so the last frame "
        "is the first), or --flip (a spin near the intermediate "
        "axis: the Dzhanibekov flip).  Written atomically and "
        "deterministically: .gif (Pillow) or .mp4 (needs the "
        "optional extra 'animation', imageio-ffmpeg).",
    )
    add_body_options(parser)
    spin = parser.add_argument_group("spin (exactly one)")
    spin.add_argument("--theta", type=_finite, help="polar angle of omega0 from I3 (rad)")
    spin.add_argument("--dtheta", type=_finite, help="offset theta - theta_crit (rad)")
    spin.add_argument("--n", type=_positive_int, help="the closed orbit Delta alpha = 2 pi n")
    spin.add_argument("--p", type=_positive_int, help="the closed orbit 2 pi p/q (with --q)")
    spin.add_argument("--q", type=_positive_int, help="see --p")
    spin.add_argument(
        "--flip",
        type=_flip_offset,
        nargs="?",
        const=0.05,
        metavar="OFFSET",
        help="spin near the intermediate axis, tipped by OFFSET rad "
        "(default 0.05): the tennis-racket flip",
    )
    parser.add_argument(
        "--phi",
        type=_finite,
        default=0.0,
        help="azimuth of omega0 from I1 with --theta/--dtheta (rad)",
    )
    parser.add_argument(
        "--branch",
        choices=["SAM", "LAM"],
        help="with --n or --p: the branch, when both have the orbit",
    )
    parser.add_argument(
        "--periods", type=_finite, help="duration in periods T (default q for an orbit, else 1)"
    )
    parser.add_argument(
        "--frames", type=_positive_int, default=120, help="number of frames (default 120)"
    )
    parser.add_argument(
        "--fps", type=_positive_int, default=20, help="frames per second (default 20)"
    )
    parser.add_argument(
        "--dpi",
        type=_positive_int,
        default=80,
        help="pixels per inch of the 9 x 4 in frames (default 80)",
    )
    parser.add_argument(
        "--solid",
        choices=["auto", "ellipsoid"],
        default="auto",
        help="the solid drawn: auto (the body's shape when known, "
        "else its equivalent ellipsoid) or ellipsoid",
    )
    parser.add_argument(
        "--out",
        required=True,
        metavar="FILE.gif|FILE.mp4",
        help="output file; the suffix picks the format",
    )
    parser.set_defaults(run=_cmd_animate)


# ---------------------------------------------------------------- survey
def _cmd_survey(args):
    import json
    import time

    from .survey import Survey, check_survey

    if args.check:
        return _check_survey_directory(args, check_survey)
    if args.out is None:
        raise InputError("orbits survey: --out DIR is required (or --check DIR)")
    if args.n_max is None:
        raise InputError("orbits survey: the following arguments are required: --n-max")
    if (args.resolution is None) == (args.bodies is None):
        raise InputError("orbits survey: give exactly one of --resolution N and --bodies FILE")
    if args.skip_invalid and args.bodies is None:
        raise InputError("--skip-invalid applies to a --bodies file")
    if args.scheduler is not None and not args.scheduler.strip():
        raise InputError("--scheduler is empty; give tcp://HOST:PORT")
    options = dict(q_max=args.q_max, fmt=args.format, chunk=args.chunk)
    from .survey import survey_estimate

    announced = False
    if args.resolution is not None:
        # say it before building the grid, which itself takes seconds when large
        from .survey import _GRID_INSIDE, check_resolution, check_survey_bounds

        check_resolution(args.resolution)
        count = max(1, int(_GRID_INSIDE * args.resolution**2))
        check_survey_bounds(count, args.n_max, args.q_max, args.chunk)
        announce("survey", *reversed(survey_estimate(count, args.n_max, args.q_max, args.chunk)))
        announced = True
        survey = Survey.grid(args.out, args.resolution, args.n_max, **options)
    else:
        table = bodies_file_from_args(args)
        survey = Survey(
            args.out,
            table.moments,
            {"file": str(args.bodies)},
            args.n_max,
            names=table.names,
            skipped=[message for _, message in table.skipped],
            **options,
        )
    memory, seconds = survey_estimate(
        survey.moments.shape[0], survey.n_max, survey.q_max, survey.chunk
    )
    total = survey.moments.shape[0]
    start = time.perf_counter()
    with progress_bar(total, "survey", unit="body") as bar:

        def notify(message):
            bar.write(f"orbits survey: {message}", file=sys.stderr)

        def status(message):
            if sys.stderr.isatty():
                notify(message)

        if not announced:
            announce("survey", seconds, memory)
        report = survey.run(
            scheduler=args.scheduler, progress=bar.update, notify=notify, status=status
        )
    pending = sum(len(survey.chunk_moments(k)) for k in survey.last_todo)
    elapsed = time.perf_counter() - start
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        conjecture = report["conjecture_minimum_at_the_ends"]
        rate = f", {pending / elapsed:.0f} bodies/s" if pending else ""
        print(
            f"orbits survey: {total} bodies ({pending} computed now in "
            f"{elapsed:.1f} s{rate}), {report['orbits']} closed orbits with "
            f"n <= {args.n_max}, in {args.out}"
        )
        low, high = report["min_total_phase_range"]
        print(
            f"minimum total phase: {low / (2 * math.pi):.6f} to "
            f"{high / (2 * math.pi):.6f} x 2 pi; bodies with a 2 pi orbit: "
            f"{report['bodies_with_a_two_pi_orbit']}"
        )
        if conjecture["held_on_every_body"]:
            print("conjecture (the minimum lies at theta -> 0 or pi/2): held on every body")
        else:
            print(
                f"conjecture (the minimum lies at theta -> 0 or pi/2): FAILED on "
                f"{len(conjecture['counterexamples'])} bodies:"
            )
            for row in conjecture["counterexamples"]:
                print(
                    f"  body {row['body']}: I = ({row['I1']:.6f}, {row['I2']:.6f}, "
                    f"{row['I3']:.6f}), minimum {row['min_total_phase']:.9f} at "
                    f"theta = {row['min_theta']:.9f}"
                )
    return 0


def _check_survey_directory(args, check_survey):
    """``orbits survey --check DIR``: verify every part, compute nothing."""
    import json

    given = [
        name
        for name in ("resolution", "bodies", "n_max", "scheduler", "out")
        if getattr(args, name) is not None
    ]
    if given:
        raise InputError(
            f"orbits survey --check takes only the directory (and --json), "
            f"not --{given[0].replace('_', '-')}"
        )
    status = check_survey(args.check)
    if args.json:
        print(json.dumps(status, indent=2))
    else:
        verdict = "complete, every part verified" if status["complete"] else "NOT complete"
        print(
            f"orbits survey --check {args.check}: {status['verified']} of "
            f"{status['chunks']} chunk(s) verified; {verdict}"
        )
        for line in status["damaged"]:
            print(f"  damaged {line}")
        if status["missing"]:
            print(
                f"  missing: {', '.join(status['missing'][:10])}"
                + (" ..." if len(status["missing"]) > 10 else "")
            )
    return 0 if status["complete"] else EXIT_CHECK_FAILED


def _add_survey(subparsers):
    parser = subparsers.add_parser(
        "survey",
        help="minimum phases and closed orbits over many bodies",
        description="Runs the closed-orbit search over the region of physical "
        "asymmetric bodies (the paper's I1-I2 plane, |I| = 1) or an "
        "explicit list, and writes DIR with manifest.json, the "
        "tables bodies/ and orbits/ (partitioned, one file per "
        "chunk) and report.json (the minimum-at-the-ends "
        "conjecture, bodies with a 2 pi orbit, ...).  Each chunk is "
        "written atomically and recorded in the manifest's ledger "
        "(SHA-256 per part); running the same command again checks "
        "every part and computes only the missing or damaged ones; "
        "other parameters in the same DIR are refused; one run at a "
        "time holds DIR (a lock).",
    )
    source = parser.add_mutually_exclusive_group()
    source.add_argument(
        "--resolution",
        type=_positive_int,
        metavar="N",
        help="an N x N grid over the bounding box of the region, keeping the points inside it",
    )
    source.add_argument(
        "--bodies", metavar="FILE.csv", help="a CSV with columns I1, I2, I3 (optionally name)"
    )
    source.add_argument(
        "--check",
        metavar="DIR",
        help="verify the survey in DIR against its ledger (SHA-256 of "
        "every part) without computing; exit 1 if it is damaged "
        "or incomplete",
    )
    parser.add_argument(
        "--skip-invalid",
        action="store_true",
        help="with --bodies: skip invalid rows (listed on stderr and "
        "in the manifest) instead of stopping",
    )
    parser.add_argument(
        "--n-max", type=_positive_int, help="largest multiple n (or p/q) of 2 pi searched per body"
    )
    parser.add_argument(
        "--q-max", type=_positive_int, default=1, help="also p/q orbits with q up to Q (default 1)"
    )
    parser.add_argument(
        "--format",
        choices=["csv", "parquet"],
        default="parquet",
        help="table format (default parquet: typed, exact, compact; csv is exact too)",
    )
    parser.add_argument(
        "--chunk", type=_positive_int, default=20_000, help="bodies per chunk (default 20000)"
    )
    parser.add_argument(
        "--scheduler",
        metavar="tcp://HOST:PORT",
        help="run the chunks on this dask.distributed scheduler "
        "(needs orbits[distributed]); default: in-process on "
        "all cores",
    )
    parser.add_argument("--json", action="store_true", help="print the report as JSON")
    parser.add_argument("--out", metavar="DIR", help="survey directory")
    parser.set_defaults(run=_cmd_survey)


# ---------------------------------------------------------------- verify


def progress_bar(total, description, enabled=None, unit="orbit"):
    """A tqdm bar on a terminal (stderr), a no-op otherwise."""
    from tqdm import tqdm

    if enabled is None:
        enabled = sys.stderr.isatty()
    return tqdm(
        total=total,
        desc=description,
        unit=unit,
        disable=not enabled,
        file=sys.stderr,
        dynamic_ncols=True,
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
        from .atomic import ensure_writable

        ensure_writable(args.table)
    one = any(getattr(args, name, None) is not None for name in BODY_SELECTORS)
    body = body_from_args(args) if one else None
    n_bodies = 1 if one else args.bodies
    total = n_bodies * args.angles
    from .catalog import _bytes, memory_budget

    memory = total * _VERIFY_BYTES_PER_CONDITION
    if memory > memory_budget():
        raise InputError(
            f"verify with {n_bodies} bodies x {args.angles} angles = "
            f"{total} initial conditions would need about {_bytes(memory)} "
            f"of memory, more than the {_bytes(memory_budget())} allowed "
            "(half of this machine's)"
        )
    announce("verify", total * _VERIFY_SECONDS_PER_CONDITION, memory)
    # imports SciPy (seconds on a cold start): after the estimate
    from .checks import verify, verify_body

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
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        what = f"body {summary['body']}" if one else f"{args.bodies} bodies"
        print(
            f"orbits verify: {summary['initial_conditions']} initial conditions "
            f"({what} x {args.angles} angles), tolerance "
            f"{args.tolerance:g} rad"
        )
        print(f"{'check':<16} {'max |discrepancy| (rad)':>24}  result")
        for name, label in (
            ("montgomery", "(b) Montgomery"),
            ("ode_rotation", "(a) ODE rotation"),
            ("exact_motion", "(c) exact motion"),
        ):
            value = summary["checks"][name]["max_abs_error"]
            verdict = "ok" if value <= args.tolerance else "FAIL"
            print(f"{label:<16} {value:>24.3e}  {verdict}")
        print(f"ODE period vs eqn:TK: max |dT| = {summary['ode_period_max_abs_error']:.3e}")
    if args.table:
        from .atomic import write_csv_atomic

        write_csv_atomic(report.table, args.table)
    return 0 if report.passed else EXIT_CHECK_FAILED


def _add_verify(subparsers):
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
        "--bodies", type=_positive_int, default=293, help="number of bodies (default 293)"
    )
    group = parser.add_argument_group(
        "your own body (optional)",
        "Instead of the region sample, check one body given by any of the body "
        "options of 'orbits phase' (e.g. --moments, --box ... --mass M, --mesh F)",
    )
    # the body options without --bodies (which is the count here)
    sub = _Parser(add_help=False)
    add_body_options(sub)
    for action in sub._actions:
        if action.dest in BODY_SELECTORS or action.dest in (
            "mass",
            "density",
            "unit",
            "defect",
            "name",
        ):
            action.required = False
            group._add_action(action)
    parser.add_argument(
        "--angles",
        type=_positive_int,
        default=22,
        help="number of angles theta_j = (j + 1/2) pi / (2 K) (default 22)",
    )
    parser.add_argument(
        "--tolerance",
        type=_finite,
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


# ---------------------------------------------------------------- bench
def _cmd_bench(args):
    from . import bench

    unknown = set(args.only or ()) - set(bench.BENCHMARKS)
    if unknown:
        raise InputError(
            f"unknown benchmark(s): {', '.join(sorted(unknown))}; "
            f"known: {', '.join(bench.BENCHMARKS)}"
        )
    report = bench.run(args.only, quick=args.quick, load=not args.no_load_check)
    print(bench.to_json(report) if args.json else bench.format_table(report))
    return 0


def _add_bench(subparsers):
    parser = subparsers.add_parser(
        "bench",
        help="time our kernels against SciPy in the same process",
        description="Times each task with our compiled kernels and with the "
        "obvious SciPy alternative, best of several runs after a "
        "warm-up, and prints the ratio.",
    )
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.add_argument(
        "--only",
        nargs="+",
        metavar="NAME",
        help="run only these benchmarks (names as in the table; a wrong name lists them)",
    )
    parser.add_argument(
        "--quick",
        action="store_true",
        help="smaller problem sizes (a smoke test, not for the README)",
    )
    parser.add_argument(
        "--no-load-check",
        action="store_true",
        help="skip the under-load check (by default each task is "
        "timed again beside a CPU-bound process and must hold "
        "within 2x)",
    )
    parser.set_defaults(run=_cmd_bench)


def build_parser():
    parser = _Parser(
        prog="orbits",
        description="Geometric phase, exact motion and closed orbits of the "
        "force-free asymmetric top (Mecholsky 2019).",
    )
    parser.add_argument("--version", action="version", version=f"orbits {__version__}")
    parser.add_argument(
        "--threads",
        type=_positive_int,
        metavar="N",
        help="threads for large inputs (default: all of numba's; small inputs always run on one)",
    )
    subparsers = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    _add_phase(subparsers)
    _add_catalog(subparsers)
    _add_figures(subparsers)
    _add_survey(subparsers)
    _add_verify(subparsers)
    _add_bench(subparsers)
    _add_animate(subparsers)
    return parser


def _raise_terminated(signum, frame):
    from .atomic import Terminated

    raise Terminated(signum)


def _install_signal_handlers():
    """SIGTERM and SIGHUP raise :class:`~orbits.atomic.Terminated` (main thread only)."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        return {}
    previous = {}
    for name in ("SIGTERM", "SIGHUP"):
        number = getattr(signal, name, None)
        if number is not None:
            previous[number] = signal.signal(number, _raise_terminated)
    return previous


def announce_compilation(stream=None):
    """On a terminal, say once that the first run compiles the kernels.

    numba caches compiled kernels (``cache=True``) next to their source, in
    ``orbits/core/__pycache__`` (or under ``NUMBA_CACHE_DIR``); when no index
    file is there yet the first call compiles them, which takes seconds.
    Returns True when the line was printed.
    """
    import os
    from pathlib import Path

    stream = sys.stderr if stream is None else stream
    if not stream.isatty():
        return False
    core = Path(__file__).resolve().parent / "core"
    # numba uses NUMBA_CACHE_DIR instead of __pycache__ when it is set
    if os.environ.get("NUMBA_CACHE_DIR"):
        places = [Path(os.environ["NUMBA_CACHE_DIR"])]
    else:
        places = [core / "__pycache__"]
    if any(next(place.rglob("*.nbi"), None) is not None for place in places if place.is_dir()):
        return False
    print(
        "orbits: first run: compiling the numerical kernels (cached for later runs)...",
        file=stream,
        flush=True,
    )
    return True


def main(argv=None):
    """Entry point of the ``orbits`` console script; returns the exit code."""
    import signal

    from .atomic import Terminated

    previous = _install_signal_handlers()
    try:
        args = build_parser().parse_args(argv)
        args.argv = argv
        if args.threads is not None:
            from .threads import set_num_threads

            set_num_threads(args.threads)
        announce_compilation()
        return args.run(args)
    except KeyboardInterrupt:
        print("orbits: interrupted; no partial output was written", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Terminated as stop:
        name = signal.Signals(stop.signum).name
        print(f"orbits: stopped by {name}; no partial output was written", file=sys.stderr)
        return 128 + stop.signum
    except OrbitsError as error:
        print(f"orbits: error: {' '.join(str(error).split())}", file=sys.stderr)
        return EXIT_USAGE
    except MemoryError:
        print(
            "orbits: error: out of memory; use smaller sizes (--n-max, --q-max, "
            "--resolution, --chunk, --bodies)",
            file=sys.stderr,
        )
        return EXIT_USAGE
    except BrokenPipeError:
        # the reader (e.g. `head`) closed the pipe: not an error of ours
        sys.stdout = None
        return 0
    except OSError as error:
        print(
            f"orbits: error: {error.strerror or error}: {error.filename or ''}".rstrip(": "),
            file=sys.stderr,
        )
        return EXIT_USAGE
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)


if __name__ == "__main__":
    sys.exit(main())
