"""What the subcommands share: the parser, number types, body options, progress.

:class:`Parser` (argparse with one-line errors and exponent-aware negative
numbers), the argument types :func:`finite`, :func:`moment` and
:func:`positive_int`, the body selectors (:func:`add_body_options`,
:func:`body_from_args`, :func:`bodies_from_args` for ``--bodies`` files),
the provenance line :func:`command_line`, the estimate line
:func:`announce`, the :func:`progress_bar` and the exit codes.
"""

import argparse
import math
import re
import sys

from .._args import below_normal, below_normal_message, read_as_zero
from ..bodies import PRESETS, Body
from ..cells import numbers_label
from ..errors import InputError
from ..limits import format_bytes, format_duration

# exit codes (besides 0, and 128 + N for signal N)
EXIT_CHECK_FAILED = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130


class _Formatter(argparse.HelpFormatter):
    """argparse's help, with an option of 2 or 3 numbers shown as such.

    ``nargs="+"`` (argparse has no "2 or 3") would read ``--cylinder R L
    [RY] [R L [RY] ...]``, as if groups repeated; an action with ``shown``
    set is printed with that text instead.
    """

    def _format_args(self, action, default_metavar):
        shown = getattr(action, "shown", None)
        return shown if shown is not None else super()._format_args(action, default_metavar)


class Parser(argparse.ArgumentParser):
    """argparse with a one-line error message (no usage dump).

    It also reads ``-1e-300`` (and ``-inf``) as a number: argparse's own
    pattern for negative numbers has no exponent, so ``--dtheta -1e-300``
    would fail, and ``-inf`` must reach the finiteness check.
    """

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", _Formatter)
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(
            r"^-((\d+\.?\d*|\.\d+)([eE][-+]?\d+)?|inf|infinity|nan)$", re.IGNORECASE
        )

    def _print_message(self, message, file=None):
        # argparse drops a write that fails, so `orbits --help >/dev/full`
        # printed nothing and exited 0; written and flushed here, the error
        # reaches orbits.cli.main (exit 2; a closed pipe, as with `| head`, 0)
        if message:
            file = file or sys.stderr
            file.write(message)
            file.flush()

    def error(self, message):
        # the top-level parser's name is the "orbits: error:" prefix already;
        # a subcommand's ("orbits phase") says where the fault is
        if " " not in self.prog:
            raise InputError(message)
        raise InputError(f"{self.prog}: {message}")

    def parse_known_args(self, args=None, namespace=None):
        """Parse as argparse does, and record in ``namespace.given`` what was typed.

        argparse fills every option's default in, so ``--mass 1`` and no
        ``--mass`` look the same; the defaults are therefore swapped for a
        sentinel while parsing, the options still holding it are set to
        their real defaults afterwards, and the others (those on the
        command line) are the set ``given`` of destinations, which
        :func:`check_arguments` judges against :data:`APPLIES`.
        """
        for action in self._actions:
            _once(action)
        saved = {
            action: action.default
            for action in self._actions
            if action.dest is not argparse.SUPPRESS and action.default is not argparse.SUPPRESS
        }
        for action in saved:
            action.default = _NOT_GIVEN
        try:
            namespace, extras = super().parse_known_args(args, namespace)
        finally:
            for action, default in saved.items():
                action.default = default
        given = set(getattr(namespace, "given", ()))
        # judged before any default is filled in: two spellings of one option
        # (--unit, kept for --constants-unit) share a destination
        typed = {
            action.dest
            for action in saved
            if getattr(namespace, action.dest, _NOT_GIVEN) is not _NOT_GIVEN
        }
        given |= typed
        for action, default in saved.items():
            if action.dest not in typed and getattr(namespace, action.dest) is _NOT_GIVEN:
                if isinstance(default, str):
                    default = self._get_value(action, default)  # as argparse does
                setattr(namespace, action.dest, default)
        namespace.given = given
        return namespace, extras


# actions that may be given more than once, or that end the parse
_REPEATABLE = (
    argparse._HelpAction,
    argparse._VersionAction,
    argparse._AppendAction,
    argparse._CountAction,
    argparse._SubParsersAction,
)
_ONCE_CLASSES = {}


def _once(action):
    """Make ``action`` refuse a second setting of its destination (idempotent).

    argparse lets the last of ``--theta 0.5 --theta 0.7`` win silently, and
    two spellings of one option (``--unit MHz --constants-unit GHz``) too;
    here either is one line naming both.
    """
    kind = type(action)
    if (
        not action.option_strings
        or isinstance(action, _REPEATABLE)
        or kind in _ONCE_CLASSES.values()
    ):
        return
    if kind not in _ONCE_CLASSES:

        def __call__(self, parser, namespace, values, option_string=None):
            seen = namespace.__dict__.setdefault("_options_seen", {})
            first = seen.get(self.dest)
            if first is not None:
                nargs = self.nargs
                several = nargs in ("+", "*") or (isinstance(nargs, int) and nargs > 1)
                if first == option_string:
                    hint = f": give every value after one {option_string}" if several else ""
                    raise InputError(f"{option_string} is given more than once{hint}")
                raise InputError(f"{first} and {option_string} set the same thing: give one")
            seen[self.dest] = option_string
            kind.__call__(self, parser, namespace, values, option_string)

        _ONCE_CLASSES[kind] = type(f"Once{kind.__name__}", (kind,), {"__call__": __call__})
    action.__class__ = _ONCE_CLASSES[kind]


class _NotGivenType:
    def __repr__(self):
        return "<not given>"


_NOT_GIVEN = _NotGivenType()


# what a number on the command line may look like: ASCII digits, an optional
# sign, point and exponent.  Python's float() and int() also take "1_0" and
# non-ASCII digits ("\uff11\uff10"), which would pass as 10 unseen.
_DECIMAL = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?", re.ASCII)
_SPECIAL = ("nan", "+nan", "-nan", "inf", "+inf", "-inf", "infinity", "+infinity", "-infinity")
_INTEGER = re.compile(r"[+-]?[0-9]+", re.ASCII)


def finite(text):
    if not (_DECIMAL.fullmatch(text) or text.lower() in _SPECIAL):
        raise argparse.ArgumentTypeError(f"not a number: {text!r}")
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"not a finite number: {text!r}")
    return value


def moment(text):
    """A moment typed in decimal: refused where the double would not be it.

    Below the smallest normal double (2.2e-308) a decimal is stored with
    fewer than 53 bits (``1e-320`` becomes ``9.99988671826831e-321``), so the
    body computed would silently differ from the one typed.
    """
    value = finite(text)
    sign = read_as_zero(text, value)
    if sign is not None:  # 1e-400 reads as 0: say so, not "moments (0, 2, 2.5)"
        raise argparse.ArgumentTypeError(
            f"{text!r} is {sign}below the smallest normal double (2.2e-308): it reads as "
            "0; give the moments in larger units"
        )
    if below_normal(value):
        raise argparse.ArgumentTypeError(below_normal_message(repr(text)))
    return value


def integer_at_least(minimum):
    """An argparse type: an ASCII integer >= ``minimum``, refused in one line."""

    def parse(text):
        if not _INTEGER.fullmatch(text):
            raise argparse.ArgumentTypeError(f"not an integer: {text!r}")
        value = int(text)
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be an integer >= {minimum}, got {value}")
        return value

    return parse


positive_int = integer_at_least(1)


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
        type=moment,
        metavar=("I1", "I2", "I3"),
        help="principal moments of inertia",
    )
    exclusive.add_argument(
        "--t-handle",
        nargs=3,
        type=finite,
        metavar=("L1", "L2", "W"),
        help="the paper's T-handle of unit mass: cross piece "
        "L1, shaft L2, square section W (eqn:IsforT)",
    )
    exclusive.add_argument(
        "--ellipsoid",
        nargs=2,
        type=finite,
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
        "--name",
        help="name of the single body (its label in catalogs, figures and "
        "printed tables; default: the moments or the preset)",
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
        type=finite,
        metavar=("A", "B", "C"),
        help="uniform solid box with full edges A, B, C along x, y, z, in metres "
        "(with --mass in kg: moments in kg m^2; Body.box)",
    )
    cylinder = exclusive.add_argument(
        "--cylinder",
        nargs="+",
        type=finite,
        metavar="R L [RY]",
        help="uniform solid cylinder along z, in metres: radius R (along x), "
        "length L, optional second semi-axis RY of an "
        "elliptic section (a circular one is a symmetric "
        "top); with --mass in kg (Body.cylinder)",
    )
    cylinder.shown = "R L [RY]"  # two or three numbers (checked after parsing)
    exclusive.add_argument(
        "--point-masses",
        metavar="FILE.csv",
        help="rigid point masses: a CSV with columns mass (kg), x, y, "
        "z (m), about the centre of mass (Body.from_point_masses)",
    )
    exclusive.add_argument(
        "--mesh",
        metavar="FILE",
        help="uniform solid bounded by a closed STL/OBJ mesh, vertices in "
        "metres, with --density in kg/m^3 (Body.from_mesh; needs orbits[mesh])",
    )
    exclusive.add_argument(
        "--rotational-constants",
        nargs=3,
        type=finite,
        metavar=("A", "B", "C"),
        help="a molecule from its rotational constants, in --constants-unit "
        "(moments in kg m^2; Body.from_rotational_constants)",
    )
    group.add_argument(
        "--mass",
        type=finite,
        default=1.0,
        help="mass in kg for --box and --cylinder (default 1 kg): it scales the moments "
        "(kg m^2) and with them the E, |L| and D that phase --omega prints; the motion, "
        "periods and phases depend only on the moments' ratios",
    )
    group.add_argument(
        "--density",
        type=finite,
        default=1.0,
        help="density in kg/m^3 for --mesh (default 1 kg/m^3); as --mass, it scales "
        "the moments, not the motion, periods or phases",
    )
    group.add_argument(
        "--constants-unit",
        choices=CONSTANTS_UNITS,
        default="cm-1",
        help="unit of --rotational-constants (default cm-1)",
    )
    # the old spelling, until the next major version: one deprecation line on stderr
    group.add_argument(
        "--unit",
        dest="constants_unit",
        action=_DeprecatedUnit,
        help=argparse.SUPPRESS,
    )
    group.add_argument(
        "--defect",
        choices=["error", "flatten"],
        default="error",
        help="measured moments past the flat limit I3 = I1 + I2 (the inertial "
        "defect of --rotational-constants, or --point-masses/--mesh a hair "
        "past it): refuse (default) or put the body on the flat edge, "
        "reporting the excess",
    )


CONSTANTS_UNITS = ["cm-1", "MHz", "GHz"]


class _DeprecatedUnit(argparse.Action):
    """``--unit``: the old name of ``--constants-unit`` (works, with a note on stderr).

    The note is kept in ``namespace.notes`` and printed by
    :func:`orbits.cli.main` after a successful run, so that a refusal stays
    one line.
    """

    def __call__(self, parser, namespace, values, option_string=None):
        if values not in CONSTANTS_UNITS:  # e.g. --unit rad/s, meant as --units
            parser.error(
                f"argument --unit: invalid choice: {values!r} (--unit is the old name of "
                f"--constants-unit, the unit of --rotational-constants: "
                f"{', '.join(CONSTANTS_UNITS)}; the unit of a spin is --units)"
            )
        notes = list(getattr(namespace, "notes", ()))
        notes.append(
            "--unit is deprecated; use --constants-unit (the unit of "
            "--rotational-constants; --units is the unit of a spin)"
        )
        namespace.notes = notes
        setattr(namespace, self.dest, values)


POINT_MASS_COLUMNS = ("mass", "x", "y", "z")


def _point_masses_from_csv(path):
    """``(masses, positions)`` of a point-mass CSV, read strictly.

    A header naming ``mass, x, y, z`` (any order, nothing else), then one
    row per mass with exactly those fields, each a plain decimal number
    (:data:`orbits.catalog.NUMBER`: ``1_0``, non-ASCII digits, ``nan``,
    ``0x10`` and empty cells are refused, not read as something else).
    ``#`` starts a comment to the end of its line; blank lines are skipped.
    """
    import csv
    import math

    import numpy as np

    from ..catalog import NUMBER
    from ..limits import read_input_text

    text = read_input_text(path, "point-mass file")
    header, order, rows = None, None, []
    lines = [line.split("#", 1)[0] for line in text.splitlines()]
    reader = csv.reader(lines, strict=True)
    try:
        for record in reader:
            line = reader.line_num
            if not "".join(record).strip():
                continue  # a blank or comment line
            if header is None:
                header = [cell.strip() for cell in record]
                _check_point_mass_header(path, header)
                order = [header.index(name) for name in POINT_MASS_COLUMNS]
                continue
            if len(record) != len(header):
                raise InputError(
                    f"{path}, line {line}: {len(record)} fields where the header has "
                    f"{len(header)} (mass, x, y, z)"
                )
            cells = [record[k].strip() for k in order]
            for name, cell in zip(POINT_MASS_COLUMNS, cells):
                if not NUMBER.fullmatch(cell) or not math.isfinite(float(cell)):
                    raise InputError(
                        f"{path}, line {line}: {name} = {cell!r}; mass, x, y, z must be "
                        "numbers (plain finite decimals)"
                    )
            rows.append([float(cell) for cell in cells])
    except csv.Error as error:
        raise InputError(f"{path} is not a CSV of point masses: {error}") from None
    if header is None:
        raise InputError(f"{path}: no header line (the columns mass, x, y, z)")
    if not rows:
        raise InputError(f"{path}: no point masses after the header")
    values = np.array(rows, dtype=float)
    return values[:, 0], np.ascontiguousarray(values[:, 1:])


def _check_point_mass_header(path, header):
    from ..catalog import header_problems

    what = header_problems(header, POINT_MASS_COLUMNS, POINT_MASS_COLUMNS)
    if what:
        raise InputError(f"{path}: point-mass CSV needs columns mass, x, y, z; {what}")


def _real_body_from_args(args):
    """The body of a real-body option, or None if none was given."""
    name = getattr(args, "name", None)
    if getattr(args, "box", None) is not None:
        return Body.box(*args.box, args.mass, name=name or numbers_label("box", args.box))
    if getattr(args, "cylinder", None) is not None:
        if len(args.cylinder) not in (2, 3):
            raise InputError("--cylinder takes R L or R L RY")
        radius, length, *rest = args.cylinder
        return Body.cylinder(
            radius,
            length,
            args.mass,
            radius_y=rest[0] if rest else None,
            name=name or numbers_label("cylinder", args.cylinder),
        )
    if getattr(args, "point_masses", None) is not None:
        masses, positions = _point_masses_from_csv(args.point_masses)
        return _flattened(
            Body.from_point_masses, args, masses, positions, name=name or args.point_masses
        )
    if getattr(args, "mesh", None) is not None:
        return _flattened(
            Body.from_mesh, args, args.mesh, density=args.density, name=name or args.mesh
        )
    if getattr(args, "rotational_constants", None) is not None:
        return _flattened(
            Body.from_rotational_constants,
            args,
            *args.rotational_constants,
            unit=args.constants_unit,
            name=name or numbers_label("rotational-constants", args.rotational_constants),
        )
    return None


def _flattened(constructor, args, *values, **options):
    """A measured body built with ``--defect``; the excess removed is reported on stderr.

    Measured moments (point masses, meshes, rotational constants) may lie a
    hair past the flat limit ``I3 = I1 + I2``: ``--defect flatten`` puts the
    body on it (the constructor's ``defect="flatten"``) and its warning,
    which gives the excess, is printed as one line.
    """
    from .._args import held_warnings

    if args.defect != "error":
        options["defect"] = args.defect
    with held_warnings() as caught:  # not catch_warnings: process-wide
        body = constructor(*values, **options)
    for message, _ in caught:
        print(f"orbits: warning: {message}", file=sys.stderr)
    return body


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
        return Body(args.moments, name=numbers_label("moments", args.moments))
    if args.t_handle is not None:
        return Body.t_handle(*args.t_handle, name=numbers_label("t-handle", args.t_handle))
    if args.ellipsoid is not None:
        return Body.ellipsoid(*args.ellipsoid, name=numbers_label("ellipsoid", args.ellipsoid))
    return Body.preset(args.preset)


def command_line(argv):
    """The command as typed, for the provenance header of output files."""
    import shlex

    words = sys.argv[1:] if argv is None else list(argv)
    return "orbits " + " ".join(shlex.quote(word) for word in words)


def bodies_file_from_args(args, report=True):
    """The strictly read ``--bodies`` file; skipped rows reported on stderr
    (later, by :func:`report_skipped`, with ``report=False``: after the
    checks that could still refuse the run, so that a refusal is one line)."""
    from ..catalog import read_bodies_csv

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
    if report:
        report_skipped(table)
    return table


def report_skipped(table):
    """One warning line per skipped row of a bodies file (the first 20, then a count)."""
    for _, message in table.skipped[:20]:
        print(f"orbits: warning: skipped {message}", file=sys.stderr)
    if len(table.skipped) > 20:
        print(
            f"orbits: warning: skipped {len(table.skipped) - 20} more invalid rows",
            file=sys.stderr,
        )


def bodies_from_args(args):
    """The bodies selected by the body options and header notes (skipped rows)."""
    if getattr(args, "bodies", None) is not None:
        table = bodies_file_from_args(args)
        return table.bodies(), table.skipped_note()
    if getattr(args, "skip_invalid", False):
        raise InputError("--skip-invalid applies to a --bodies file")
    return [body_from_args(args)], []


def angle_argument(value, args):
    """An angle of the command line in radians (``--degrees`` converts)."""
    return math.radians(value) if getattr(args, "degrees", False) else value


# Below the smallest normal double (2.2e-308) the spacing of doubles is a
# fixed 2**-1074 = 4.9e-324: an offset keeps 12 significant digits down to
# 2**-1074 * 1e12 = 4.9e-312; below that the phase of the offset as stored
# differs visibly from that of the offset typed (1.5e-8 relative at 1e-320).
SUBNORMAL_STEP = 2.0**-1074
SMALLEST_OFFSET = SUBNORMAL_STEP * 1e12


def offset_argument(value, args):
    """A ``--dtheta`` in radians (``orbits phase``, ``orbits animate``), refused
    where a double keeps fewer than 12 significant digits of it (subnormal
    offsets below 4.941e-312)."""
    offset = angle_argument(value, args)
    if offset != 0.0 and abs(offset) < SMALLEST_OFFSET:
        digits = max(0, int(math.log10(abs(offset) / SUBNORMAL_STEP)))
        raise InputError(
            f"--dtheta {value!r} is a subnormal double with about {digits} significant "
            f"digits (computed as {offset:.6g} rad); offsets from {SMALLEST_OFFSET:.4g} "
            "up keep at least 12"
        )
    return offset


def announce(command, seconds, memory):
    """One stderr line before a step estimated to take more than 2 s."""
    if seconds > 2:
        print(
            f"orbits {command}: estimated {format_duration(seconds)}, up to {format_bytes(memory)}"
            " of memory; working...",
            file=sys.stderr,
            flush=True,
        )


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


# ------------------------------------------------------------ applicability
# What a subcommand works on (argparse dest names): the body, or the source
# that stands in for one, and the spin.  At most one of each kind is given
# (argparse's exclusive groups and the commands' own checks see to that).
# "sample" is verify's region sample, chosen by giving no body option.
SINGLE_BODIES = BODY_SELECTORS
SELECTORS = {
    "phase": (
        SINGLE_BODIES,
        ("theta", "dtheta", "omega", "total_phase", "period_ratio", "periods"),
    ),
    "catalog": (SINGLE_BODIES + ("bodies",), ("omega",)),
    "figures": (SINGLE_BODIES + ("paper", "survey"), ()),
    "survey": (("resolution", "bodies", "check"), ()),
    "verify": (SINGLE_BODIES, ()),
    "bench": ((), ()),
    "animate": (SINGLE_BODIES, ("theta", "dtheta", "n", "p", "flip", "omega")),
}
# what a command works on when none of its body selectors is given (a
# command not listed reports the missing body itself)
NO_BODY = {"verify": "sample"}
ALL_BODIES = frozenset(name for bodies, _ in SELECTORS.values() for name in bodies) | frozenset(
    NO_BODY.values()
)
COMMANDS = tuple(SELECTORS)
BODY_COMMANDS = ("phase", "catalog", "figures", "verify", "animate")


def _only(*names):
    return frozenset(names)


def _all_but(*names):
    return ALL_BODIES - frozenset(names)


class Applies:
    """Where one option applies: subcommands, bodies and spins.

    Parameters
    ----------
    commands : tuple of str
        The subcommands that have the option (argparse refuses it elsewhere).
    bodies, spins : frozenset of str or None
        The body and spin selectors (dest names of :data:`SELECTORS`, or
        ``"sample"``) it applies to; None: every one.  ``spins`` may also be
        a dict from subcommand to such a set, for an option whose meaning
        differs between subcommands.
    """

    __slots__ = ("commands", "bodies", "spins")

    def __init__(self, commands, bodies=None, spins=None):
        self.commands, self.bodies, self.spins = tuple(commands), bodies, spins

    def __repr__(self):
        return f"Applies({self.commands!r}, bodies={self.bodies!r}, spins={self.spins!r})"

    def spins_for(self, command):
        """The spin selectors the option applies to in ``command`` (None: every one)."""
        return self.spins.get(command) if isinstance(self.spins, dict) else self.spins


# Every option that is not itself a selector, and where it applies.  A new
# option is one line here (tests/test_cli_applicability.py fails for an
# option of the parser that is missing).  Given where it does not apply, an
# option is refused with one line naming both (check_arguments): never
# silently ignored.
APPLIES = {
    "--threads": Applies(COMMANDS),
    # ---- body modifiers
    "--name": Applies(BODY_COMMANDS, bodies=_only(*SINGLE_BODIES)),
    "--mass": Applies(BODY_COMMANDS, bodies=_only("box", "cylinder")),
    "--density": Applies(BODY_COMMANDS, bodies=_only("mesh")),
    # (the deprecated spelling --unit has the same dest, so the same rule)
    "--constants-unit": Applies(BODY_COMMANDS, bodies=_only("rotational_constants")),
    "--defect": Applies(
        BODY_COMMANDS, bodies=_only("rotational_constants", "point_masses", "mesh")
    ),
    "--skip-invalid": Applies(("catalog", "survey"), bodies=_only("bodies")),
    # verify --bodies N: the size of the region sample (a selector elsewhere)
    "--bodies": Applies(("verify",), bodies=_only("sample")),
    # ---- spin modifiers
    "--phi": Applies(("phase", "animate"), spins=_only("theta", "dtheta")),
    "--degrees": Applies(("phase",), spins=_only("theta", "dtheta", "total_phase")),
    # animate: --omega, or the --speed of --theta, --dtheta and --flip (the
    # command refuses --units with neither --omega nor --speed)
    "--units": Applies(
        ("phase", "catalog", "animate"),
        spins={
            "phase": _only("omega"),
            "catalog": _only("omega"),
            "animate": _only("omega", "theta", "dtheta", "flip"),
        },
    ),
    "--time-unit": Applies(("phase",), spins=_only("periods")),
    "--nearest": Applies(("catalog",), bodies=_only(*SINGLE_BODIES), spins=_only("omega")),
    "--speed": Applies(("animate",), spins=_only("theta", "dtheta", "flip")),
    "--seconds": Applies(("animate",)),
    "--q": Applies(("animate",), spins=_only("p")),
    "--branch": Applies(("animate",), spins=_only("n", "p")),
    # ---- searches and outputs
    "--n-max": Applies(
        ("catalog", "figures", "survey"), bodies=_only(*SINGLE_BODIES, "bodies", "resolution")
    ),
    "--q-max": Applies(
        ("catalog", "figures", "survey"), bodies=_only(*SINGLE_BODIES, "bodies", "resolution")
    ),
    "--verify": Applies(("catalog",)),
    "--out": Applies(("catalog", "figures", "survey", "animate"), bodies=_all_but("check")),
    "--csv": Applies(("phase",)),
    "--formats": Applies(("figures",)),
    "--format": Applies(("survey",), bodies=_all_but("check")),
    "--chunk": Applies(("survey",), bodies=_all_but("check")),
    "--columns": Applies(("survey",), bodies=_all_but("check")),
    "--scheduler": Applies(("survey",), bodies=_all_but("check")),
    "--json": Applies(("survey", "verify", "bench")),
    "--angles": Applies(("verify",)),
    "--tolerance": Applies(("verify",)),
    "--table": Applies(("verify",)),
    "--no-progress": Applies(("verify",)),
    "--only": Applies(("bench",)),
    "--quick": Applies(("bench",)),
    "--device": Applies(("bench", "survey"), bodies=_all_but("check")),
    "--no-load-check": Applies(("bench",)),
    "--periods": Applies(("animate",)),
    "--frames": Applies(("animate",)),
    "--fps": Applies(("animate",)),
    "--dpi": Applies(("animate",)),
    "--solid": Applies(("animate",)),
}

# what follows the name of a selector in a refusal
_SELECTOR_NOTES = {
    "sample": "the region sample (no body option)",
    "check": "--check (which takes only the directory and --json)",
}

# Angles typed in radians beyond one turn are refused: the top's symmetries
# would fold them silently, and --theta 60 almost surely means degrees.
# (--dtheta is never folded: within the turn, the library refuses any
# theta_crit + dtheta outside [0, pi/2].)
ANGLE_OPTIONS = ("theta", "dtheta", "phi")
ONE_TURN = 2.0 * math.pi


def option_string(dest):
    """``--t-handle`` for the dest ``t_handle`` (every option here is spelled so)."""
    return "--" + dest.replace("_", "-")


def _label(selector):
    return _SELECTOR_NOTES.get(selector, option_string(selector))


def _targets(names, command):
    """Words for the selectors an option applies to, in the command's order."""
    bodies, spins = SELECTORS[command]
    order = list(bodies) + list(spins) + [NO_BODY.get(command)]
    present = [name for name in order if name in names]
    singles = [name for name in present if name in SINGLE_BODIES]
    words = [_label(name) for name in present]
    if len(singles) == len(SINGLE_BODIES) > 1:
        words = ["a single body (" + ", ".join(option_string(name) for name in singles) + ")"] + [
            _label(name) for name in present if name not in SINGLE_BODIES
        ]
    if len(words) <= 2:
        return " and ".join(words)
    return ", ".join(words[:-1]) + " and " + words[-1]


def _selected(args, names):
    given = [name for name in names if name in args.given]
    return given[0] if len(given) == 1 else None


# the options that name a file or a directory (argparse dests)
PATH_OPTIONS = ("out", "check", "bodies", "point_masses", "mesh", "table", "survey")


def check_arguments(args):
    """Refuse options given where they do not apply, and angles beyond a turn.

    Run by :func:`orbits.cli.main` after parsing, before any work.  Only
    options typed on the command line are judged (``args.given``, see
    :meth:`Parser.parse_known_args`); defaults never are.

    Raises
    ------
    InputError
        ``--mass applies to --box and --cylinder, not to --t-handle``, or an
        angle in radians outside [-2 pi, 2 pi] (or degrees outside
        [-360, 360] with ``--degrees``).  This is the only range checked
        here; a ``--dtheta`` inside it is refused later, by the library,
        unless ``theta_crit + dtheta`` lies in [0, pi/2].
    """
    command = getattr(args, "command", None)
    for dest in PATH_OPTIONS:
        if getattr(args, dest, None) == "":
            # '' read as the current directory: "cannot write .: it is a directory"
            raise InputError(f"{option_string(dest)} must be a non-empty path, got '' (str)")
    if command not in SELECTORS:
        return
    given = getattr(args, "given", set())
    bodies, spins = SELECTORS[command]
    body = _selected(args, bodies)
    if body is None and not any(name in given for name in bodies):
        body = NO_BODY.get(command)
    spin = _selected(args, spins)
    for dest in sorted(given, key=option_string):
        if dest in bodies or dest in spins or dest == "command":
            continue
        option = option_string(dest)
        rule = APPLIES.get(option)
        if rule is None:
            continue  # tests/test_cli_applicability.py keeps this from happening
        for selected, allowed in ((body, rule.bodies), (spin, rule.spins_for(command))):
            if selected is not None and allowed is not None and selected not in allowed:
                raise InputError(
                    f"{option} applies to {_targets(allowed, command)}, not to {_label(selected)}"
                )
        allowed = rule.spins_for(command)
        if spin is None and allowed is not None and not any(name in given for name in spins):
            # e.g. catalog --units rpm with no --omega: nothing for it to apply to
            raise InputError(f"{option} applies only with {_targets(allowed, command)}")
    _check_angles(args, given)
    _check_names(args, given)
    _check_output_is_no_input(args, given)


# options that name files the command writes or reads
_PATH_OPTIONS = ("out", "table", "bodies", "point_masses", "mesh")
_OUTPUT_OPTIONS = ("out", "table")
_INPUT_OPTIONS = ("bodies", "point_masses", "mesh", "survey")


def _check_output_is_no_input(args, given):
    """Refuse an output that is one of the command's input files.

    ``catalog --bodies in.csv --out in.csv`` would replace the bodies with
    the catalog.  The same file under another name (a link, a hard link,
    ``./in.csv``) is found too (``os.path.samefile``).
    """
    import os

    for out in _OUTPUT_OPTIONS:
        target = getattr(args, out, None)
        if out not in given or not isinstance(target, str) or target == "-":
            continue
        for source in _INPUT_OPTIONS:
            read = getattr(args, source, None)
            if source not in given or not isinstance(read, str) or read == "-":
                continue
            if not os.path.isfile(read):  # a survey directory takes a figure beside its parts
                continue
            try:
                same = os.path.samefile(target, read)
            except (OSError, ValueError):  # one of them does not exist (yet)
                continue
            if same:
                raise InputError(
                    f"{option_string(out)} {target} is the input file of "
                    f"{option_string(source)}: writing it would replace the input; "
                    "give another path"
                )


def _check_names(args, given):
    """Refuse a file name with a control character (a newline, a tab, ...).

    Such a name is legal on POSIX but would split or garble every message
    and provenance line that quotes it, and is nearly always a typing or
    quoting accident.
    """
    for dest in _PATH_OPTIONS:
        value = getattr(args, dest, None)
        if dest in given and isinstance(value, str):
            bad = [c for c in value if ord(c) < 32 or ord(c) == 127]
            if bad:
                raise InputError(
                    f"{option_string(dest)} {value!r} contains the control character "
                    f"{bad[0]!r}: give a file name without control characters"
                )


def _check_angles(args, given):
    degrees = "degrees" in given
    limit = 360.0 if degrees else ONE_TURN
    for dest in ANGLE_OPTIONS:
        if dest not in given:
            continue
        value = getattr(args, dest)
        for angle in value if isinstance(value, list) else [value]:
            if abs(angle) <= limit:
                continue
            option = option_string(dest)
            if degrees:
                raise InputError(
                    f"{option} {angle:g} deg is outside [-360, 360] (one turn either way)"
                )
            if abs(angle) <= 720.0:
                hint = "add --degrees, or " if hasattr(args, "degrees") else ""
                raise InputError(
                    f"{option} {angle:g} rad is outside [-2 pi, 2 pi] and looks like degrees "
                    f"({angle:g} deg = {math.radians(angle):.6g} rad): {hint}give radians"
                )
            raise InputError(
                f"{option} {angle:g} rad is outside [-2 pi, 2 pi]: too large to fold as an "
                "angle (give radians within one turn)"
            )
