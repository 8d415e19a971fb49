"""Closed-orbit search: the paper's Fig. 6 roots, completeness, range, rationals."""

import math
import re
import warnings

import numpy as np
import pytest

import orbits
from orbits import Body, InputError, closed_orbits
from orbits.core import search as kernels
from orbits.search import UnresolvedOrbitsWarning, minimum_phase, phase_levels

FIG6 = Body.preset("fig6")
T_HANDLE = Body.preset("t-handle")


def test_fig6_roots_of_the_paper():
    """Sec. III.C: theta = 0.9562 ... 1.2742 with n = 2, 3, 4, 5, 5, 4, 3, 2."""
    table = closed_orbits(FIG6, n_max=5)
    assert table["n"].tolist() == [2, 3, 4, 5, 5, 4, 3, 2]
    assert table["branch"].tolist() == ["SAM"] * 4 + ["LAM"] * 4
    paper = [0.9562, 1.004, 1.011, 1.012, 1.014, 1.021, 1.061, 1.2742]
    for got, printed in zip(table["theta"], paper):
        decimals = len(repr(printed).split(".")[1])
        assert abs(got - printed) <= 0.5 * 10.0**-decimals
    # the critical angle sits between the two n = 5 orbits
    assert table["theta"][3] < orbits.critical_angle(FIG6) < table["theta"][4]
    # "each n is about 6x closer than the last"
    offsets = table.loc[table.branch == "SAM", "dtheta"].abs().to_numpy()
    ratios = offsets[:-1] / offsets[1:]
    assert np.all((5.5 < ratios[1:]) & (ratios[1:] < 7.0))


def test_every_root_meets_its_level_and_n_max_300_works():
    table = closed_orbits(FIG6, n_max=300)
    target = 2 * np.pi * table["n"] / table["q"]
    # checked from dtheta, independently of the search
    again = orbits.total_phase(FIG6, dtheta=table["dtheta"].to_numpy())
    assert np.all(np.abs(again - target) <= 1e-10 * target)
    assert np.all(np.abs(table["residual"]) <= 1e-10 * target)
    # every n from the branch minimum up to 300, once on each branch
    for branch, limit in (
        ("SAM", orbits.phase_limits(FIG6).theta_zero),
        ("LAM", orbits.phase_limits(FIG6).theta_half_pi),
    ):
        found = sorted(table.loc[table.branch == branch, "n"])
        assert found == list(range(math.floor(limit / (2 * np.pi)) + 1, 301))
    assert table["dtheta"].abs().min() < 1e-200
    assert (np.diff(table["dtheta"]) > 0).all()  # sorted by theta
    # full relative precision near the separatrix: the roots are distinct
    assert table["dtheta"].nunique() == len(table)


def test_roots_independently_by_bisection():
    """The n = 3 roots by plain bisection on the public API."""
    for branch, sign in (("SAM", -1.0), ("LAM", 1.0)):
        lo, hi = 1e-6, 0.3
        for _ in range(200):
            mid = math.sqrt(lo * hi)
            value = orbits.total_phase(FIG6, dtheta=sign * mid) - 6 * np.pi
            lo, hi = (mid, hi) if value > 0 else (lo, mid)
        table = closed_orbits(FIG6, n_max=3)
        row = table[(table.branch == branch) & (table.n == 3)].iloc[0]
        assert row.dtheta == pytest.approx(sign * lo, rel=1e-14)


def test_rational_levels():
    p, q, values = phase_levels(3, 4)
    fractions = list(zip(p, q))
    assert (1, 1) in fractions and (3, 4) in fractions and (5, 2) in fractions
    assert (2, 4) not in fractions and (2, 2) not in fractions  # lowest terms
    assert np.all(np.diff(values) > 0)
    assert np.all(p <= 3 * q)
    assert all(math.gcd(int(a), int(b)) == 1 for a, b in fractions)


def test_rational_orbits_close_after_q_periods():
    table = closed_orbits(FIG6, n_max=4, q_max=3)
    assert set(table["q"]) == {1, 2, 3}
    assert (table.loc[table.q == 1, "n"] >= 2).all()
    for _, row in table[table.q > 1].head(6).iterrows():
        t, omega = orbits.herpolhode(FIG6, dtheta=row.dtheta, periods=row.q, points=3001)
        assert np.abs(omega[-1] - omega[0]).max() <= 1e-9
        # but not after fewer periods
        for fewer in range(1, row.q):
            t, omega = orbits.herpolhode(FIG6, dtheta=row.dtheta, periods=fewer, points=3)
            assert np.abs(omega[-1] - omega[0]).max() > 1e-3


@pytest.mark.parametrize("seed", range(6))
def test_search_is_complete_on_non_monotone_profiles(seed):
    """The scan-and-split search against brute force on wiggly profiles.

    No physical body in a 300 x 300 grid has a non-monotone phase at
    phi = 0, so the splitting at extrema is exercised on a synthetic
    profile with the same divergence at the separatrix.
    """
    rng = np.random.default_rng(seed)
    width = rng.uniform(0.3, 1.4)
    params = np.array(
        [
            rng.uniform(0.5, 2.0),
            rng.uniform(3, 8),
            rng.uniform(0.5, 3.0),
            rng.uniform(2.0, 12.0),
            rng.uniform(0.0, 3.0),
            rng.uniform(0.005, 0.05),
            width,
        ]
    )
    levels = np.sort(rng.uniform(2.0, 25.0, 40))
    root_level = np.empty(4000, dtype=np.int64)
    root_offset = np.empty(4000)
    info = np.empty(kernels.BRANCH_INFO_SIZE)
    count = kernels.search_branch(
        kernels.KIND_SYNTHETIC, params, width, levels, root_level, root_offset, 0, info
    )
    d = np.concatenate(
        [
            np.geomspace(1e-300, 1e-3 * width, 100_000),
            np.linspace(1e-3 * width, width, 2_000_001)[1:-1],
        ]
    )
    a, b, c, k, depth, spread, w = params
    f = (
        a * np.log(w / d)
        + b
        + c * np.sin(k * np.pi * d / w)
        - depth * np.exp(-(((w - d) / spread) ** 2))
    )
    expected = sum(
        int(np.count_nonzero((f[:-1] - level) * (f[1:] - level) < 0)) for level in levels
    )
    assert count == expected
    for j, offset in zip(root_level[:count], root_offset[:count]):
        assert kernels.synthetic_profile(offset, params) == pytest.approx(levels[j], abs=1e-9)
    # the refined minimum is attained where reported, and no sample beats it
    assert kernels.synthetic_profile(info[1], params) == pytest.approx(info[0], rel=1e-15)
    assert info[0] <= f.min() + 1e-12


def test_unrepresentable_roots_are_reported():
    body = Body((0.05, 1.0, 1.049))  # ~23x closer per n: n = 300 is past 1e-308
    with pytest.warns(UnresolvedOrbitsWarning, match="2.2e-308") as told:
        table = closed_orbits(body, n_max=300)
    assert table.attrs["unresolved"] > 0
    # the warning says how many each branch left out: with those found, every
    # level n above the branch's minimum phase (one root each: monotone here)
    left = re.search(r"\((\d+) on SAM and (\d+) on LAM\)", str(told[0].message))
    for name, count in zip(("SAM", "LAM"), map(int, left.groups())):
        levels = 300 - math.floor(table.attrs["minimum_phase"][name][0] / (2 * math.pi))
        assert count > 0 and int((table["branch"] == name).sum()) + count == levels
    assert table["dtheta"].abs().min() >= kernels.SMALLEST_OFFSET
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        closed_orbits(FIG6, n_max=300)  # the paper's body: all representable


def test_minimum_phase_at_the_ends():
    value, where = minimum_phase(FIG6)
    limits = orbits.phase_limits(FIG6)
    assert value == pytest.approx(min(limits), rel=1e-12)
    assert where == pytest.approx(-orbits.critical_angle(FIG6))  # theta = 0


@pytest.mark.parametrize(
    "moments", [(1e-3, 0.5, 0.5009), (0.2, 0.5, 0.6), (0.3, 0.6, 0.742), (1.0, 2.0, 2.5)]
)
def test_branch_minima_lie_at_their_ends_with_their_signs(moments):
    """Each branch's minimum (closed_orbits' attrs, minimum_phase) and where
    it lies: SAM at theta = 0 (dtheta = -theta_c < 0), LAM at theta = pi/2
    (dtheta = pi/2 - theta_c > 0), against a dense scan of orbits.phases on
    each branch and the closed-form end limits (eqns alphamin1/2).  A LAM
    location stored with the SAM sign passed every test before."""
    theta_c = orbits.critical_angle(moments)
    limits = orbits.phase_limits(moments)
    found = closed_orbits(moments, n_max=5).attrs["minimum_phase"]
    ends = {
        "SAM": (limits.theta_zero, -theta_c),
        "LAM": (limits.theta_half_pi, np.pi / 2 - theta_c),
    }
    for name, (value, where) in found.items():
        end_value, end = ends[name]
        assert where == pytest.approx(end, rel=1e-15) and np.sign(where) == np.sign(end)
        assert value == pytest.approx(end_value, rel=1e-13)
        # the scan: log-spaced from the separatrix to the end, on this branch
        width = abs(end)
        offsets = np.sign(end) * width * np.geomspace(1e-12, 1.0, 2000)
        scanned = orbits.phases(moments, dtheta=offsets)["total_phase"].to_numpy()
        assert scanned.min() >= value * (1 - 1e-13)
    best = min(found.values())
    assert minimum_phase(moments) == (best[0], pytest.approx(best[1], rel=1e-15))


def test_minimum_phase_scans_and_keeps_a_minimum_inside_a_branch(monkeypatch):
    """minimum_phase takes the minimum of the full scan of each branch (the
    bracketing search), wherever it lies; one inside a branch is reported as
    found, also below 2 pi (only an end value is raised to 2 pi)."""
    import orbits.search as search_module

    kernels = search_module._kernels
    scan = kernels.search_body_bracketing
    calls = []

    def dipping_scan(i1, i2, i3, levels, branch, level, offset, info):
        count = scan(i1, i2, i3, levels, branch, level, offset, info)
        calls.append(levels.size)
        info[kernels.INFO_MIN_LAM] = 6.0  # below 2 pi, inside the LAM branch
        info[kernels.INFO_MIN_AT_LAM] = 0.25 * info[kernels.INFO_WIDTH_LAM]
        return count

    monkeypatch.setattr(kernels, "search_body_bracketing", dipping_scan)
    value, where = minimum_phase(FIG6)
    assert calls == [0]
    width = np.pi / 2 - orbits.critical_angle(FIG6)
    assert value == 6.0 and where == pytest.approx(0.25 * width, rel=1e-15)


def test_body_with_no_two_pi_orbit():
    # every physical body: minimum phase > 2 pi, so n = 1 never occurs
    table = closed_orbits(Body((0.3, 0.5, 0.7)), n_max=1)
    assert len(table) == 0
    assert list(table.columns) == list(orbits.CATALOG_COLUMNS)


@pytest.mark.parametrize(
    "kwargs", [dict(n_max=0), dict(n_max=2.5), dict(n_max=3, q_max=0), dict(n_max=True)]
)
def test_bad_counts(kwargs):
    with pytest.raises(InputError, match="integer >= 1"):
        closed_orbits(FIG6, **kwargs)


def test_bad_body():
    with pytest.raises(orbits.SymmetricTopError):
        closed_orbits([1.0, 1.0, 1.5], n_max=3)
    with pytest.raises(InputError, match="one body"):
        closed_orbits([[1.0, 2.0, 2.5], [1.0, 2.0, 2.6]], n_max=3)


def test_catalog_rows_carry_d():
    """D = M^2/(2E) of each row, for its |I| = 1 moments: I1 < D < I3, and
    D > I2 exactly on SAM (the separatrix is D = I2), closer to I2 as the
    orbit approaches the separatrix."""
    table = closed_orbits(FIG6, n_max=12, q_max=2)
    d = table["D"].to_numpy()
    np.testing.assert_allclose(d, table["momentum"] ** 2 / (2 * table["energy"]), rtol=4e-16 * 8)
    assert np.all((table["I1"] < d) & (d < table["I3"]))
    assert np.array_equal(d > table["I2"], table["branch"] == "SAM")
    # phi = 0: D = (I1^2 sin^2 + I3^2 cos^2)/(I1 sin^2 + I3 cos^2), independently
    s2, c2 = np.sin(table["theta"]) ** 2, np.cos(table["theta"]) ** 2
    i1, i3 = table["I1"], table["I3"]
    np.testing.assert_allclose(d, (i1**2 * s2 + i3**2 * c2) / (i1 * s2 + i3 * c2), rtol=1e-14)


@pytest.mark.parametrize("scale", [2.0**-1000, 2.0**-300, 2.0**300, 2.0**1000, 1e-120, 1e80])
def test_search_bodies_is_scale_free(scale):
    """search_bodies at any scale of doubles: the roots of the unit-scale body
    (bit for bit at powers of two; within a few ulps where the scaled moments
    round).  Before, 1e-80 moved roots by 7e-4, 1e-120 raised ZeroDivisionError
    and 1e80 found no roots."""
    levels = 2.0 * np.pi * np.array([2.0, 3.0, 5.0])
    given = np.array([[1.0, 2.0, 2.5]])
    expected = orbits.search_bodies(given, levels)
    got = orbits.search_bodies(given * scale, levels)
    count = int(expected.counts[0])
    assert count == 6 and int(got.counts[0]) == count
    np.testing.assert_array_equal(got.branch[0, :count], expected.branch[0, :count])
    np.testing.assert_array_equal(got.level[0, :count], expected.level[0, :count])
    if math.frexp(scale)[0] == 0.5:
        np.testing.assert_array_equal(got.offset[0, :count], expected.offset[0, :count])
    else:
        np.testing.assert_allclose(got.offset[0, :count], expected.offset[0, :count], rtol=1e-13)


def test_search_bodies_refuses_a_non_physical_body():
    levels = 2.0 * np.pi * np.array([2.0, 3.0])
    with pytest.raises(orbits.NonPhysicalBodyError, match="I3 <= I1 \\+ I2"):
        orbits.search_bodies([[1.0, 2.0, 3.5]], levels)


def test_an_unnamed_body_is_labelled_by_its_moments_as_given():
    """Not by the internal power-of-two scaling (was ``I=(0.25, 0.5, 0.625)``)."""
    assert closed_orbits([1.0, 2.0, 2.5], 3)["body"].iloc[0] == "I=(1, 2, 2.5)"
    assert closed_orbits(Body([2.5, 1.0, 2.0]), 3)["body"].iloc[0] == "I=(1, 2, 2.5)"
    assert orbits.catalog([[3.0, 6.0, 9.0]], 3)["body"].iloc[0] == "I=(3, 6, 9)"
    near = closed_orbits([1.0, 1.00000001, 1.5], 3)["body"].iloc[0]
    assert near == "I=(1, 1.00000001, 1.5)"
    tiny = closed_orbits(np.array([1.0, 2.0, 2.5]) * 1e-200, 3)["body"].iloc[0]
    assert tiny == "I=(1e-200, 2e-200, 2.5e-200)"


def test_search_bodies_refuses_repeated_or_non_positive_levels_and_huge_capacity():
    """A level given twice returned every root twice; a capacity beyond the
    machine's memory let NumPy's MemoryError through."""
    body = np.array([[0.26, 0.55, 0.793662]])
    for levels in ([20.0, 20.0], [-1.0, 20.0], [0.0, 20.0], [20.0, 19.0]):
        with pytest.raises(orbits.InputError, match="strictly ascending"):
            orbits.search_bodies(body, levels)
    with pytest.raises(orbits.InputError, match="capacity=1000000000000 .* memory"):
        orbits.search_bodies(body, [20.0], capacity=10**12)
    rows = orbits.search_bodies(body, [20.0, 25.0])
    assert rows.counts.tolist() == [4]  # two roots a level (SAM and LAM)


@pytest.mark.parametrize("moments", [[["1", "2", "3"]], [[True, 2.0, 3.0]], [[1j, 2.0, 3.0]], "a"])
def test_search_bodies_refuses_what_is_not_numbers(moments):
    """Text and booleans were searched as numbers; complex and 'a' raised
    TypeError and ValueError."""
    with pytest.raises(orbits.ArgumentTypeError, match="moments must be real numbers"):
        orbits.search_bodies(moments, np.array([13.0, 20.0]))
