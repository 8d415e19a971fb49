"""Elliptic kernels against mpmath at working precision scaled to kc.

Every reference argument is wrapped in ``mpf`` before any arithmetic: a
reference that forms ``b - a*p`` in doubles is itself wrong at 1e-13.
"""

import math

import mpmath as mp
import numpy as np
import pytest

from orbits.core import elliptic as ek

EPS = np.finfo(float).eps


def mp_cel(kc, p, a, b):
    """cel via K and Pi: a K + (b - a p)(Pi(1-p|m) - K)/(1-p)."""
    kc, p, a, b = (mp.mpf(float(v)) for v in (kc, p, a, b))
    m = 1 - kc**2
    n = 1 - p
    k = mp.ellipk(m)
    if n == 0:
        return b * k if a == b else a * k + (b - a) * (mp.ellipe(m) - kc**2 * k) / m
    return a * k + (b - a * p) * (mp.ellippi(n, m) - k) / n


def dps_for(kc):
    return 30 + int(2 * abs(math.log10(kc)))


def rel_err(value, ref):
    return abs(float((mp.mpf(float(value)) - ref) / ref))


@pytest.fixture(scope="module")
def rng():
    return np.random.default_rng(12345)


def test_cel_accuracy_including_kc_to_1e_minus_150(rng):
    worst = 0.0
    for i in range(300):
        kc = 10.0 ** rng.uniform(-150, 0) if i % 2 else rng.uniform(1e-3, 1.0)
        p = 10.0 ** rng.uniform(-3, 3)
        a, b = rng.uniform(0.05, 3.0, 2)
        with mp.workdps(dps_for(kc)):
            worst = max(worst, rel_err(ek.cel(kc, p, a, b), mp_cel(kc, p, a, b)))
    assert worst <= 8 * EPS


def test_cel_pair_equals_two_cels(rng):
    for _ in range(100):
        kc = 10.0 ** rng.uniform(-50, 0)
        p = 10.0 ** rng.uniform(-2, 2)
        a1, b1, a2, b2 = rng.uniform(0.1, 2.0, 4)
        first, second = ek.cel_pair(kc, p, a1, b1, a2, b2)
        assert first == pytest.approx(ek.cel(kc, p, a1, b1), rel=2 * EPS)
        assert second == pytest.approx(ek.cel(kc, p, a2, b2), rel=2 * EPS)


def test_cel_special_cases():
    # K(0) = pi/2 and Pi(n|0) = pi / (2 sqrt(1-n)) (DLMF 19.6.1, 19.6.3)
    assert ek.cel(1.0, 1.0, 1.0, 1.0) == pytest.approx(math.pi / 2, rel=EPS)
    assert ek.cel(1.0, 5.0, 1.0, 1.0) == pytest.approx(math.pi / (2 * math.sqrt(5.0)), rel=2 * EPS)
    assert math.isnan(ek.cel(0.0, 1.0, 1.0, 1.0))
    assert math.isnan(ek.cel(0.5, -1.0, 1.0, 1.0))


def test_ellipk_from_kc(rng):
    for _ in range(100):
        kc = 10.0 ** rng.uniform(-150, 0)
        with mp.workdps(dps_for(kc)):
            ref = mp.ellipk(1 - mp.mpf(kc) ** 2)
            assert rel_err(ek.ellipk_kc(kc), ref) <= 4 * EPS


def test_carlson_rf_rj_rc(rng):
    for _ in range(200):
        x, y, z = rng.uniform(0.0, 3.0, 3)
        p = 10.0 ** rng.uniform(-2, 2)
        assert rel_err(ek.carlson_rf(x, y, z), mp.elliprf(x, y, z)) <= 8 * EPS
        assert rel_err(ek.carlson_rj(x, y, z, p), mp.elliprj(x, y, z, p)) <= 16 * EPS
        assert rel_err(ek.carlson_rc(x + 0.01, p), mp.elliprc(x + 0.01, p)) <= 8 * EPS
    # the series branch of R_C around x = y
    assert rel_err(ek.carlson_rc(1.0, 1.0 + 1e-9), mp.elliprc(1, 1 + mp.mpf(1e-9))) <= 4 * EPS
    assert rel_err(ek.carlson_rc(1.0, 1.0 - 1e-9), mp.elliprc(1, 1 - mp.mpf(1e-9))) <= 4 * EPS


def test_complete_pi_from_carlson(rng):
    worst = 0.0
    for _ in range(200):
        kc = 10.0 ** rng.uniform(-20, 0)
        n = -(10.0 ** rng.uniform(-3, 2))
        with mp.workdps(dps_for(kc)):
            ref = mp.ellippi(mp.mpf(n), 1 - mp.mpf(kc) ** 2)
            worst = max(worst, rel_err(ek.ellippi_complete_carlson(n, kc), ref))
    # R_F + (n/3) R_J cancels when n << 0: the loss is about |n| eps
    assert worst <= 100 * 16 * EPS


def test_incomplete_f_any_amplitude(rng):
    for _ in range(200):
        kc = 10.0 ** rng.uniform(-12, 0)
        phi = rng.uniform(-12.0, 12.0)
        with mp.workdps(dps_for(kc)):
            ref = mp.ellipf(mp.mpf(phi), 1 - mp.mpf(kc) ** 2)
            assert abs(float(ek.ellipf_kc(phi, kc) - ref)) <= 16 * EPS * max(1.0, abs(float(ref)))


@pytest.mark.parametrize("one_minus_m", [0.7, 1e-3, 1e-8, 1e-12])
def test_jacobi_functions_near_m_one(rng, one_minus_m):
    """sn, cn, dn to absolute 1e-13 over ten periods, down to 1 - m = 1e-12."""
    kc = math.sqrt(one_minus_m)
    quarter = ek.ellipk_kc(kc)
    with mp.workdps(40):
        m = 1 - mp.mpf(kc) ** 2
        for u in rng.uniform(-40 * quarter, 40 * quarter, 40):
            am, sn, cn, dn, j, r = ek.jacobi_amplitude(u, kc)
            assert abs(sn - float(mp.ellipfun("sn", u, m=m))) <= 1e-13
            assert abs(cn - float(mp.ellipfun("cn", u, m=m))) <= 1e-13
            assert abs(dn - float(mp.ellipfun("dn", u, m=m))) <= 1e-13
            # am is continuous and equals atan2(sn, cn) up to whole turns
            principal = float(mp.atan2(mp.ellipfun("sn", u, m=m), mp.ellipfun("cn", u, m=m)))
            turns = round((am - principal) / (2 * math.pi))
            assert abs(am - principal - 2 * math.pi * turns) <= 1e-13 * max(1.0, abs(am))
            assert j == round(am / math.pi)
            assert abs(r) <= quarter * (1 + 1e-15)
