"""The flat edge I3 = I1 + I2, decided exactly (issue 9, item 3).

The triangle test is exact (TwoSum); a body beyond the edge by at most
8 eps I3 is moved exactly onto it by changing one moment by the excess,
beyond that it is rejected.  On every accepted body Delta alpha >= 2 pi,
equal to 2 pi only in the limit theta -> 0 on the edge, so no n = 1 orbit
is ever reported.
"""

import math
from fractions import Fraction

import mpmath as mp
import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st
from mp_formulas import period_and_total_phase

import orbits
from orbits.bodies import Body, canonical_moments
from orbits.survey import compute_chunk

TWO_PI = 2.0 * math.pi
EPS = np.finfo(float).eps
ANGLES = np.array(
    [0.0, 1e-300, 1e-12, 1e-6, 1e-3, 0.1, 0.5, 0.9, 1.2, 1.5, math.pi / 2 - 1e-9, math.pi / 2]
)


def exact_excess(moments):
    a, b, c = sorted(Fraction(float(v)) for v in moments)
    return c - a - b


def check_never_below_two_pi(body):
    """min Delta alpha >= 2 pi, no p/q <= 1 orbit, every phase >= 2 pi."""
    low, _ = orbits.minimum_phase(body)
    assert low >= TWO_PI
    table = orbits.closed_orbits(body, n_max=3, q_max=2)
    assert (table["n"] > table["q"]).all()
    assert (table["total_phase"] > TWO_PI).all()
    for branch in ("SAM", "LAM"):
        assert table.attrs["minimum_phase"][branch][0] >= TWO_PI
    theta_c = orbits.critical_angle(body)
    angles = ANGLES[ANGLES != theta_c]
    phases = orbits.total_phase(body, angles)
    assert np.all(np.isfinite(phases)) and np.all(phases >= TWO_PI)
    return low


def test_the_issue_body_has_no_n1_orbit():
    """0.3 + 0.6 < 0.9 in doubles: main reported an n = 1 orbit at theta = 4.3e-8."""
    assert exact_excess((0.3, 0.6, 0.9)) > 0
    body = Body((0.3, 0.6, 0.9))
    assert body.is_flat and exact_excess(body.moments) == 0
    # I1 moved up by the excess (5.6e-17), nothing else
    assert body.moments[1:].tolist() == [0.6, 0.9]
    assert Fraction(body.moments[0]) - Fraction(0.3) == exact_excess((0.3, 0.6, 0.9))
    low = check_never_below_two_pi(body)
    assert low <= TWO_PI * (1 + 1e-14)  # the flat edge: 2 pi, at theta -> 0
    assert 1 not in orbits.closed_orbits([0.3, 0.6, 0.9], 3)["n"].tolist()


def test_rod_given_as_1e_minus_200_no_longer_gives_zero():
    """--moments 1e-200 1 1.0000000000000002 printed total_phase 0 on main."""
    body = Body((1e-200, 1.0, 1.0000000000000002))
    assert body.is_flat
    assert float(orbits.total_phase(body, 0.5)) > TWO_PI


def test_beyond_the_slack_is_rejected_with_the_reason():
    with pytest.raises(orbits.NonPhysicalBodyError, match="triangle inequality"):
        Body((0.3, 0.6, 0.9 * (1 + 16 * EPS)))
    with pytest.raises(orbits.NonPhysicalBodyError, match="triangle inequality"):
        orbits.total_phase([1.0, 4.0, 8.0], 0.3)


def test_inside_is_never_moved_and_clearly_inside_is_above_two_pi():
    body = Body((0.26, 0.55, 0.793662))
    assert body.moments.tolist() == [0.26, 0.55, 0.793662] and not body.is_flat
    # eqn:alphamin1 > 2 pi strictly inside: the minimum is the end value
    low = check_never_below_two_pi(body)
    assert low > TWO_PI * (1 + 1e-3)
    assert low == pytest.approx(orbits.phase_limits(body).theta_zero, rel=1e-12)


@settings(max_examples=150, deadline=None)
@given(a=st.floats(1e-6, 1.0), ratio=st.floats(1.0, 1e6), scale=st.integers(-900, 900))
@example(a=0.9999999999999999, ratio=1.0000000000000002, scale=0)  # no exact move: refused
def test_bodies_built_as_a_b_a_plus_b(a, ratio, scale):
    """(a, b, fl(a + b)) in floating point: rounding puts it on either side."""
    b = a * ratio
    moments = np.ldexp([a, b, a + b], scale)
    try:
        body = Body(moments)
    except orbits.SymmetricTopError:
        assert a == b or a + b == b
        return
    except orbits.NonPhysicalBodyError as error:
        # allowed only within the slack and when no single-moment move onto the
        # edge is exact and keeps I1 < I2 < I3 (e.g. (1 - 2^-53, 1, 2))
        assert "no body on the edge" in str(error)
        i1, i2, i3 = (Fraction(float(v)) for v in np.sort(moments))
        excess = i3 - i1 - i2
        assert 0 < excess <= Fraction(8 * EPS) * i3
        for new, order in (
            (i1 + i2, lambda x: i2 < x),
            (i3 - i2, lambda x: 0 < x < i2),
            (i3 - i1, lambda x: i1 < x < i3),
        ):
            assert Fraction(float(new)) != new or not order(new)
        return
    excess = exact_excess(moments)
    assert exact_excess(body.moments) <= 0
    assert body.is_flat == (excess >= 0)
    moved = [
        Fraction(float(x)) - Fraction(float(y)) for x, y in zip(body.moments, np.sort(moments))
    ]
    if excess > 0:
        # exactly one moment moved, by exactly the excess (<= 8 eps I3)
        assert sum(d != 0 for d in moved) == 1
        assert abs(sum(moved)) == excess
        assert excess <= Fraction(8 * EPS) * Fraction(float(np.max(moments)))
    else:
        assert not any(moved)
    low = check_never_below_two_pi(body)
    if body.is_flat:
        # 2 pi at theta -> 0, to the rounding of the closed form there
        assert low <= TWO_PI * (1 + 1e-14)


@settings(max_examples=60, deadline=None)
@given(exponent=st.floats(1.0, 300.0), ulps=st.integers(1, 40), scale=st.integers(-900, 900))
def test_rods_down_to_1e_minus_300(exponent, ulps, scale):
    """I1/I3 = 10^-exponent, I3 - I2 = ulps * 2^-53: accepted (then on or
    inside the edge, with phases >= 2 pi) or rejected as non-physical."""
    i1 = 10.0**-exponent
    moments = np.ldexp([i1, 1.0 - ulps * 2.0**-53, 1.0], scale)
    assume(moments[0] >= np.finfo(float).tiny)  # the scaled I1 still a normal double
    excess = exact_excess(moments)
    try:
        body = Body(moments)
    except orbits.NonPhysicalBodyError as error:
        assert excess > Fraction(8 * EPS) * Fraction(float(moments[2]))
        assert "triangle" in str(error)
        return
    except orbits.SymmetricTopError:
        # two moments equal, or equal once scaled to |I| = 1 (the catalog's
        # columns; computed on the power-of-two scaled moments, no overflow)
        ordered = np.sort(moments)
        unit = np.ldexp(ordered, -np.frexp(ordered[2])[1])
        unit = unit / math.sqrt((unit[0] ** 2 + unit[1] ** 2) + unit[2] ** 2)
        assert any(v[0] == v[1] or v[1] == v[2] for v in (ordered, unit))
        return
    assert exact_excess(body.moments) <= 0
    assert body.is_flat == (excess >= 0)
    check_never_below_two_pi(body)


def test_thin_flat_rod_matches_the_exact_rod_of_ratio_1e_minus_300():
    """(1e-300, 1 - 2^-53, 1) is computed as the flat rod (2^-53, 1 - 2^-53, 1);
    its phase is that of the exact flat rod I1/I3 = 1e-300 to 1e-14 (the
    library's accuracy; mpmath at 340 digits, theta away from theta_crit ~ pi/4)."""
    with mp.workdps(340):
        i1, i2 = mp.mpf(10) ** -300, mp.mpf(1)
        i3 = i1 + i2
        for theta in (0.3, 0.7, 1.2, 1.5):
            t = mp.mpf(theta)
            w1, w3 = mp.sin(t), mp.cos(t)
            two_e = i1 * w1**2 + i3 * w3**2
            m_sq = i1**2 * w1**2 + i3**2 * w3**2
            exact = float(period_and_total_phase(i1, i2, i3, two_e, m_sq)[1])
            got = float(orbits.total_phase([1e-300, 1 - 2.0**-53, 1.0], theta))
            assert abs(got / exact - 1) <= 1e-14  # measured 2.2e-16


def test_canonical_form_is_vectorised_and_exact():
    rows = np.array([[0.3, 0.6, 0.9], [0.26, 0.55, 0.793662], [0.1, 0.2, 0.1 + 0.2]])
    unit, exponent = canonical_moments(rows)
    for k in range(3):
        single, e = canonical_moments(rows[k])
        assert np.array_equal(single, unit[k]) and e == exponent[k]
        assert exact_excess(unit[k]) <= 0


def test_survey_of_flat_bodies_reports_no_two_pi_orbit():
    moments = np.array(
        [
            [0.3, 0.6, 0.9],
            [0.1, 0.2, 0.1 + 0.2],
            [2.0**-53, 1 - 2.0**-53, 1.0],
            [0.26, 0.55, 0.793662],
        ]
    )
    bodies, table = compute_chunk(moments, 4, q_max=3)
    assert (bodies["min_total_phase"] >= TWO_PI).all()
    assert bodies["min_at_end"].all()
    assert (table["n"] > table["q"]).all()
    assert (bodies["n_smallest"] != 1).all()


def test_a_rod_thinner_than_rounding_says_that_its_i1_was_moved():
    """spin_phases([1e-20, 1 - 2**-53, 1], [1, 0, 0]) reported I1, E, M and D
    11,000 times those of the moments given, with no word."""
    import warnings

    with pytest.warns(orbits.InertialDefectWarning, match="I1 9.99.*e-21 became 1.11.*e-16"):
        table = orbits.spin_phases([1e-20, 1 - 2**-53, 1.0], [1.0, 0.0, 0.0])
    assert table["I1"].iloc[0] == 2.0**-53  # the moved body, as the warning says
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        orbits.Body([0.3, 0.6, 0.9])  # moved by one rounding: no warning


def test_the_flat_edge_warning_points_at_the_callers_line_and_never_overflows():
    """stacklevel=4 pointed into orbits/phases.py for spin_phases and
    total_phase; a unit I1 that underflowed gave 'became inf, inf of itself'
    and two RuntimeWarnings (errors in this suite)."""
    import warnings

    rod = (1e-20, 1 - 2**-53, 1.0)
    calls = [
        lambda: orbits.Body(rod),
        lambda: orbits.spin_phases(rod, [1.0, 0.0, 0.0]),
        lambda: orbits.total_phase(rod, 0.3),
        lambda: orbits.Motion(rod, [1.0, 0.0, 1.0]),
    ]
    for call in calls:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            call()
        (warning,) = [w for w in caught if issubclass(w.category, orbits.InertialDefectWarning)]
        assert warning.filename == __file__
    with pytest.warns(
        orbits.InertialDefectWarning, match="became 1.48701690847778..e\\+284, by far"
    ):
        orbits.Body((1e-300, 9.999999999999999e299, 1e300))


def test_catalog_verify_of_a_moved_rod_warns_once(tmp_path, capsys):
    """The closure check warned again about the catalog's own |I| = 1
    moments ('0.41 of itself'), which describe the same moved body."""
    from orbits.cli import main

    argv = ["catalog", "--moments", "1e-20", "0.99999999999999989", "1", "--n-max", "4"]
    assert main(argv + ["--verify", "--out", str(tmp_path / "rod.csv")]) == 0
    err = capsys.readouterr().err
    warned = [line for line in err.splitlines() if "flat edge by rounding" in line]
    assert len(warned) == 1 and "1.1e+04 of itself" in warned[0]


def test_a_moved_rod_is_named_by_its_place_among_all_bodies():
    """The warning counted within the bodies beyond the edge: the third of
    three bodies was named without any place (it was the only one moved),
    and the first of several as "#0"."""
    rods = [[1.0, 2.0, 2.5], [1.0, 2.0, 2.6], [1e-300, 1 - 2**-53, 1.0]]
    with pytest.warns(
        orbits.InertialDefectWarning, match=r"\(body 3 of 3\) lie beyond the flat edge"
    ):
        orbits.total_phase(rods, 0.3)
    with pytest.raises(orbits.SymmetricTopError, match=r"\(body 1 of 2\)"):
        orbits.total_phase([[1.0, 1.0, 1.5], [1.0, 2.0, 2.5]], 0.3)


def test_the_first_exact_move_onto_the_edge_is_taken():
    """I3 <- I1 + I2 first, then I1 <- I3 - I2, then I2 <- I3 - I1 (each
    exact): (0.25, 0.5, 0.75 + ulp) becomes (0.25, 0.5, 0.75); the other
    order gave (0.25 + ulp, 0.5, 0.75 + ulp), a body 2e-15 off in phase."""
    body = Body((0.25, 0.5, np.nextafter(0.75, 1.0)))
    assert body.moments.tolist() == [0.25, 0.5, 0.75]
