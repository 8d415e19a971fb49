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
