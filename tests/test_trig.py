"""Polynomial sin/cos (orbits.core.trig) against mpmath."""

import math

import mpmath as mp
import numpy as np

from orbits.core.trig import SINCOS_LIMIT, cos_small, sin_small, sincos


def ulps(value, exact):
    exact = float(exact)
    return abs(value - exact) / np.spacing(max(abs(exact), 1e-300))


def test_sincos_within_4_ulps_of_mpmath():
    rng = np.random.default_rng(7)
    xs = np.concatenate(
        [
            rng.uniform(-10.0, 10.0, 3000),
            rng.uniform(-SINCOS_LIMIT, SINCOS_LIMIT, 3000),
            np.arange(-40, 41) * (math.pi / 4),  # near the quadrant boundaries and zeros
            np.nextafter(np.arange(1, 30) * (math.pi / 2), np.inf),
            [0.0, -0.0, 1e-300, -5e-324, 0.785398, SINCOS_LIMIT, -SINCOS_LIMIT],
        ]
    )
    worst = 0.0
    with mp.workdps(40):
        for x in xs:
            s, c = sincos(float(x))
            worst = max(
                worst, ulps(s, mp.sin(mp.mpf(float(x)))), ulps(c, mp.cos(mp.mpf(float(x))))
            )
    assert worst <= 4.0, worst


def test_sincos_beyond_the_limit_is_libm():
    for x in (SINCOS_LIMIT * 1.5, -1e10, 1e300):
        assert sincos(x) == (math.sin(x), math.cos(x))
    s, c = sincos(math.inf)
    assert math.isnan(s) and math.isnan(c)
    s, c = sincos(math.nan)
    assert math.isnan(s) and math.isnan(c)


def test_small_polynomials_within_two_ulps_on_their_range():
    """The SIMD phase set-up's sin/cos on [-pi/4, pi/4] (and tiny arguments)."""
    x = np.concatenate(
        [np.linspace(-math.pi / 4, math.pi / 4, 2001), np.geomspace(1e-300, math.pi / 4, 500)]
    )
    with mp.workdps(40):
        for value in x:
            assert ulps(sin_small(value), mp.sin(mp.mpf(value))) <= 2.0
            assert ulps(cos_small(value), mp.cos(mp.mpf(value))) <= 2.0


# ------------------------------------------------------------------------
# Each test below kills a mutant of orbits/core/angles.py that passed the suite (a
# mutation audit of the core kernels, 2026-11-29: 49 mutants, 11 survivors
# that changed an output).

EPS = np.finfo(float).eps


def test_fold_angle_folds_values_just_above_pi_over_2():
    """A4: all_folded must test against pi/2 exactly (mutant: a slightly larger
    bound, 1.5708, which returns 1.5708 unfolded).  Reference: mpmath."""
    import mpmath as mp

    from orbits.core.angles import all_folded
    from orbits.phases import fold_angle

    given = np.array([1.5708, 0.5 * math.pi + 1e-9, 1.0])
    got = fold_angle(given)
    with mp.workdps(40):
        exact = [float(mp.pi - mp.mpf(x)) for x in given[:2]] + [1.0]
    np.testing.assert_allclose(got, exact, rtol=0, atol=2 * EPS)
    assert (got <= 0.5 * math.pi).all()
    assert not all_folded(np.array([0.5 * math.pi + 1e-9]))
    assert all_folded(np.array([0.0, 0.5 * math.pi]))
