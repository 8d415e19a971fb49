"""Every public function validates its inputs (issue 9, item 5).

Random garbage goes into one argument of each public function at a time
(the others valid); the only acceptable outcomes are a correct result
(finite numbers where numbers are returned, equal to the result for the
same value given as a plain float where that is defined) or an
``OrbitsError`` subclass.  Type faults are ``ArgumentTypeError``, which is
also a ``TypeError``.
"""

import math
from decimal import Decimal
from fractions import Fraction

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import orbits
from orbits import ArgumentTypeError, InputError, OrbitsError
from orbits.survey import Survey, check_survey, compute_chunk, read_survey

FIG6 = [0.26, 0.55, 0.793662]
BODY = orbits.Body(FIG6)
MOTION = orbits.Motion.from_spin(BODY, 0.4)

junk = st.one_of(
    st.none(),
    st.booleans(),
    st.text(max_size=6),
    st.binary(max_size=4),
    st.complex_numbers(max_magnitude=10),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-4, 40),
    st.sampled_from([10**30, -(10**30), 2**64, 2**63 - 1]),
    st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=5),
    st.lists(st.integers(-2, 6), max_size=4),
    st.lists(st.floats(0.05, 2.0), min_size=3, max_size=3),
    st.sampled_from(
        [
            [[1, 2], [1, 2, 3]],
            {"a": 1},
            object(),
            np.array(["x"]),
            np.float32(0.5),
            np.int8(3),
            Fraction(1, 3),
            Decimal("0.5"),
            np.zeros((2, 2)),
            np.ones((2, 3)),
            np.array([]),
            [],
            (),
            FIG6,
            [FIG6, FIG6],
            [0.3, 0.6, 0.9],
            [1e300, 1e300, 1e300],
            np.bool_(True),
            np.datetime64("2020-01-01"),
            # beyond a double as a count: OverflowError from float(); NumPy
            # calls timedelta64 an Integral, which int() refuses; a 0-d array
            # has __iter__ and raises when iterated
            Fraction(10**400, 3),
            10**400,
            np.timedelta64(3, "s"),
            np.array(0.5),
            slice(1),
            "3",
            "0.5",
            b"3",
            3 + 0j,
            [1e-200] * 3,
            math.nan,
            math.inf,
            -0.0,
            0,
            1,
            2,
            0.5,
            1.2,
        ]
    ),
)


def check_finite(result):
    """Numbers in a result are finite (no silent NaN or inf)."""
    if isinstance(result, pd.DataFrame):
        numeric = result.select_dtypes("number").to_numpy(dtype=float)
        assert np.all(np.isfinite(numeric)), result
    elif isinstance(result, (tuple, list)):
        for item in result:
            check_finite(item)
    elif isinstance(result, (np.ndarray, float, int, np.floating)):
        assert np.all(np.isfinite(np.asarray(result, dtype=float))), result


def same_as_float(call, value):
    """The call's result with ``value`` given as a float64 array."""
    return call(np.asarray(value, dtype=float))


CALLS = {
    # phases
    "total_phase.moments": lambda x: orbits.total_phase(x, 0.5),
    "total_phase.theta": lambda x: orbits.total_phase(FIG6, x),
    "total_phase.dtheta": lambda x: orbits.total_phase(FIG6, dtheta=x),
    "total_phase.phi": lambda x: orbits.total_phase(FIG6, 0.5, phi=x),
    "phases.moments": lambda x: orbits.phases(x, 0.5),
    "phases.theta": lambda x: orbits.phases(FIG6, x),
    "phases.dtheta": lambda x: orbits.phases(BODY, dtheta=x, phi=0.1),
    "phases.phi": lambda x: orbits.phases(FIG6, [0.1, 1.3], phi=x),
    "spin_phases.moments": lambda x: orbits.spin_phases(x, [0.3, 0.2, 0.9]),
    "spin_phases.omega": lambda x: orbits.spin_phases(BODY, x),
    "critical_angle.moments": lambda x: orbits.critical_angle(x),
    "critical_angle.phi": lambda x: orbits.critical_angle(FIG6, x),
    "phase_limits": lambda x: orbits.phase_limits(x),
    # motion
    "Motion.from_spin.body": lambda x: orbits.Motion.from_spin(x, 0.3).period,
    "Motion.from_spin.theta": lambda x: orbits.Motion.from_spin(BODY, x).period,
    "Motion.from_spin.dtheta": lambda x: orbits.Motion.from_spin(BODY, dtheta=x).period,
    "Motion.from_spin.phi": lambda x: orbits.Motion.from_spin(BODY, 0.3, phi=x).period,
    "Motion.from_spin.speed": lambda x: orbits.Motion.from_spin(BODY, 0.3, speed=x).energy,
    "Motion.from_omega.body": lambda x: (
        orbits.Motion.from_omega(x, [0.3, 0.2, 0.9], axes="principal").period
    ),
    "Motion.from_omega.omega": lambda x: (
        orbits.Motion.from_omega(BODY, x, axes="principal").period
    ),
    "Motion.state": lambda x: tuple(MOTION.state(x)),
    "Motion.omega": lambda x: MOTION.omega(x),
    "Motion.angular_momentum": lambda x: MOTION.angular_momentum(x),
    "Motion.euler_angles": lambda x: MOTION.euler_angles(x),
    "Motion.rotation": lambda x: MOTION.rotation(x),
    "Motion.quaternion": lambda x: MOTION.quaternion(x),
    "Motion.omega_space": lambda x: MOTION.omega_space(x),
    "Motion.rotation_object": lambda x: MOTION.rotation_object(x).as_quat(),
    "herpolhode.body": lambda x: orbits.herpolhode(x, 0.3, points=5),
    "herpolhode.theta": lambda x: orbits.herpolhode(FIG6, x, points=5),
    "herpolhode.periods": lambda x: orbits.herpolhode(FIG6, 0.3, periods=x, points=5),
    "herpolhode.points": lambda x: orbits.herpolhode(FIG6, 0.3, points=x),
    "polhode.body": lambda x: orbits.polhode(x, 0.3, points=5),
    "polhode.dtheta": lambda x: orbits.polhode(FIG6, dtheta=x, points=5),
    "polhode.periods": lambda x: orbits.polhode(FIG6, 0.3, periods=x, points=5),
    "polhode.points": lambda x: orbits.polhode(FIG6, 0.3, points=x),
    # closed orbits
    "closed_orbits.body": lambda x: orbits.closed_orbits(x, 3),
    "closed_orbits.n_max": lambda x: orbits.closed_orbits(BODY, x),
    "closed_orbits.q_max": lambda x: orbits.closed_orbits(BODY, 3, x),
    "minimum_phase": lambda x: orbits.minimum_phase(x),
    "phase_levels": lambda x: orbits.phase_levels(x, 2),
    "catalog.bodies": lambda x: orbits.catalog(x, 3),
    "catalog.n_max": lambda x: orbits.catalog([BODY], x),
    "catalog.q_max": lambda x: orbits.catalog([BODY], 3, q_max=x),
    "orbit_row.n": lambda x: orbits.orbit_row(BODY, n=x, branch="SAM"),
    "set_num_threads": lambda x: orbits.set_num_threads(x),
    "poinsot_animation.fps": lambda x: len(
        orbits.poinsot_animation(BODY, 0.4, frames=2, fps=x, dpi=20).times
    ),
    "poinsot_animation.seconds": lambda x: len(
        orbits.poinsot_animation(BODY, 0.4, seconds=x, fps=4, dpi=20).times
    ),
    "closure_errors.moments": lambda x: orbits.closure_errors(x, [-0.05], [2]),
    "closure_errors.dtheta": lambda x: orbits.closure_errors(FIG6, x, [1]),
    "closure_errors.periods": lambda x: orbits.closure_errors(FIG6, [-0.05], x),
    "closure_errors.rtol": lambda x: orbits.closure_errors(FIG6, [-0.05], [1], rtol=x),
    "read_catalog": lambda x: orbits.read_catalog(x),
    "region_grid": lambda x: orbits.region_grid(x),
    "region_sample": lambda x: orbits.region_sample(x),
    "spins_with_total_phase": lambda x: orbits.spins_with_total_phase(BODY, x),
    # survey API
    "compute_chunk.moments": lambda x: compute_chunk(x, 3),
    "compute_chunk.n_max": lambda x: compute_chunk([FIG6], x),
    "Survey.from_bodies": lambda x: (
        Survey.from_bodies("unused-survey-dir", x, 3, fmt="csv").parameters
    ),
    "Survey.n_max": lambda x: Survey("unused-survey-dir", [FIG6], {}, x, fmt="csv").chunks,
    "Survey.out_dir": lambda x: Survey(x, [FIG6], {}, 3, fmt="csv").chunks,
    "read_survey": lambda x: read_survey(x),
    "check_survey": lambda x: check_survey(x),
}

# calls whose result for a float array of the same value must be identical
COMPARABLE = {
    "total_phase.moments",
    "total_phase.theta",
    "total_phase.dtheta",
    "total_phase.phi",
    "critical_angle.moments",
    "critical_angle.phi",
}


@pytest.mark.parametrize("name", sorted(CALLS))
@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@pytest.mark.filterwarnings("ignore::orbits.UnresolvedOrbitsWarning")
@given(value=junk)
def test_garbage_gives_a_result_or_an_orbits_error(name, value, monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)  # any relative path junk stays in here
    call = CALLS[name]
    try:
        result = call(value)
    except OrbitsError as error:
        assert str(error).strip()  # a message (the CLI prints it on one line)
        return
    check_finite(result)
    if name in COMPARABLE:
        expected = same_as_float(call, value)
        np.testing.assert_array_equal(result, expected)


# ------------------------------------------------------- the examples
def test_type_faults_are_argument_type_errors_naming_the_argument():
    cases = [
        (lambda: orbits.total_phase([1j, 2, 3], 0.5), "moments"),
        (lambda: orbits.total_phase(["a", "b", "c"], 0.5), "moments"),
        (lambda: orbits.closed_orbits(FIG6, n_max="3"), "n_max"),
        (lambda: orbits.total_phase(FIG6, "0.5"), "theta"),
        (lambda: orbits.spin_phases(FIG6, [1, 2, "x"]), "omega"),
        (lambda: orbits.read_catalog(3), "path"),
        (lambda: orbits.region_grid(None), "resolution"),
        (lambda: orbits.herpolhode(FIG6, 0.3, periods="2"), "periods"),
    ]
    for call, name in cases:
        with pytest.raises(ArgumentTypeError, match=name):
            call()
    assert issubclass(ArgumentTypeError, TypeError)
    assert issubclass(ArgumentTypeError, InputError)


def test_booleans_mixed_into_numbers_are_refused():
    """np.asarray([True, 2, 1]) is [1, 2, 1]: the boolean would be read as 1."""
    cases = [
        (lambda: orbits.Body([True, 2, 3]), "moments"),
        (lambda: orbits.total_phase([0.3, 0.6, 0.9], [0.2, True]), "theta"),
        (
            lambda: orbits.total_phase([[0.3, 0.6, 0.9], [0.3, np.bool_(False), 0.9]], 0.2),
            "moments",
        ),
        (
            lambda: orbits.spin_phases(FIG6, [[1.0, 0.2, 0.1], (0.5, np.array([True]), 1.0)]),
            "omega",
        ),
    ]
    for call, name in cases:
        with pytest.raises(ArgumentTypeError, match=f"{name} must be real numbers, got .*bool"):
            call()
    # nested sequences of plain numbers are still numbers
    np.testing.assert_array_equal(
        orbits.total_phase([[0.3, 0.6, 0.9], (1, 2, 2.5)], 0.2),
        orbits.total_phase(np.array([[0.3, 0.6, 0.9], [1.0, 2.0, 2.5]]), 0.2),
    )


def test_masked_entries_are_refused_not_computed():
    """np.asarray drops a mask: the hidden values would be computed silently."""
    hidden = np.ma.array([0.5, 1.2], mask=[False, True])
    cases = [
        (lambda: orbits.total_phase(FIG6, hidden), "theta"),
        (lambda: orbits.phases(FIG6, dtheta=hidden - 1.0), "dtheta"),
        (lambda: orbits.total_phase(np.ma.array([1.0, 2.0, 2.5], mask=[0, 1, 0]), 0.3), "moments"),
        (lambda: orbits.Body(np.ma.array([1.0, 2.0, 2.5], mask=[0, 1, 0])), "moments"),
        (lambda: orbits.Motion.from_spin(FIG6, theta=0.5).omega(hidden), "t"),
    ]
    for call, name in cases:
        with pytest.raises(ArgumentTypeError, match=f"{name} is a masked array"):
            call()
    # nothing masked: the values are the array's
    clear = np.ma.array([0.5, 1.2], mask=[False, False])
    np.testing.assert_array_equal(
        orbits.total_phase(FIG6, clear), orbits.total_phase(FIG6, [0.5, 1.2])
    )


def test_shapes_that_do_not_broadcast_are_refused():
    with pytest.raises(InputError, match="broadcast"):
        orbits.total_phase([FIG6, FIG6, FIG6], [0.1, 0.2])
    with pytest.raises(InputError, match="broadcast"):
        orbits.phases(FIG6, [0.1, 0.2], phi=[0.0, 0.1, 0.2])
    with pytest.raises(InputError, match="broadcast"):
        orbits.closure_errors([FIG6, FIG6], [-0.05, -0.06, -0.07], [1])


def test_closure_errors_refuses_q_zero():
    """Returned NaN on main."""
    with pytest.raises(InputError, match="periods"):
        orbits.closure_errors(FIG6, [-0.05], [0])


def test_tiny_spin_is_not_called_the_separatrix():
    """spin_phases(body, [1e-200]*3) said 'on the separatrix' on main: its
    energy (~1e-400) is not a double, which is now what the error says; a
    spin of 1e-100 is computed (the phases do not depend on |omega|)."""
    with pytest.raises(InputError, match="energy does not fit"):
        orbits.spin_phases(BODY, [1e-200] * 3)
    small = orbits.spin_phases(BODY, [1e-100] * 3).iloc[0]
    unit = orbits.spin_phases(BODY, [1.0] * 3).iloc[0]
    assert small["total_phase"] == pytest.approx(unit["total_phase"], rel=1e-15)
    assert small["energy"] == pytest.approx(1e-200 * unit["energy"], rel=1e-15)
    assert small["period"] == pytest.approx(1e100 * unit["period"], rel=1e-15)


def test_survey_with_an_unusable_body_is_refused_up_front(tmp_path):
    """Main reported the paper's conjecture FAILED from a NaN minimum."""
    with pytest.raises(orbits.NonPhysicalBodyError, match="body 2 of 2"):
        Survey.from_bodies(tmp_path / "s", [FIG6, [1.0, 4.0, 8.0]], 3, fmt="csv")
    # a body at 1e150 is usable now, and its row is that of the unscaled body
    survey = Survey.from_bodies(tmp_path / "s", [FIG6, [v * 2.0**500 for v in FIG6]], 3, fmt="csv")
    survey.prepare()
    survey.run()
    report = survey.report()
    assert report["conjecture_minimum_at_the_ends"]["held_on_every_body"]
    bodies, _ = read_survey(tmp_path / "s")
    first, second = bodies.iloc[0], bodies.iloc[1]
    for column in ("I1", "I2", "I3", "min_total_phase", "theta_crit"):
        assert first[column] == second[column]


def test_bodies_file_flags_exactly_the_unusable_rows(tmp_path):
    from orbits.catalog import read_bodies_csv

    path = tmp_path / "bodies.csv"
    path.write_text(
        "I1,I2,I3\n0.26,0.55,0.793662\n0.26e150,0.55e150,0.793662e150\n"
        "1,4,8\n0.3,0.6,0.9\n1e-300,0.9999999999999999,1\n"
    )
    with pytest.raises(InputError, match="row 3"):
        read_bodies_csv(path)
    table = read_bodies_csv(path, skip_invalid=True)
    assert [row for row, _ in table.skipped] == [3]
    assert len(table.bodies()) == 4


def test_a_survey_of_tiny_chunks_is_estimated_and_refused(tmp_path):
    """Each chunk rewrites the manifest, whose ledger grows by a chunk: an
    adversarial `--resolution 200 --n-max 30 --chunk 5` took 102.6 s with no
    estimate line (the estimate ignored the chunks: under a second), and
    `--resolution 1612 --chunk 1` was estimated at 24 s (it needs weeks)."""
    from orbits.survey import check_survey_bounds, survey_estimate

    _, small = survey_estimate(15_402, 30, 1, 5)
    _, usual = survey_estimate(15_402, 30, 1, 20)
    assert 102.6 / 2 <= small <= 102.6 * 2 and 8.6 / 2 <= usual <= 8.6 * 2
    with pytest.raises(InputError, match=r"would take .*a larger --chunk \(now 1\)"):
        check_survey_bounds(1_000_828, 10, 1, 1)
    from orbits.cli import main

    assert (
        main(
            [
                "survey",
                "--resolution",
                "1612",
                "--n-max",
                "10",
                "--chunk",
                "1",
                "--out",
                str(tmp_path / "s"),
            ]
        )
        == 2
    )
    assert not (tmp_path / "s").exists()


@pytest.mark.parametrize("n_max", [1e308, 10**400, 2**63 - 1, 10**17])
def test_huge_level_counts_are_refused_before_any_allocation(n_max, tmp_path):
    """A hypothesis draw (n_max = 1e308) got the CI runner OOM-killed.

    The memory estimate was inf * 0 = NaN for zero bodies, and NaN > budget
    is False: phase_levels then tried to build 1e308 fractions.  Every
    entry point now refuses with a one-line message.
    """
    from orbits.limits import check_search_bounds
    from orbits.search import phase_levels
    from orbits.survey import check_survey_bounds

    calls = [
        lambda: phase_levels(n_max, 2),
        lambda: compute_chunk([FIG6], n_max),
        lambda: orbits.closed_orbits(BODY, n_max),
        lambda: orbits.catalog([BODY], n_max),
        lambda: check_search_bounds(n_max, 1, 0),
        lambda: check_survey_bounds(1000, n_max, 1, 10),
        lambda: Survey.from_bodies(tmp_path / "s", [FIG6], n_max, fmt="csv"),
    ]
    for call in calls:
        with pytest.raises(InputError, match="would need") as error:
            call()
        assert "\n" not in str(error.value) and len(str(error.value)) < 300


@pytest.mark.parametrize(
    "value", [Fraction(10**400, 3), Fraction(10**400, 1), 10**400, np.timedelta64(3, "s")]
)
@pytest.mark.parametrize(
    "name",
    [
        "closed_orbits.n_max",
        "closed_orbits.q_max",
        "phase_levels",
        "catalog.q_max",
        "orbit_row.n",
        "set_num_threads",
        "poinsot_animation.fps",
        "herpolhode.points",
    ],
)
def test_counts_beyond_a_double_are_orbits_errors(name, value, monkeypatch, tmp_path):
    """float() of such counts overflowed (OverflowError), int() of a
    timedelta64 (an Integral to NumPy) raised TypeError."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(OrbitsError):
        CALLS[name](value)


def test_a_zero_d_array_or_a_one_element_duration():
    """catalog(np.array(0.5)) iterated a 0-d array (TypeError); seconds=[3.0]
    reached float() (TypeError) after check_real_time had accepted it."""
    with pytest.raises(ArgumentTypeError, match="bodies must be"):
        orbits.catalog(np.array(0.5), 3)
    with pytest.raises(ArgumentTypeError, match="bodies must be"):
        Survey.from_bodies("unused-survey-dir", np.array(0.5), 3)
    for seconds in ([3.0], np.array([3.0]), 3.0):
        drawn = orbits.poinsot_animation(BODY, 0.4, seconds=seconds, fps=4, dpi=20)
        assert len(drawn.times) == 13 and drawn.times[-1] == pytest.approx(3.0, rel=1e-12)


@pytest.mark.parametrize(
    "solver, args, name",
    [
        ("spins_with_periods", (math.inf, 5.0), "P_psi"),
        ("spins_with_periods", (5.0, math.inf), "P_phi"),
        ("spins_with_periods", (0.0, 5.0), "P_psi"),
        ("spins_with_period_ratio", (math.inf,), "ratio"),
        ("spins_with_period_ratio", (-1.0,), "ratio"),
        ("spins_with_total_phase", (math.inf,), "total_phase"),
        ("spins_with_total_phase", (math.nan,), "total_phase"),
    ],
)
def test_inverse_solvers_name_a_target_that_is_not_positive_and_finite(solver, args, name):
    # refused by the argument's own check, naming it (with inf let through,
    # later checks refused it as "does not fit a double" or "too near the
    # separatrix": true of no spin, and not what was wrong)
    body = orbits.Body.preset("fig6")
    with pytest.raises(InputError, match=f"^{name} must be positive and finite, got "):
        getattr(orbits, solver)(body, *args)
