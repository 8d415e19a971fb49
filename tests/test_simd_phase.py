"""The SIMD total phase (fixed-pass ``cel`` over lanes) against the scalar path."""

import math
import os
import platform
import re
from pathlib import Path

import mpmath as mp
import numba
import numpy as np
import pandas as pd
import pytest
from mp_formulas import period_and_total_phase
from numba import njit

import orbits
from orbits.atomic import csv_float_options
from orbits.bodies import canonical_moments
from orbits.core import elliptic
from orbits.core import phase as kernels
from orbits.phases import fold_angle

REFERENCE = Path(__file__).parent / "reference" / "phase_reference.csv"


def test_pass_count_is_monotone_in_kc():
    """The proof behind one pass count per batch: fewer passes for larger kc."""
    kc = np.geomspace(1e-300, 1.0, 4000)
    passes = np.array([elliptic.cel_passes(k) for k in kc])
    assert np.all(np.diff(passes) <= 0)
    assert passes[0] == 13 and passes[-1] == 1


def _lanes(kc, p, a, b, passes):
    n = kc.size
    out = np.empty(n)
    scratch = [np.empty(n) for _ in range(3)]
    elliptic.cel_lanes(kc.copy(), p.copy(), a.copy(), b.copy(), out, n, passes, *scratch)
    return out


def test_cel_lanes_matches_cel():
    """Every lane, with the batch's pass count, agrees with the looping ``cel``.

    The scale is ``cel`` with ``|a|, |b|`` (the integral of the absolute
    integrand), so cancellation in ``a, b`` of mixed sign is not counted.
    """
    rng = np.random.default_rng(7)
    n = 20_000
    kc = 10.0 ** rng.uniform(-160.0, 0.0, n)
    kc[:2000] = rng.uniform(0.0, 1.0, 2000)
    p = 10.0 ** rng.uniform(-8.0, 8.0, n)
    a = rng.uniform(-2.0, 2.0, n)
    b = rng.uniform(-2.0, 2.0, n)
    want = np.array([elliptic.cel(*args) for args in zip(kc, p, a, b)])
    scale = np.array([elliptic.cel(k, q, abs(x), abs(y)) for k, q, x, y in zip(kc, p, a, b)])
    for passes in (elliptic.cel_passes(kc.min()), 20):
        got = _lanes(kc, p, a, b, passes)
        assert np.max(np.abs(got - want) / scale) <= 4e-15
    # a batch of large kc only: few passes, same values
    big = kc > 0.5
    got = _lanes(kc[big], p[big], a[big], b[big], elliptic.cel_passes(kc[big].min()))
    assert np.max(np.abs(got - want[big]) / scale[big]) <= 4e-15


def _scalar(moments, angle, phi, from_offset):
    n = angle.size
    out = np.empty(n)
    status = np.empty(n, np.int8)
    kernels.total_phase_many_scalar(
        *(np.ascontiguousarray(moments[:, k]) for k in range(3)),
        phi,
        angle,
        from_offset,
        out,
        status,
    )
    return out, status


@pytest.mark.parametrize("from_offset", [False, True])
def test_simd_path_matches_scalar_path(from_offset):
    """Many bodies, theta over [0, pi/2] or dtheta down to 1e-300, any phi."""
    rng = np.random.default_rng(3)
    n = 30_000
    moments = np.sort(rng.uniform(0.05, 1.0, (n, 3)), axis=1)
    moments[:, 2] = np.minimum(moments[:, 2], 0.999 * (moments[:, 0] + moments[:, 1]))
    moments = moments[(moments[:, 1] < moments[:, 2]) & (moments[:, 0] < moments[:, 1])]
    n = moments.shape[0]
    phi = rng.uniform(0.0, 2 * math.pi, n)
    if from_offset:
        theta_c = orbits.critical_angle(moments, phi)
        sign = np.where(rng.uniform(size=n) < 0.5, -1.0, 1.0)
        width = np.where(sign < 0, theta_c, math.pi / 2 - theta_c)
        angle = sign * width * 10.0 ** rng.uniform(-300.0, 0.0, n)
    else:
        angle = rng.uniform(0.0, math.pi / 2, n)
    # the same input on both paths: total_phase hands the kernels the exact
    # power-of-two normalisation of the moments (orbits.bodies.canonical_moments)
    # and the azimuth folded into [0, pi/2] (orbits.phases.fold_angle): near the
    # separatrix the theta path is ill-conditioned in phi, so the unfolded phi
    # (the same spin to an ulp) would differ by more than the paths do
    moments, _ = canonical_moments(moments)
    phi = fold_angle(phi)
    want, status = _scalar(moments, angle, phi, from_offset)
    assert (status == 0).all()
    kw = {"dtheta": angle} if from_offset else {"theta": angle}
    got = orbits.total_phase(moments, phi=phi, **kw)
    assert np.max(np.abs(got / want - 1)) <= 1e-14
    # one body, the per-body kernel (its own SIMD set-up)
    one = moments[0]
    if from_offset:
        theta_c = float(orbits.critical_angle(one, phi[0]))
        sign = np.where(rng.uniform(size=n) < 0.5, -1.0, 1.0)
        width = np.where(sign < 0, theta_c, math.pi / 2 - theta_c)
        angle = sign * width * 10.0 ** rng.uniform(-300.0, 0.0, n)
    kw1 = {"dtheta": angle} if from_offset else {"theta": angle}
    got1 = orbits.total_phase(one, phi=phi[0], **kw1)
    want1, _ = _scalar(np.tile(one, (n, 1)), angle, np.full(n, phi[0]), from_offset)
    again = np.empty(n)
    kernels.total_phase_one_body_scalar(
        *one, phi[0], angle, from_offset, again, np.empty(n, np.int8)
    )
    assert np.array_equal(again, want1)
    assert np.max(np.abs(got1 / want1 - 1)) <= 1e-14


def test_simd_path_against_mpmath_reference():
    """The reference table (mpmath), dtheta rows, through ``total_phase``: 1e-13."""
    rows = pd.read_csv(REFERENCE, comment="#", **csv_float_options())
    rows = rows[rows["mode"] == "dtheta"]
    got = orbits.total_phase(
        rows[["m1", "m2", "m3"]].to_numpy(),
        dtheta=rows["dtheta"].to_numpy(),
        phi=rows["phi"].to_numpy(),
    )
    error = np.abs(got / rows["total_phase"].to_numpy() - 1)
    assert error.max() <= 1e-13
    assert rows["dtheta"].abs().min() < 1e-250


def test_separatrix_and_edges_in_a_batch():
    """Off-domain lanes do not disturb their neighbours in the batch."""
    body = orbits.Body((0.26, 0.55, 0.793662))
    theta_c = float(orbits.critical_angle(body))
    theta = np.linspace(0.0, math.pi / 2, 1001)
    assert np.all(np.isfinite(orbits.total_phase(body, theta)))
    with pytest.raises(orbits.SeparatrixError):
        orbits.total_phase(body, np.concatenate([theta, [theta_c]]))


@pytest.mark.skipif(platform.machine() not in ("x86_64", "AMD64"), reason="x86 only")
@pytest.mark.skipif(
    tuple(int(v) for v in numba.__version__.split(".")[:2]) < (0, 68),
    reason="vectorisation checked with numba 0.68.1; numba 0.60.0 leaves this loop "
    "scalar: the same results, only slower",
)
@pytest.mark.skipif(
    os.environ.get("NUMBA_CPU_NAME", "host") != "host",
    reason="vector width is checked for the host CPU; a generic CPU (NUMBA_CPU_NAME) "
    "is checked for results only",
)
def test_llvm_emits_packed_sqrt_and_division():
    """The lane loop is vectorised: packed sqrt/div (SSE2 at least, ymm with AVX2)."""
    fresh = njit(error_model="numpy")(elliptic.cel_lanes.py_func)
    arrays = [np.ones(8) for _ in range(8)]
    fresh(*arrays[:5], 8, 2, *arrays[5:])
    asm = "\n".join(fresh.inspect_asm().values())
    assert re.search(r"\bv?sqrtpd\b", asm)
    assert re.search(r"\bv?divpd\b", asm)


def test_one_body_simd_path_against_mpmath_reference():
    """Per-body calls (the one-body SIMD set-up) on the reference table.

    dtheta rows: 1e-13.  theta rows: 1e-13 plus the conditioning of theta
    itself, as in test_phases (theta_c is known to a few ulps only).
    """
    rows = pd.read_csv(REFERENCE, comment="#", **csv_float_options())
    checked = 0
    for (m1, m2, m3, phi, mode), group in rows.groupby(["m1", "m2", "m3", "phi", "mode"]):
        body = orbits.Body((m1, m2, m3))
        expected = group["total_phase"].to_numpy()
        if mode == "dtheta":
            got = orbits.total_phase(body, dtheta=group["dtheta"].to_numpy(), phi=phi)
            assert np.all(np.abs(got / expected - 1) <= 1e-13)
        else:
            got = orbits.total_phase(body, group["theta"].to_numpy(), phi=phi)
            theta_c = float(orbits.critical_angle(body, phi))
            ulp = np.spacing(min(theta_c, math.pi / 2 - theta_c))
            bound = 1e-13 + np.abs(group["dalpha_dtheta"].to_numpy()) * 4 * ulp / np.abs(expected)
            assert np.all(np.abs(got / expected - 1) <= bound)
        checked += len(group)
    assert checked == len(rows)


@pytest.mark.parametrize(
    "moments",
    [(0.5, 0.500001, 1.0), (0.3, 0.3 + 1e-9, 0.5), (0.2, 0.999999, 1.0), (0.6, 0.9 - 1e-9, 0.9)],
    ids=["oblate", "oblate-1e-9", "prolate", "prolate-1e-9"],
)
@pytest.mark.parametrize("phi", [0.0, 0.4, 1.0])
def test_simd_path_on_the_far_half_of_a_wide_branch(moments, phi):
    """Offsets beyond pi/4 from theta_c, batched: theta_c next to pi/2 (an
    oblate body: SAM spans nearly all of [0, pi/2]) or next to 0 (prolate:
    LAM does).  There |sin dtheta| is formed as the cosine of pi/2 - |dtheta|;
    the random bodies of the tests above almost never have such a branch, and
    a batch path taking the sine's series up to pi/2 was 2.2e-14 off here
    (against <= 1e-15 for the scalar path and mpmath)."""
    theta_c = float(orbits.critical_angle(moments, phi))
    width = max(theta_c, math.pi / 2 - theta_c)
    assert width > 1.5  # a branch nearly pi/2 wide
    sign = -1.0 if theta_c > math.pi / 4 else 1.0
    fractions = np.array([0.5, 0.6, 0.8, 0.9, 0.99, 0.999, 1 - 1e-6, 1 - 1e-12, 1.0])
    dtheta = sign * width * fractions
    # the same input on both paths (see test_simd_path_matches_scalar_path)
    unit, _ = canonical_moments(np.array(moments))
    batch = np.tile(unit, (dtheta.size, 1))
    want, status = _scalar(batch, dtheta, np.full(dtheta.size, fold_angle(phi)), True)
    assert (status == 0).all()
    got = orbits.total_phase(batch, dtheta=dtheta, phi=phi)
    assert np.max(np.abs(got / want - 1)) <= 2e-15
    # one body: the per-body kernel, its own SIMD set-up
    got = orbits.total_phase(unit, dtheta=dtheta, phi=phi)
    assert np.max(np.abs(got / want - 1)) <= 2e-15
    # and against the paper's formula in mpmath, from the spin (theta, phi)
    # that the offset names (theta_c + dtheta rounded: the theta path)
    theta = np.array([theta_c + d for d in dtheta])
    got_theta = np.concatenate(
        [orbits.total_phase(batch, theta, phi=phi), orbits.total_phase(unit, theta, phi=phi)]
    )
    with mp.workdps(60):
        i1, i2, i3 = (mp.mpf(float(v)) for v in unit)
        for t, value in zip(np.tile(theta, 2), got_theta):
            st, ct = mp.sin(mp.mpf(t)), mp.cos(mp.mpf(t))
            w = (st * mp.cos(phi), st * mp.sin(phi), ct)
            two_e = i1 * w[0] ** 2 + i2 * w[1] ** 2 + i3 * w[2] ** 2
            m_sq = i1**2 * w[0] ** 2 + i2**2 * w[1] ** 2 + i3**2 * w[2] ** 2
            _, expected = period_and_total_phase(i1, i2, i3, two_e, m_sq)
            assert abs(value / float(expected) - 1) <= 2e-15, (t, value, expected)
