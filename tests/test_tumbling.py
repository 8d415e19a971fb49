"""Tumbling periods (P_phi, P_psi), spins of a given total phase, and Apophis."""

import math
import re
import warnings

import numpy as np
import pytest
from scipy import integrate

import orbits
from orbits import Body, Motion
from orbits.errors import InputError
from orbits.tumbling import spins_with_period_ratio, spins_with_total_phase

FIG6 = Body.preset("fig6")


def _azimuth_gain_by_quadrature(motion, axis):
    """Azimuth about L gained in one period by the body axis ``axis`` (0 or 2).

    dphi/dt = L (I_i w_i^2 + I_j w_j^2) / (I_i^2 w_i^2 + I_j^2 w_j^2) for the
    Euler angles with body z along ``axis`` (i, j the other two): uses only
    omega(t) (Jacobi functions), not the Pi of the closed form.
    """
    inertia = motion.body.moments
    others = [k for k in range(3) if k != axis]

    def rate(t):
        w = motion.omega(t)
        num = sum(inertia[k] * w[k] ** 2 for k in others)
        den = sum((inertia[k] * w[k]) ** 2 for k in others)
        return motion.momentum * num / den

    # split at quarter periods, where the integrand's shape changes
    edges = np.linspace(0.0, motion.period, 9)
    return sum(
        integrate.quad(rate, a, b, epsabs=0.0, epsrel=1e-13, limit=200)[0]
        for a, b in zip(edges[:-1], edges[1:])
    )


@pytest.mark.parametrize("theta", [0.2, 0.6, 1.0, 1.3, 1.5])
def test_precession_period_is_the_azimuth_gain_of_the_literature_axis(theta):
    motion = Motion.from_spin(FIG6, theta)
    periods = motion.tumbling_periods()
    axis = 2 if motion.branch == "SAM" else 0
    assert periods.axis == ("short" if axis == 2 else "long")
    gain = _azimuth_gain_by_quadrature(motion, axis)
    assert periods.rotation == motion.period
    assert periods.precession == pytest.approx(2 * math.pi * motion.period / gain, rel=1e-11)
    assert periods.ratio == pytest.approx(gain / (2 * math.pi), rel=1e-11)


def test_rotation_about_momentum_from_the_two_periods():
    for theta in (0.3, 1.4):
        p = Motion.from_spin(FIG6, theta).tumbling_periods()
        sign = 1.0 if p.axis == "short" else -1.0
        assert 1.0 / p.about_momentum == pytest.approx(
            1.0 / p.precession - sign / p.rotation, rel=1e-13
        )


def test_a_closed_orbit_has_an_exactly_rational_period_ratio():
    table = orbits.closed_orbits(FIG6, n_max=6, q_max=3)
    assert len(table) > 10
    for row in table.itertuples():
        ratio = Motion.from_spin(FIG6, dtheta=row.dtheta).tumbling_periods().ratio
        whole = row.n + row.q if row.branch == "SAM" else row.n - row.q
        # ratio = (p +- q)/q exactly, to the root's residual
        assert ratio * row.q == pytest.approx(whole, abs=1e-9 * whole)
    # and a spin between two closed orbits has a ratio that is not p/q, q <= 3
    motion = Motion.from_spin(FIG6, 0.1234)
    ratio = motion.tumbling_periods().ratio
    assert min(abs(ratio * q - round(ratio * q)) for q in (1, 2, 3)) > 1e-3


def test_periods_scale_with_the_spin_and_carry_its_unit():
    slow = Motion.from_omega(FIG6, [0.1, 0.0, 0.3]).tumbling_periods()
    fast = Motion.from_omega(FIG6, [1.0, 0.0, 3.0]).tumbling_periods()
    assert slow.precession == pytest.approx(10 * fast.precession, rel=1e-13)
    assert slow.ratio == pytest.approx(fast.ratio, rel=1e-13)


# (99942) Apophis, Pravec et al. (2014), "The tumbling spin state of (99942)
# Apophis", Icarus 233, 48-60 (uncertainties 3 sigma):
#   SAM, P_phi = 27.38 +- 0.07 h, P_psi = 263 +- 6 h, P_1 = 30.56 +- 0.01 h,
#   I_a/I_c = 0.61 (+0.11 -0.08), I_b/I_c = 0.965 (+0.009 -0.015),
#   E/E0 = 1.024 +- 0.013 with E0 = L^2 / (2 I_c) the basic spin state energy.
APOPHIS = Body((0.61, 0.965, 1.0), name="Apophis")
P_PHI, P_PSI, P_1, E_OVER_E0 = 27.38, 263.0, 30.56, 1.024


def test_apophis_spin_state_from_its_periods():
    spins = spins_with_period_ratio(APOPHIS, P_PSI / P_PHI)
    assert set(spins["branch"].astype(str)) == {"SAM", "LAM"}
    sam = spins[spins["branch"] == "SAM"].iloc[0]
    motion = Motion.from_spin(APOPHIS, dtheta=sam["dtheta"])
    unit = motion.period / P_PSI  # model time units per hour
    periods = motion.tumbling_periods()
    assert periods.rotation / unit == pytest.approx(P_PSI, abs=6.0)
    assert periods.precession / unit == pytest.approx(P_PHI, abs=0.07)
    # independent of the two inputs: the lightcurve period and the energy
    assert periods.about_momentum / unit == pytest.approx(P_1, abs=0.01)
    e_over_e0 = 2.0 * motion.energy * APOPHIS.moments[2] / motion.momentum**2
    assert e_over_e0 == pytest.approx(E_OVER_E0, abs=0.013)
    # the LAM solution with the same ratio is not Apophis: its P_1 is off
    lam = spins[spins["branch"] == "LAM"].iloc[0]
    lam_periods = Motion.from_spin(APOPHIS, dtheta=lam["dtheta"]).tumbling_periods()
    lam_unit = lam_periods.rotation / P_PSI
    assert abs(lam_periods.about_momentum / lam_unit - P_1) > 1.0


# ---------------------------------------------------------------- total phase
def test_spins_with_total_phase_match_closed_orbits():
    """The same roots as the catalog's search, refined: within an ulp or two
    of them and never further from the target (the search stops within
    1e-10 of it; spins_with_total_phase polishes to the doubles)."""
    table = orbits.closed_orbits(FIG6, n_max=4)
    for n in (2, 3, 4):
        spins = spins_with_total_phase(FIG6, 2 * math.pi * n)
        expected = np.sort(table.loc[table["n"] == n, "dtheta"].to_numpy())
        np.testing.assert_allclose(spins["dtheta"].to_numpy(), expected, rtol=1e-14, atol=0)
        ours = np.abs(
            orbits.total_phase(FIG6, dtheta=spins["dtheta"].to_numpy()) - 2 * math.pi * n
        )
        assert np.all(ours <= 4 * np.spacing(2 * math.pi * n))


@pytest.mark.parametrize("value", [20.0, 10.0 * math.e, 123.456])
def test_any_total_phase_is_hit_on_both_branches(value):
    spins = spins_with_total_phase(FIG6, value)
    assert {"SAM", "LAM"} <= set(spins["branch"].astype(str))
    # recomputed independently by the closed form of total_phase
    again = orbits.total_phase(FIG6, dtheta=spins["dtheta"].to_numpy())
    np.testing.assert_allclose(again, value, rtol=1e-12)


def test_total_phase_below_the_minimum_is_an_error_with_the_minimum():
    low, _ = orbits.minimum_phase(FIG6)
    with pytest.raises(InputError, match="at least"):
        spins_with_total_phase(FIG6, 0.5 * low)
    for bad in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(InputError):
            spins_with_total_phase(FIG6, bad)


def test_a_total_phase_at_a_branch_minimum_gives_the_end_spin():
    """The minimum itself (the limit at theta = 0, correctly rounded from
    mpmath, two ulps below the phase computed there; or that computed phase)
    was refused as "at least 6.589020292142196" (an audit); it is the spin
    about the axis.  Just below, by more than the rounding, is still none."""
    import mpmath

    with mpmath.workdps(40):
        i1, i2, i3 = (mpmath.mpf(float(x)) for x in FIG6.unit_moments)
        sam_end = float(2 * mpmath.pi * mpmath.sqrt(i1 * i2 / ((i3 - i2) * (i3 - i1))))
        lam_end = float(2 * mpmath.pi * mpmath.sqrt(i2 * i3 / ((i2 - i1) * (i3 - i1))))
    computed = float(orbits.total_phase(FIG6, 0.0))
    # 2 ulps here; the bounds below allow the kernels' own spread (the
    # search's minimum, total_phase and phases can differ by a few ulps on
    # another CPU), within the 4 ulps the solver takes as the minimum
    assert abs(computed - sam_end) <= 4 * np.spacing(sam_end)
    for target in (sam_end, computed):
        table = spins_with_total_phase(FIG6, target)
        assert table["theta"].tolist() == [0.0] and table["branch"].tolist() == ["SAM"]
        assert abs(table["residual"].iloc[0]) <= 8 * np.spacing(target)
    # the LAM end (theta = pi/2) is LAM's minimum, and SAM also reaches it;
    # the phase is flat there (quadratic in pi/2 - theta), so its rounding
    # spans about sqrt(eps) of theta
    table = spins_with_total_phase(FIG6, lam_end)
    assert table["branch"].tolist() == ["SAM", "LAM"]
    assert table["theta"].iloc[1] == pytest.approx(math.pi / 2, abs=1e-7)
    assert np.all(np.abs(table["residual"]) <= 8 * np.spacing(lam_end))
    with pytest.raises(InputError, match="at least 6.589020292142196"):
        spins_with_total_phase(FIG6, sam_end - 1e-14)
    # the largest double: refused, without an overflow warning from its ulp
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(InputError, match="closer than"):
            spins_with_total_phase(FIG6, np.finfo(float).max)


def test_unreachable_ratio_states_each_branch_in_ratio_terms():
    """A ratio below both branches' minima: the message gives each branch's
    smallest P_psi/P_phi, from Eqs. (28), (29) at the axes (the minimum of
    each branch for this body), not the total phase of the lower branch.

    It used to say "the total phase is at least 6.589 rad (1.0487 turns)",
    the SAM minimum, for a ratio below 1 that only LAM can have.
    """
    at_zero, at_half_pi = orbits.phase_limits(FIG6)
    sam_least = at_zero / (2 * math.pi) + 1.0  # 2.0487
    lam_least = at_half_pi / (2 * math.pi) - 1.0  # 0.6794
    with pytest.raises(InputError, match="no spin of this body") as error:
        spins_with_period_ratio(FIG6, 0.6)
    shown = [float(x) for x in re.findall(r"P_psi/P_phi is at least (\S+),", str(error.value))]
    np.testing.assert_allclose(shown, [sam_least, lam_least], rtol=1e-10)
    assert "total phase" not in str(error.value)
    # just above the LAM minimum a LAM spin exists
    spins = spins_with_period_ratio(FIG6, lam_least * (1 + 1e-6))
    assert spins["branch"].astype(str).tolist() == ["LAM"]
    # the total-phase request names both branches' minima in radians
    with pytest.raises(InputError) as error:
        spins_with_total_phase(FIG6, 6.0)
    shown = [float(x) for x in re.findall(r"total phase is at least (\S+) rad", str(error.value))]
    np.testing.assert_allclose(shown, [at_zero, at_half_pi], rtol=1e-10)


def test_total_phase_beyond_what_a_double_reaches_says_so():
    """Above the phase at |dtheta| = 2.2e-308 the spins exist but cannot be stored.

    The largest phases are those at the smallest normal offset on each branch
    (about 2,424 rad on SAM and 2,430 rad on LAM for this body); between them
    the LAM spin is returned with a warning, above both the error says why
    (it used to claim that no spin has that phase).
    """
    tiny = 2.2250738585072014e-308
    sam, lam = orbits.total_phase(FIG6, dtheta=[-tiny, tiny])
    assert 2400 < sam < lam < 2440
    with pytest.warns(orbits.UnresolvedOrbitsWarning, match="2.2e-308"):
        spins = spins_with_total_phase(FIG6, 0.5 * (sam + lam))
    assert spins["branch"].astype(str).tolist() == ["LAM"]
    for target in (lam * (1 + 1e-9), 1e5, 1e300):
        with pytest.raises(InputError, match="closer than") as error:
            spins_with_total_phase(FIG6, target)
        assert "at least" not in str(error.value)
        assert f"{sam:.6f} rad on SAM" in str(error.value)
        assert f"{lam:.6f} rad on LAM" in str(error.value)
    # a ratio whose SAM and LAM phases are both out of reach, the same
    with pytest.raises(InputError, match="closer than"):
        spins_with_period_ratio(FIG6, lam / (2 * math.pi) + 2.0)


# ---------------------------------------------------------------- SciPy hand-off
def test_rotation_object_is_the_rotation_with_scalar_last_quaternions():
    motion = Motion.from_spin(FIG6, 0.7)
    t = np.linspace(0.0, 3.0, 7)
    rotation = motion.rotation_object(t)
    np.testing.assert_allclose(rotation.as_matrix(), motion.rotation(t), atol=1e-14)
    ours = motion.quaternion(t)  # (w, x, y, z)
    theirs = rotation.as_quat()  # (x, y, z, w)
    # same rotation up to the sign of the quaternion
    dots = np.abs(np.sum(ours[:, [1, 2, 3, 0]] * theirs, axis=1))
    np.testing.assert_allclose(dots, 1.0, atol=1e-14)
    single = motion.as_scipy(0.5)
    assert single.single
    np.testing.assert_allclose(
        single.apply([0.0, 0.0, 1.0]), motion.rotation(0.5) @ [0.0, 0.0, 1.0], atol=1e-15
    )


def test_scalar_time_shapes():
    motion = Motion.from_spin(FIG6, 0.7)
    assert motion.omega(1.0).shape == (3,)
    assert motion.omega_space(1.0).shape == (3,)
    assert motion.euler_angles(1.0).shape == (3,)
    assert motion.rotation(1.0).shape == (3, 3)
    assert motion.quaternion(1.0).shape == (4,)
    assert motion.omega([1.0]).shape == (1, 3)
    assert motion.omega(np.zeros((2, 5))).shape == (2, 5, 3)
    np.testing.assert_array_equal(motion.omega(1.0), motion.omega([1.0])[0])


@pytest.mark.parametrize("periods", [(2e-308, 1e-308), (1e-300, 1e-300), (1e300, 1e300)])
def test_periods_beyond_a_double_name_the_period_not_a_speed(periods):
    """|omega0| = T/P_psi overflowing (or its energy underflowing) is the
    periods' unit, said so; not 'speed must be positive, got inf', an
    argument the caller never gave."""
    with pytest.raises(orbits.InputError, match=r"P_psi = .* give the periods"):
        orbits.spins_with_periods(orbits.Body.preset("fig6"), *periods)


def test_a_period_ratio_beyond_a_double_names_the_periods():
    with pytest.raises(orbits.InputError, match=r"P_psi / P_phi = 1e\+308 / 1e-308"):
        orbits.spins_with_periods(orbits.Body.preset("fig6"), 1e308, 1e-308)


def test_a_spin_vector_that_rounds_the_orbit_is_flagged():
    """spins_with_periods(fig6, 1, 0.01) printed w = (613.22, 0, 382.91) rad/s,
    whose own periods are 0.222 s and 0.00976 s: its dtheta = -1.85e-79 is
    beyond what a double spin holds, and nothing said so."""
    import warnings

    apophis = (0.61, 0.965, 1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the published periods: w holds the orbit
        table = orbits.spins_with_periods(apophis, 263.0, 27.38)
    for _, row in table.iterrows():
        again = orbits.Motion(apophis, row[["w1", "w2", "w3"]].to_numpy(float))
        assert again.tumbling_periods().rotation == pytest.approx(263.0, rel=1e-9)
    with pytest.warns(orbits.UnresolvedOrbitsWarning, match="round the orbit") as caught:
        table = orbits.spins_with_periods(orbits.Body.preset("fig6"), 1.0, 0.01)
    assert all(w.filename == __file__ for w in caught)
    # the periods are the orbit's (of dtheta); w started from is far off
    assert table["P_psi"].to_numpy() == pytest.approx(1.0, rel=1e-12)
    row = table.iloc[0]
    again = orbits.Motion(orbits.Body.preset("fig6"), row[["w1", "w2", "w3"]].to_numpy(float))
    assert abs(again.tumbling_periods().rotation - 1.0) > 0.1


def test_too_near_the_separatrix_speaks_in_the_requests_terms():
    """A period ratio beyond reach was answered in total-phase radians
    (2423.57 on SAM, 2429.85 on LAM: the order reversed in ratio terms)."""
    with pytest.raises(orbits.InputError, match=r"P_psi/P_phi is 386\.72\d+ on SAM and 385\.72"):
        orbits.spins_with_period_ratio(orbits.Body.preset("fig6"), 387.105)
    with pytest.warns(orbits.UnresolvedOrbitsWarning, match="with period ratio") as caught:
        orbits.spins_with_periods(orbits.Body.preset("fig6"), 386.0, 1.0)
    assert all(w.filename == __file__ for w in caught)


def _mp_lam_ratio(moments, dtheta):
    """``P_psi / P_phi = Delta alpha / 2 pi - 1`` of the LAM spin ``dtheta``
    (phi = 0), eqn:GeometricPhase in mpmath at 60 digits."""
    import mpmath as mp
    from mp_formulas import period_and_total_phase

    with mp.workdps(60):
        # the moments as the package holds them (a body on the flat edge
        # I3 = I1 + I2 is made exactly flat: canonical_moments)
        i1, i2, i3 = (mp.mpf(float(v)) for v in Body(moments).moments)
        theta = mp.atan2(mp.sqrt(i3 * (i3 - i2)), mp.sqrt(i1 * (i2 - i1))) + mp.mpf(dtheta)
        w1, w3 = mp.sin(theta), mp.cos(theta)
        two_e, m_sq = i1 * w1**2 + i3 * w3**2, (i1 * w1) ** 2 + (i3 * w3) ** 2
        _, total = period_and_total_phase(i1, i2, i3, two_e, m_sq, sam=False)
        return float(total / (2 * mp.pi) - 1)


@pytest.mark.parametrize(
    "rod, ratio",
    [
        ((1e-10, 0.5, 0.5 + 1e-10), 1e-9),
        ((1e-9, 1.0, 1.0 + 1e-9 - 1e-12), 1.0000998606818356e-09),
        ((1e-8, 1.0, 1.0 + 1e-8 - 1e-11), 1.0100000162882594e-08),
        ((1e-7, 1.0, 1.0 + 1e-7 - 1e-10), 1.0001000494386236e-07),
    ],
)
def test_a_rods_long_axis_ratio_that_cancels_is_said(rod, ratio):
    """P_psi / P_phi = Delta alpha / 2 pi - 1 on LAM, a ratio near 0 on a thin
    rod: the search's root (within 1e-10 of Delta alpha) gave a spin whose
    ratio was 7.6e-2 off on (1e-9, 1, 1 + 1e-9 - 1e-12) with a warning of
    8e-7, and 1.4e-7 off with none before that (found by audits).  Now the
    root is polished and the warning (from spins_with_period_ratio too)
    bounds the error of the spin's ratio against the request, checked by
    mpmath."""
    for solve in (
        lambda: orbits.spins_with_period_ratio(rod, ratio),
        lambda: orbits.spins_with_periods(rod, 1.0, 1.0 / ratio),
    ):
        with pytest.warns(orbits.UnresolvedOrbitsWarning, match="only to about") as caught:
            table = solve()
        bound = float(re.search(r"only to about (\S+) \(relative\)", str(caught[0].message))[1])
        assert bound < 2e-6
        (dtheta,) = table["dtheta"].to_numpy()
        exact = _mp_lam_ratio(rod, dtheta)
        assert abs(exact / ratio - 1.0) <= bound
        if "P_phi" in table:  # the row's P_phi is that spin's, to the same bound
            assert abs(table["P_phi"].iloc[0] * exact / table["P_psi"].iloc[0] - 1.0) <= bound


def test_a_rods_ratio_far_from_zero_is_not_warned():
    rod = (1e-10, 0.5, 0.5 + 1e-10)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        table = orbits.spins_with_periods(rod, 1.0, 1e4)  # ratio 1e-4: 9e-12 at most
    assert table["P_phi"].iloc[0] == pytest.approx(1e4, rel=1e-9)
