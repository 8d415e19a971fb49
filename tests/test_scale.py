"""Moment scale: every entry point is scale-free (issue 9, item 2).

The moments are normalised by an exact power of two at the boundary
(orbits.bodies.canonical_moments), so a power-of-two scale gives bit-identical
results, and any other factor only the rounding of the scaled moments
(relative 1/2 ulp each), amplified by the conditioning of the body.
"""

import math

import mpmath as mp
import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from mp_formulas import period_and_total_phase

import orbits
from orbits.bodies import Body, region_sample
from orbits.cli import main
from orbits.survey import compute_chunk

EPS = np.finfo(float).eps
FIG6 = np.array([0.26, 0.55, 0.793662])
T_HANDLE = Body.t_handle(8.0, 4.0, 1.0).moments


def mp_total_phase(moments, theta, dps=50):
    """eqn:GeometricPhase in mpmath for the exact double moments (phi = 0)."""
    with mp.workdps(dps):
        i1, i2, i3 = (mp.mpf(float(v)) for v in sorted(moments))
        w1, w3 = mp.sin(theta), mp.cos(theta)
        two_e = i1 * w1**2 + i3 * w3**2
        m_sq = i1**2 * w1**2 + i3**2 * w3**2
        return float(period_and_total_phase(i1, i2, i3, two_e, m_sq)[1])


# ---------------------------------------------------------------- the issue
@pytest.mark.parametrize("factor", [1e78, 1e-80, 1e-90, 1e-150, 1e150, 1e300, 1e-300])
def test_fig6_at_any_scale_matches_mpmath(factor):
    """Was NaN (1e78), 4.6e-3 off (1e-80), SystemError (1e-150)."""
    scaled = FIG6 * factor
    got = float(orbits.total_phase(scaled, 0.5))
    expected = mp_total_phase(scaled, mp.mpf(0.5))
    assert abs(got / expected - 1) <= 1e-14
    assert abs(got / float(orbits.total_phase(FIG6, 0.5)) - 1) <= 1e-14


def test_cli_catalog_at_1e150_is_the_unscaled_catalog(tmp_path):
    """Was an empty catalog with exit code 0."""
    small, large = tmp_path / "small.csv", tmp_path / "large.csv"
    assert (
        main(
            [
                "catalog",
                "--moments",
                "0.26",
                "0.55",
                "0.793662",
                "--n-max",
                "5",
                "--out",
                str(small),
            ]
        )
        == 0
    )
    assert (
        main(
            [
                "catalog",
                "--moments",
                "0.26e150",
                "0.55e150",
                "0.793662e150",
                "--n-max",
                "5",
                "--out",
                str(large),
            ]
        )
        == 0
    )
    a, b = orbits.read_catalog(small), orbits.read_catalog(large)
    assert len(a) == 8
    columns = [c for c in orbits.CATALOG_COLUMNS if c != "body"]
    # 0.26e150 is not 0.26 * 1e150 exactly: the bodies differ by rounding
    assert (a[["branch", "n", "q"]] == b[["branch", "n", "q"]]).all().all()
    floats = [c for c in columns if a[c].dtype.kind == "f" and c != "residual"]
    np.testing.assert_allclose(b[floats], a[floats], rtol=1e-13, atol=0)


# ------------------------------------------------------- powers of two: exact
bodies = st.sampled_from(
    [
        FIG6,
        T_HANDLE,
        np.array([1.0, 1.0 + 2**-40, 1.0 + 2**-39]),
        np.array([0.1, 0.2, 0.3]),
        np.array([2.0**-50, 1.0, 1.0 + 2**-52]),
    ]
    + [region_sample(40)[k] for k in range(0, 40, 4)]
)
exponents = st.integers(-990, 990)


@settings(max_examples=60, deadline=None)
@given(body=bodies, k=exponents)
# found in CI: I1 = 2^-50 scaled to 2^-1023, an exact subnormal moment
@example(body=np.array([2.0**-50, 1.0, 1.0 + 2.0**-52]), k=-973)
def test_power_of_two_scale_is_bit_identical(body, k):
    scaled = np.ldexp(body, k)
    theta_c = orbits.critical_angle(body)
    assert orbits.critical_angle(scaled) == theta_c
    offsets = np.array(
        [
            -theta_c,
            -0.3 * theta_c,
            -1e-9,
            -1e-300,
            1e-300,
            1e-7,
            0.5 * (math.pi / 2 - theta_c),
            math.pi / 2 - theta_c,
        ]
    )
    a = orbits.phases(body, dtheta=offsets)
    b = orbits.phases(scaled, dtheta=offsets)
    for column in (
        "theta",
        "theta_crit",
        "energy",
        "momentum",
        "m",
        "period",
        "dynamic_phase",
        "total_phase",
        "geometric_phase",
        "I1",
        "I2",
        "I3",
    ):
        assert np.array_equal(a[column].to_numpy(), b[column].to_numpy()), column
    assert np.all(np.isfinite(a[["total_phase", "period"]].to_numpy()))
    np.testing.assert_array_equal(
        orbits.total_phase(scaled, [0.1, 1.2]), orbits.total_phase(body, [0.1, 1.2])
    )
    # the physical motion: E and M scale with the moments, T not at all
    m0, m1 = (orbits.Motion.from_spin(b_, dtheta=-0.3 * theta_c) for b_ in (body, scaled))
    assert m1.energy == math.ldexp(m0.energy, k)
    assert m1.momentum == math.ldexp(m0.momentum, k)
    assert m1.period == m0.period and m1.total_phase() == m0.total_phase()


@settings(max_examples=25, deadline=None)
@given(body=bodies, k=exponents)
def test_power_of_two_scale_gives_the_same_catalog(body, k):
    a = orbits.closed_orbits(body, n_max=6, q_max=2)
    b = orbits.closed_orbits(np.ldexp(body, k), n_max=6, q_max=2)
    columns = [c for c in orbits.CATALOG_COLUMNS if c != "body"]
    assert a[columns].equals(b[columns])
    assert orbits.minimum_phase(body) == orbits.minimum_phase(np.ldexp(body, k))


def test_survey_chunk_is_scale_free():
    moments = region_sample(30)
    scale = np.ldexp(1.0, np.arange(-900, 900, 60))[:, None]
    a_bodies, a_orbits = compute_chunk(moments, 5)
    b_bodies, b_orbits = compute_chunk(moments * scale, 5)
    assert a_bodies.equals(b_bodies) and a_orbits.equals(b_orbits)
    assert np.all(b_bodies["min_total_phase"] >= 2 * math.pi)


# ----------------------------------------------------------- any other factor
@settings(max_examples=80, deadline=None)
@given(
    index=st.integers(0, 199), exponent=st.floats(-300.0, 300.0), fraction=st.floats(1e-3, 0.999)
)
def test_arbitrary_factor_within_the_conditioning(index, exponent, fraction):
    """A factor f in [1e-300, 1e300] rounds each moment by <= eps/2.

    Bound: |rel. change| <= 8 eps I3 / min(I2 - I1, I3 - I2), the
    conditioning of the body to a relative perturbation of its moments
    (measured worst: 2.1 eps I3 / min gap over 1000 bodies of the region).
    """
    body = region_sample(200)[index]
    factor = 10.0**exponent
    theta_c = orbits.critical_angle(body)
    offsets = np.array([-fraction * theta_c, fraction * (math.pi / 2 - theta_c)])
    offsets = offsets[np.abs(offsets) >= 1e-6]
    cond = body[2] / min(body[1] - body[0], body[2] - body[1])
    a = orbits.total_phase(body, dtheta=offsets)
    b = orbits.total_phase(body * factor, dtheta=offsets)
    assert np.all(np.abs(b / a - 1) <= 8 * EPS * cond)
    assert abs(orbits.critical_angle(body * factor) / theta_c - 1) <= 8 * EPS * cond


def test_spin_magnitude_is_scale_free():
    """|omega| from 2^-1000 to 2^1000: phases unchanged, E, M, T rescaled exactly."""
    body = Body(FIG6)
    base = orbits.spin_phases(body, [0.3, 0.2, 0.9]).iloc[0]
    for k in (-500, -100, 100, 500):
        row = orbits.spin_phases(body, np.ldexp([0.3, 0.2, 0.9], k)).iloc[0]
        assert row["total_phase"] == base["total_phase"]
        assert row["energy"] == math.ldexp(base["energy"], 2 * k)
        assert row["momentum"] == math.ldexp(base["momentum"], k)
        assert row["period"] == math.ldexp(base["period"], -k)
    with pytest.raises(orbits.InputError, match="energy"):
        orbits.spin_phases(body, [1e-200] * 3)  # E ~ 1e-400: not a double
