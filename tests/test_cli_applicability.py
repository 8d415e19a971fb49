"""The argument-applicability table (orbits.cli.shared.APPLIES), enumerated.

Every option of every subcommand is either a selector (a body, source or
spin) or has a row in the table; every option, given with every body and
spin selector of every subcommand, is refused (one line naming both) exactly
where its row says it does not apply, and passes the check where it does.
Defaults never count: only options typed on the command line are judged.
"""

import argparse
import itertools
import math

import pytest

from orbits.cli import build_parser, main
from orbits.cli.shared import (
    APPLIES,
    NO_BODY,
    SELECTORS,
    SINGLE_BODIES,
    check_arguments,
    option_string,
)
from orbits.errors import InputError

BODY_ARGS = {
    "moments": ["--moments", "1", "2", "2.5"],
    "t_handle": ["--t-handle", "8", "4", "1"],
    "ellipsoid": ["--ellipsoid", "0.5", "0.7"],
    "preset": ["--preset", "fig6"],
    "box": ["--box", "1", "2", "3"],
    "cylinder": ["--cylinder", "1", "2", "1.5"],
    "point_masses": ["--point-masses", "m.csv"],
    "mesh": ["--mesh", "m.stl"],
    "rotational_constants": ["--rotational-constants", "3", "2", "1"],
    "bodies": ["--bodies", "b.csv"],
    "paper": ["--paper"],
    "survey": ["--survey", "s"],
    "resolution": ["--resolution", "4"],
    "check": ["--check", "s"],
    "sample": [],
}
SPIN_ARGS = {
    "theta": ["--theta", "0.3"],
    "dtheta": ["--dtheta", "0.01"],
    "omega": ["--omega", "1", "2", "3"],
    "total_phase": ["--total-phase", "7"],
    "period_ratio": ["--period-ratio", "2"],
    "periods": ["--periods", "263", "27.38"],
    "n": ["--n", "2"],
    "p": ["--p", "3"],
    "flip": ["--flip"],
}
# what each command needs besides its body and spin, so that argparse accepts it
REQUIRED = {
    "phase": [],
    "catalog": ["--n-max", "2", "--out", "c.csv"],
    "figures": ["--out", "o"],
    "survey": [],
    "verify": [],
    "bench": [],
    "animate": ["--out", "a.gif"],
}


def _subparsers():
    parser = build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return parser, action.choices


def _options(parser):
    """Each option by the spelling of its dest (old spellings may be kept beside it)."""
    return {
        option_string(action.dest): action
        for action in parser._actions
        if action.option_strings
        and action.default != argparse.SUPPRESS  # not --help
        # an old spelling kept beside the new one (--unit for --constants-unit)
        and option_string(action.dest) in action.option_strings
    }


_PARSER = build_parser()


def _parse(argv):
    return _PARSER.parse_args(argv)


def _option_args(option, action, parser_argv):
    """``[option, value...]`` that argparse accepts for this option."""
    if action.nargs == 0:
        return [option]
    candidates = [["2"], ["0.5"]] + ([[str(c)] for c in action.choices] if action.choices else [])
    for values in candidates:
        try:
            _parse(parser_argv([option, *values]))
        except InputError:
            continue
        return [option, *values]
    raise AssertionError(f"no value found for {option}")


def test_every_option_is_a_selector_or_in_the_table():
    top, commands = _subparsers()
    assert set(commands) == set(SELECTORS)
    seen = {}
    for command, parser in commands.items():
        bodies, spins = SELECTORS[command]
        options = _options(parser)
        for dest in bodies + spins:
            assert option_string(dest) in options, (command, dest)
        for option, action in options.items():
            # the table names options by their dest
            assert option in action.option_strings, (option, action.option_strings)
            if action.dest in bodies or action.dest in spins:
                continue
            assert option in APPLIES, f"{command} {option}: add a row to APPLIES"
            assert command in APPLIES[option].commands, (command, option)
            seen.setdefault(option, set()).add(command)
    seen["--threads"] = set(commands)
    assert set(_options(top)) == {"--threads"}
    # and the table claims no command that lacks the option
    for option, rule in APPLIES.items():
        assert set(rule.commands) == seen.get(option, set()), option


def _combinations():
    _, commands = _subparsers()
    for command, parser in commands.items():
        bodies, spins = SELECTORS[command]
        body_choices = list(bodies) + ([NO_BODY[command]] if command in NO_BODY else [])
        for body, spin in itertools.product(body_choices or [None], spins or [None]):
            yield command, parser, body, spin


def test_every_combination_is_judged_by_the_table():
    refused = accepted = 0
    for command, parser, body, spin in _combinations():
        base = BODY_ARGS[body] if body else []
        base = base + (SPIN_ARGS[spin] if spin else []) + REQUIRED[command]
        selectors = SELECTORS[command][0] + SELECTORS[command][1]
        for option, action in _options(parser).items():
            if action.dest in selectors:
                continue

            def argv(extra, option=option):
                if option == "--threads":
                    return [extra[0], extra[1], command, *base]
                return [command, *base, *extra]

            if option in base:  # a required option: given once already (twice is refused)
                args = _parse([command, *base])
            else:
                args = _parse(argv(_option_args(option, action, argv)))
            rule = APPLIES[option]
            spins = rule.spins_for(command)
            if spin is None and spins is not None and SELECTORS[command][1]:
                # a spin modifier with no spin to modify (catalog --units, no --omega)
                with pytest.raises(InputError, match=f"^{option} applies only with "):
                    check_arguments(args)
                refused += 1
                continue
            applies = (rule.bodies is None or body is None or body in rule.bodies) and (
                spins is None or spin is None or spin in spins
            )
            if applies:
                check_arguments(args)
                accepted += 1
                continue
            with pytest.raises(InputError) as caught:
                check_arguments(args)
            message = str(caught.value)
            assert message.startswith(f"{option} applies to "), message
            wrong = body if rule.bodies is not None and body not in rule.bodies else spin
            assert f", not to {option_string(wrong)}" in message or (
                wrong in ("sample", "check") and "not to " in message
            ), message
            assert "\n" not in message
            refused += 1
    # the table is not vacuous either way
    assert refused > 500 and accepted > 500, (refused, accepted)


@pytest.mark.parametrize(
    "argv, message",
    [
        # the audit's cases (issue 20, item 2)
        (["--t-handle", "8", "4", "1", "--theta", "0.3", "--mass", "0.05"], "--mass applies to"),
        (["--moments", "1", "2", "2.5", "--theta", "0.3", "--mass", "2"], "not to --moments"),
        (["--box", "1", "2", "3", "--theta", "0.3", "--density", "2"], "not to --box"),
        (["--preset", "fig6", "--theta", "0.3", "--units", "Hz"], "not to --theta"),
        # given equal to the default is still given
        (["--t-handle", "8", "4", "1", "--theta", "0.3", "--mass", "1"], "not to --t-handle"),
        (["--preset", "fig6", "--theta", "0.3", "--units", "rad/s"], "--units applies to --omega"),
        (["--preset", "fig6", "--omega", "1", "2", "3", "--phi", "0"], "not to --omega"),
        (["--preset", "fig6", "--period-ratio", "2", "--degrees"], "not to --period-ratio"),
    ],
)
def test_audit_cases(argv, message, capsys):
    assert main(["phase", *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("orbits: error: ") and message in err[0]


def test_defaults_are_not_given():
    args = _parse(["phase", "--t-handle", "8", "4", "1", "--theta", "0.3"])
    assert args.given == {"command", "t_handle", "theta"}
    # and the defaults are the real ones
    assert args.mass == 1.0 and args.units == "rad/s" and args.phi == 0.0
    assert args.degrees is False and args.constants_unit == "cm-1"
    check_arguments(args)


def test_single_bodies_are_listed_once():
    args = _parse(["figures", "--paper", "--n-max", "3", "--out", "o"])
    with pytest.raises(InputError, match=r"--n-max applies to a single body \(--moments, "):
        check_arguments(args)
    assert len(SINGLE_BODIES) == 9


@pytest.mark.parametrize(
    "argv, fragment",
    [
        (
            ["phase", "--preset", "fig6", "--theta", "60"],
            "looks like degrees (60 deg = 1.0472 rad)",
        ),
        (["phase", "--preset", "fig6", "--theta", "0.3", "--phi", "-90"], "add --degrees"),
        (["phase", "--preset", "fig6", "--dtheta", "7"], "looks like degrees"),
        (["phase", "--preset", "fig6", "--theta", "1e6"], "too large to fold"),
        (["phase", "--preset", "fig6", "--theta", "400", "--degrees"], "[-360, 360]"),
        (["animate", "--preset", "fig6", "--theta", "45", "--out", "a.gif"], "give radians"),
    ],
)
def test_angles_beyond_a_turn(argv, fragment):
    with pytest.raises(InputError) as caught:
        check_arguments(_parse(argv))
    assert fragment in str(caught.value)
    if argv[0] == "animate":  # no --degrees there: not suggested
        assert "--degrees" not in str(caught.value)


@pytest.mark.parametrize(
    "argv",
    [
        ["phase", "--preset", "fig6", "--theta", "6.28", "-6.28", "3.2"],
        ["phase", "--preset", "fig6", "--theta", "90", "--phi", "-360", "--degrees"],
        ["animate", "--preset", "fig6", "--theta", "-1", "--phi", "6", "--out", "a.gif"],
    ],
)
def test_angles_within_a_turn_pass(argv):
    check_arguments(_parse(argv))


@pytest.mark.parametrize("option", ["--theta", "--phi", "--dtheta"])
@pytest.mark.parametrize("degrees", [False, True])
def test_the_angle_limit_is_one_turn_exactly(option, degrees):
    """At the edge: one turn passes, a hair more is refused, either sign
    (a limit of 361 deg, or 2 pi + 0.5, folded 360.5 deg to 0.5 deg silently;
    only values far past it were tested)."""
    turn = 360.0 if degrees else 2 * math.pi
    units = ["--degrees"] if degrees else []
    base = ["phase", "--preset", "fig6"] + (["--theta", "0.3"] if option == "--phi" else [])
    for value in (turn, -turn):
        check_arguments(_parse(base + [option, repr(value)] + units))
    for value in (turn + 0.5, -turn - 0.5, math.nextafter(turn, math.inf)):
        with pytest.raises(InputError, match=r"\[-360, 360\]" if degrees else r"\[-2 pi, 2 pi\]"):
            check_arguments(_parse(base + [option, repr(value)] + units))


@pytest.mark.parametrize(
    "options, name",
    [
        (["--moments", "1", "2", "3"], "moments(1, 2, 3)"),
        (["--moments", "1", "1.00000001", "1.00000002"], "moments(1, 1.00000001, 1.00000002)"),
        (
            ["--moments", "0.1", "0.2", "0.30000000000000004"],
            "moments(0.1, 0.2, 0.30000000000000004)",
        ),
        (["--t-handle", "1", "2.5", "0.1234567891"], "t-handle(1, 2.5, 0.1234567891)"),
        (["--ellipsoid", "0.5", "0.3"], "ellipsoid(0.5, 0.3)"),
        (["--box", "1", "2", "3.0000001", "--mass", "1"], "box(1, 2, 3.0000001)"),
        (
            ["--rotational-constants", "3.0000001", "2", "1.5"],
            "rotational-constants(3.0000001, 2, 1.5)",
        ),
    ],
)
def test_body_labels_read_back_exactly(options, name):
    """A body's label shows each number as given: nearly equal moments stay distinct."""
    from orbits.cli.shared import body_from_args

    args = _PARSER.parse_args(["phase", *options, "--theta", "0.5"])
    assert body_from_args(args).name == name


@pytest.mark.parametrize(
    "argv, fragment",
    [
        (["catalog", "--preset", "t-handle", "--n-max", "1_0"], "not an integer: '1_0'"),
        (["catalog", "--preset", "t-handle", "--n-max", "\uff11\uff10"], "not an integer"),
        (["phase", "--moments", "1", "2", "3_0", "--theta", "0.5"], "not a number: '3_0'"),
        (["phase", "--moments", "1", "2", "3", "--theta", "0.\u0665"], "not a number"),
        (["phase", "--moments", "1", "2", "3", "--theta", " 0.5"], "not a number"),
    ],
)
def test_numbers_are_ascii_decimals(argv, fragment, capsys):
    """Python's int() and float() read "1_0" as 10 and non-ASCII digits as
    digits; the command line takes plain decimals only."""
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and fragment in err[0]


@pytest.mark.parametrize("text", ["-1.", ".5", "+0.5", "5e-1", "0.5E+0", "-.5e-1"])
def test_plain_decimals_pass(text, capsys):
    assert main(["phase", "--moments", "1", "2", "3", "--dtheta", text]) == 0
    capsys.readouterr()


@pytest.mark.parametrize("option", ["--out", "--bodies"])
def test_control_characters_in_file_names_are_refused(option, tmp_path, capsys):
    name = str(tmp_path / "a\nb")
    argv = ["survey", "--n-max", "3", option, name]
    argv += ["--out", str(tmp_path / "s")] if option == "--bodies" else ["--resolution", "10"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "contains the control character '\\n'" in err[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == []
