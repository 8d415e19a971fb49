"""Plotting primitives: what is drawn is the physics."""

import matplotlib

matplotlib.use("Agg")

import math  # noqa: E402
import re  # noqa: E402

import matplotlib as mpl  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import orbits  # noqa: E402
from orbits import Body, figures, plotting  # noqa: E402
from orbits.figures import new_figure  # noqa: E402

FIG6 = Body.preset("fig6")
T_HANDLE = Body.preset("t-handle")
SPIN = dict(theta=np.pi / 2 - 0.15, phi=np.pi / 2 - 0.2)


def test_closed_herpolhode_closes_and_is_labelled():
    table = orbits.closed_orbits(FIG6, n_max=4, q_max=2)
    for row in table.itertuples():
        ax = new_figure().add_subplot()
        line = plotting.plot_herpolhode(ax, FIG6, dtheta=row.dtheta, periods=row.q)
        xy = line.get_xydata()
        assert np.abs(xy[-1] - xy[0]).max() <= 1e-9
        assert ax.get_aspect() == 1.0
        assert "omega_x" in ax.get_xlabel() and "omega_y" in ax.get_ylabel()
        # the drawn points are the herpolhode
        t, omega = orbits.herpolhode(FIG6, dtheta=row.dtheta, periods=row.q, points=len(xy))
        np.testing.assert_array_equal(xy, omega[:, :2])


def test_body_space_map_matches_the_limit_formulas():
    grid = plotting.body_space_grid(150)
    i1, i2, minimum = grid
    limits = plotting.limits_field(i1, i2)
    inside = np.isfinite(limits)
    assert inside.sum() > 300
    # the numerical minimum over theta is the smaller of the two limits
    np.testing.assert_allclose(minimum[inside], limits[inside], rtol=1e-12)
    assert np.all(np.isnan(minimum[~inside]))
    ax = new_figure().add_subplot()
    drawn = plotting.plot_body_space(ax, grid)
    # every drawn contour vertex sits on its level of min(alphamin1, alphamin2)
    # to the accuracy of linear interpolation on the grid: the field has
    # kinks (the dashed locus) so it converges at first order, measured
    # 0.87% at 150 points and 0.46% at the figure's 300; the end vertices
    # touch the NaN cells outside the region and are left out
    checked = 0
    for level, segments in zip(drawn["contours"].levels, drawn["contours"].allsegs):
        for segment in segments:
            values = plotting.limits_field(segment[1:-1, 0], segment[1:-1, 1])
            ok = np.isfinite(values)
            np.testing.assert_allclose(values[ok], level, rtol=1e-2)
            checked += ok.sum()
    assert checked > 100
    # the kink locus: the two limits agree there (theta_c = pi/4)
    x, y = drawn["kink"].get_data()
    moments = np.stack([x, y, np.sqrt(1 - x**2 - y**2)], axis=-1)
    lim = orbits.phase_limits(moments)
    np.testing.assert_allclose(lim.theta_zero, lim.theta_half_pi, rtol=1e-9)
    np.testing.assert_allclose(orbits.critical_angle(moments), np.pi / 4, rtol=1e-9)
    # the boundaries are the prolate (I2 = I3), oblate (I1 = I2), flat (I3 = I1 + I2) curves
    b = drawn["boundaries"]
    x, y = b["prolate"].get_data()
    np.testing.assert_allclose(y, np.sqrt(1 - x**2 - y**2), atol=1e-12)
    x, y = b["oblate"].get_data()
    np.testing.assert_array_equal(x, y)
    x, y = b["flat"].get_data()
    np.testing.assert_allclose(np.sqrt(np.clip(1 - x**2 - y**2, 0, None)), x + y, atol=1e-12)
    assert drawn["colorbar"].ax.get_ylabel()
    assert ax.get_xlabel() == r"$I_1\,/\,|I|$" and ax.get_ylabel() == r"$I_2\,/\,|I|$"
    # bodies above the top level take the colour bar's "over" colour: a band
    # up to 8 2 pi (clipped there) painted the minima up to 200 2 pi near the
    # sphere in its own colour and left the bar's triangle unused
    filled = drawn["filled"]
    assert filled.extend == "max" and filled.levels[-1] == plotting.DEFAULT_CONTOURS[-1]
    assert np.nanmax(minimum) > 8 * 2 * np.pi
    # levels of the caller: none at all is the map without contours; levels
    # below 2 pi or out of order are refused in words (a ValueError of
    # matplotlib's, or an IndexError for none)
    assert (
        len(
            plotting.plot_body_space(new_figure().add_subplot(), grid, levels=[])[
                "contours"
            ].allsegs
        )
        == 0
    )
    for bad in ([5.0], [20.0, 10.0], [np.nan]):
        with pytest.raises(
            orbits.InputError, match="levels must be finite, increasing and above 2 pi"
        ):
            plotting.plot_body_space(new_figure().add_subplot(), grid, levels=bad)


def test_phase_curves_are_the_closed_form():
    ax = new_figure().add_subplot()
    lines = plotting.plot_phase_curves(ax, T_HANDLE)
    theta, total = lines["total"].get_data()
    # one break (NaN) at theta_c, so no segment joins the two branches
    gap = np.flatnonzero(np.isnan(theta))
    theta_c = orbits.critical_angle(T_HANDLE)
    assert gap.size == 1 and theta[gap[0] - 1] < theta_c < theta[gap[0] + 1]
    for line in lines.values():
        if hasattr(line, "get_ydata"):
            assert np.isnan(line.get_ydata()[gap[0]])
    keep = np.isfinite(theta)
    theta, total = theta[keep], total[keep]
    table = orbits.phases(T_HANDLE, theta)
    np.testing.assert_array_equal(total, table["total_phase"])
    np.testing.assert_allclose(
        lines["geometric"].get_ydata()[keep],
        lines["dynamic"].get_ydata()[keep] - total,
        atol=1e-12,
    )
    np.testing.assert_array_equal(lines["period"].get_ydata()[keep], table["period"])
    assert lines["period_axes"].get_ylabel().startswith("period")
    assert orbits.critical_angle(T_HANDLE) not in theta


def test_total_phase_plot_marks_the_catalog_roots():
    ax = new_figure().add_subplot()
    table = orbits.closed_orbits(FIG6, n_max=8)
    drawn = plotting.plot_total_phase(ax, FIG6, table, n_levels=8)
    marked = drawn["roots"].get_offsets()
    np.testing.assert_array_equal(marked[:, 0], table["theta"])
    np.testing.assert_allclose(marked[:, 1], 2 * np.pi * table["n"], rtol=1e-14)
    assert [line.get_ydata()[0] for line in drawn["levels"]] == pytest.approx(
        2 * np.pi * np.arange(1, 9)
    )
    # the levels are named on the right-hand axis, outside the data
    named = drawn["level_axis"]
    np.testing.assert_allclose(named.get_yticks(), 2 * np.pi * np.arange(1, 9), rtol=1e-15)
    assert [t.get_text() for t in named.get_yticklabels()] == [
        rf"$2\pi\cdot{n}$" for n in range(1, 9)
    ]
    assert not [t for t in ax.texts if "2\\pi" in t.get_text()]


def test_omega_components_are_the_exact_motion():
    ax = new_figure().add_subplot()
    drawn = plotting.plot_omega_components(ax, T_HANDLE, **SPIN)
    motion = orbits.Motion.from_spin(T_HANDLE, **SPIN)
    t = drawn["lines"][0].get_xdata()
    omega = motion.omega(t)
    for k, line in enumerate(drawn["lines"]):
        np.testing.assert_array_equal(line.get_ydata(), omega[:, k])
    assert drawn["period"] == pytest.approx(23.8181, abs=5e-5)
    assert [line.get_linestyle() for line in drawn["lines"]] == ["-", "--", "-."]


def test_binet_polhode_lies_on_both_surfaces():
    ax = new_figure().add_subplot(projection="3d")
    drawn = plotting.plot_binet(ax, T_HANDLE, **SPIN)
    x, y, z = drawn["polhode"].get_data_3d()
    unit = T_HANDLE.normalized_moments
    np.testing.assert_allclose(np.sqrt(x**2 + y**2 + z**2), drawn["momentum"], rtol=1e-13)
    np.testing.assert_allclose(
        x**2 / unit[0] + y**2 / unit[1] + z**2 / unit[2], 2 * drawn["energy"], rtol=1e-13
    )
    assert drawn["energy"] == pytest.approx(0.264805, abs=5e-7)


def test_foliation_colours_are_the_phase():
    ax = new_figure().add_subplot(projection="3d")
    drawn = plotting.plot_polhode_foliation(ax, T_HANDLE, count=12)
    cmap = mpl.colormaps["twilight"]
    unit = T_HANDLE.normalized_moments
    semi2 = unit  # semi-axes^2 of the Binet ellipsoid at E = 1/2
    for line, phase in drawn["polhodes"]:
        assert line.get_color() == pytest.approx(cmap(phase / (2 * np.pi)))
        x, y, z = (np.asarray(v, dtype=float) for v in line.get_data_3d())
        shown = np.isfinite(x)
        assert shown.sum() >= 2
        points = np.stack([x, y, z], axis=-1)
        # all polhodes on the one Binet ellipsoid of energy 1/2
        np.testing.assert_allclose(np.sum(points[shown] ** 2 / unit, axis=1), 1.0, rtol=1e-12)
        # depth cue: every point of a full-strength piece faces the viewer (outward
        # normal M / I towards it) or joins one that does; faint pieces face away
        facing = (points / semi2) @ drawn["view"]
        near = facing > 0 if line.get_alpha() in (None, 1.0) else facing <= 0
        near &= shown
        neighbour = near | np.roll(near, 1) | np.roll(near, -1)
        assert neighbour[shown].all()
    assert drawn["colorbar"].ax.get_ylabel()


def test_t_handle_drawing():
    ax = new_figure().add_subplot(projection="3d")
    drawn = plotting.plot_t_handle(ax)
    assert drawn["semi_axes"] == pytest.approx((4.23281, 3.07318, 0.645497), abs=5e-6)
    # the bars are drawn about their centre of mass, and their moments about
    # it are the T-handle's (unit density, then normalised to unit mass)
    boxes = [(np.array(lo), np.array(hi)) for lo, hi in drawn["boxes"]]
    volumes = np.array([np.prod(hi - lo) for lo, hi in boxes])
    centres = np.array([(lo + hi) / 2 for lo, hi in boxes])
    np.testing.assert_allclose(volumes @ centres, 0.0, atol=1e-12)
    tensor = np.zeros((3, 3))
    for volume, (lo, hi), centre in zip(volumes, boxes, centres):
        a, b, c = hi - lo
        tensor += volume / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
        tensor += volume * (centre @ centre * np.eye(3) - np.outer(centre, centre))
    np.testing.assert_allclose(
        np.diag(tensor) / volumes.sum(), np.sort(T_HANDLE.moments)[[0, 1, 2]], rtol=1e-13
    )


def test_plots_take_a_motion_in_real_units():
    """A phone (kg, m) spun at 120 rpm about its short axis with a wobble:
    the drawn curves are its own motion in s, rad/s and J s."""
    phone = Body.box(0.071, 0.147, 0.0078, mass=0.17)
    omega = np.array([0.3, 0.2, 120 * 2 * np.pi / 60])  # rad/s, principal frame
    motion = orbits.Motion.from_omega(phone, omega, axes="principal")
    ax = new_figure().add_subplot()
    line = plotting.plot_herpolhode(ax, motion, points=801)
    xy = line.get_xydata()
    np.testing.assert_array_equal(
        xy, motion.omega_space(np.linspace(0.0, motion.period, 801))[:, :2]
    )
    assert "rad/s" in ax.get_xlabel()
    ax = new_figure().add_subplot()
    drawn = plotting.plot_omega_components(ax, motion)
    assert drawn["period"] == motion.period
    t = drawn["lines"][2].get_xdata()
    np.testing.assert_array_equal(drawn["lines"][2].get_ydata(), motion.omega(t)[:, 2])
    assert drawn["lines"][2].get_ydata()[0] == omega[2]
    assert "(s)" in ax.get_xlabel() and "rad/s" in ax.get_ylabel()
    ax = new_figure().add_subplot(projection="3d")
    drawn = plotting.plot_binet(ax, motion)
    # E = omega.I.omega/2 in J and |L| in J s, from the definitions
    i = phone.moments
    assert drawn["energy"] == pytest.approx(0.5 * np.sum(i * omega**2), rel=1e-14)
    assert drawn["momentum"] == pytest.approx(np.linalg.norm(i * omega), rel=1e-14)
    x, y, z = drawn["polhode"].get_data_3d()
    np.testing.assert_allclose(np.sqrt(x**2 + y**2 + z**2), drawn["momentum"], rtol=1e-13)
    assert "J s" in ax.get_xlabel()


def test_angles_given_with_a_motion_are_refused():
    """A Motion has its own spin: angles beside it were ignored
    (``plot_herpolhode(ax, motion, 1.2)`` drew the theta = 0.5 curve; an
    audit).  phi = 0 (the default) is not an angle given."""
    motion = orbits.Motion.from_spin(FIG6, 0.5)
    ax = new_figure().add_subplot()
    for draw in (plotting.plot_herpolhode, plotting.plot_omega_components):
        with pytest.raises(orbits.errors.InputError, match="theta given with a Motion"):
            draw(ax, motion, 1.2)
        with pytest.raises(orbits.errors.InputError, match="dtheta given with a Motion"):
            draw(ax, motion, dtheta=-0.1)
        with pytest.raises(orbits.errors.InputError, match="phi given with a Motion"):
            draw(ax, motion, phi=0.3)
    ax3d = new_figure().add_subplot(projection="3d")
    with pytest.raises(orbits.errors.InputError, match="theta and phi given with a Motion"):
        plotting.plot_binet(ax3d, motion, 1.2, phi=0.3)
    line = plotting.plot_herpolhode(ax, motion, phi=0.0, points=101)
    np.testing.assert_array_equal(
        line.get_xydata(), motion.omega_space(np.linspace(0.0, motion.period, 101))[:, :2]
    )


def test_herpolhode_radii_bound_the_curve_and_are_reached():
    """r_min, r_max (closed form from the invariants) against the exact motion.

    Reference: the exact motion's |omega_xy(t)| minimised/maximised by a
    bounded scalar search (xatol 1e-13 s) from the best of 20001 samples;
    the motion is accurate to ~1e-15, the search's radius error is ~1e-16
    at a smooth extremum, so 1e-11 leaves 100x margin.
    """
    from scipy.optimize import minimize_scalar

    for body, kwargs in (
        (FIG6, dict(theta=0.6)),
        (FIG6, dict(theta=1.3)),
        (T_HANDLE, SPIN),
        (FIG6, dict(dtheta=-3e-4)),
    ):
        r_min, r_max = plotting.herpolhode_radii(body, **kwargs)
        motion = orbits.Motion.from_spin(body, **kwargs)
        t = np.linspace(0.0, motion.period, 20001)
        radius = np.hypot(*motion.omega_space(t)[:, :2].T)
        assert radius.min() >= r_min - 1e-12 and radius.max() <= r_max + 1e-12
        step = t[1]
        for sign, target in ((1.0, r_min), (-1.0, r_max)):
            k = int(np.argmin(sign * radius))

            def f(s, sign=sign):
                return sign * np.hypot(*motion.omega_space(np.array([s]))[0, :2])

            found = minimize_scalar(
                f, bounds=(t[k] - step, t[k] + step), method="bounded", options={"xatol": 1e-13}
            )
            assert sign * found.fun == pytest.approx(target, abs=1e-11)


def _radii_mp(moments, theta=None, dtheta=None, phi=0.0):
    """r_min, r_max from |omega|^2 - (2E/M)^2 at the crossings, in mpmath at
    700 digits (enough for the cancellation at dtheta = 1e-300)."""
    import mpmath as mp

    with mp.workdps(700):
        body = moments if isinstance(moments, Body) else Body(moments)
        i = [mp.mpf(x) for x in body.moments]
        phi = mp.mpf(phi)
        theta_c = mp.atan(
            mp.sqrt(i[2] * (i[2] - i[1]) / (i[0] * (i[1] - i[0]) * mp.cos(phi) ** 2))
        )
        theta = theta_c + mp.mpf(dtheta) if dtheta is not None else mp.mpf(theta)
        w = [mp.sin(theta) * mp.cos(phi), mp.sin(theta) * mp.sin(phi), mp.cos(theta)]
        m2 = sum((i[k] * w[k]) ** 2 for k in range(3))
        two_e = sum(i[k] * w[k] ** 2 for k in range(3))
        radii = []
        for zero in range(3):
            a, b = (k for k in range(3) if k != zero)
            ma2 = (two_e - m2 / i[b]) / (1 / i[a] - 1 / i[b])
            if ma2 >= 0 and m2 - ma2 >= 0:  # the polhode crosses M_zero = 0
                radii.append(mp.sqrt(ma2 / i[a] ** 2 + (m2 - ma2) / i[b] ** 2 - two_e**2 / m2))
        return float(min(radii)), float(max(radii))


@pytest.mark.parametrize(
    "moments, kwargs",
    [
        (FIG6, dict(theta=0.6)),
        (FIG6, dict(theta=0.4, phi=0.7)),
        (FIG6, dict(theta=1e-9)),  # next to the I3 axis: old form gave 0
        (FIG6, dict(theta=np.pi / 2 - 1e-9)),  # next to I1: old form 7x too large
        ((1.0, 1.0001, 1.0002), dict(theta=0.01)),  # old form 5e-6 off
        ((1.0, 1.0 + 1e-10, 1.0 + 2e-10), dict(theta=0.3)),  # old form gave 0
        ((1.0, 2.0, 2.5), dict(theta=0.8)),
        (FIG6, dict(dtheta=1e-12)),  # old form 5e-5 off
        (FIG6, dict(dtheta=-1e-12)),
        (FIG6, dict(dtheta=1e-300)),  # r_min ~ 1e-151: old form gave 0
        (FIG6, dict(dtheta=-1e-300)),
    ],
)
def test_herpolhode_radii_are_accurate_to_a_few_ulps(moments, kwargs):
    """Factored form (no 2E - M^2/I_j) against mpmath: 1.3e-15 measured at
    worst; bound 1e-14."""
    got = plotting.herpolhode_radii(moments, **kwargs)
    want = _radii_mp(moments, **kwargs)
    assert got == pytest.approx(want, rel=1e-14, abs=0.0)


def test_theta_text_switches_to_dtheta_near_the_separatrix():
    theta_c = orbits.critical_angle(FIG6)
    assert plotting.theta_text(theta_c - 8.371e-7, -8.371e-7) == (
        r"$\theta-\theta_c$ = -8.371e-07"
    )
    assert plotting.theta_text(0.95625, 0.95625 - theta_c) == r"$\theta$ = 0.95625"


def test_closed_herpolhode_marks():
    """Start, arrow along the motion, L axis at the origin, dashed r_min/r_max circles;
    odd n drawn over T/2 (closes_after), in which the curve already closes."""
    from orbits.figures import draw_closed_herpolhode

    table = orbits.closed_orbits(FIG6, n_max=4)
    for row in table.itertuples():
        ax = new_figure().add_subplot()
        marks = draw_closed_herpolhode(ax, FIG6, row, limit=0.6)
        xy = marks["curve"].get_xydata()
        assert marks["periods"] == (0.5 if row.n % 2 else 1.0)
        assert np.abs(xy[-1] - xy[0]).max() <= 1e-9
        np.testing.assert_array_equal(marks["start"].get_xydata()[0], xy[0])
        assert tuple(marks["centre"].get_xydata()[0]) == (0.0, 0.0)
        radii = sorted(c.get_radius() for c in marks["circles"])
        assert radii == list(plotting.herpolhode_radii(FIG6, dtheta=row.dtheta))
        assert all(c.get_linestyle() not in ("-", "solid") for c in marks["circles"])
        # the arrow runs from the start to a later point of the curve
        tail, head = np.array(marks["arrow"].xyann), np.array(marks["arrow"].xy)
        np.testing.assert_array_equal(tail, xy[0])
        later = np.flatnonzero((xy == head).all(axis=1))
        assert later.size and 0 < later[0] < len(xy) // 4
        assert ax.get_xlim() == (-0.6, 0.6) and ax.get_ylim() == (-0.6, 0.6)


# ------------------------------------------------------------------ long curves, bad input
NEAR_SPHERE = Body((1.0, 1.0001, 1.0002))


def test_a_curve_of_many_turns_keeps_at_least_100_samples_a_turn():
    """600 samples a turn stopped at 16,666 turns (10^7 samples, a figure set
    of such a body failed half-way); a longer curve now keeps 2*10^6 samples,
    never fewer than 100 a turn, up to MAX_TURNS."""
    assert plotting.herpolhode_points(1) == 2001
    assert plotting.herpolhode_points(3000) == 1_800_001
    assert plotting.herpolhode_points(10_000) == 2_000_001
    assert plotting.herpolhode_points(50_000) == 5_000_001
    assert plotting.herpolhode_points(plotting.MAX_TURNS) <= orbits.motion.MAX_POINTS
    turns = 3 * float(orbits.total_phase(NEAR_SPHERE, 0.01)) / (2 * np.pi)
    assert 16_667 < turns < 50_000
    ax = new_figure().add_subplot()
    xy = plotting.plot_herpolhode(ax, NEAR_SPHERE, 0.01, periods=3).get_xydata()
    assert len(xy) == plotting.herpolhode_points(turns) == round(100 * turns) + 1
    # the curve drawn winds as many times about the L axis (one more a
    # period: the polhode's own turn), each step a hundredth of a turn
    angle = np.unwrap(np.arctan2(xy[:, 1], xy[:, 0]))
    assert (angle[-1] - angle[0]) / (2 * np.pi) == pytest.approx(turns + 3, abs=0.01)
    assert np.abs(np.diff(angle)).max() <= 1.01 * 2 * np.pi / 100
    # and touches both of its bounding circles
    radius = np.hypot(xy[:, 0], xy[:, 1])
    r_min, r_max = plotting.herpolhode_radii(NEAR_SPHERE, 0.01)
    assert radius.min() == pytest.approx(r_min, rel=1e-4)
    assert radius.max() == pytest.approx(r_max, rel=1e-4)


def test_too_many_turns_are_refused_naming_the_argument():
    ax = new_figure().add_subplot()
    motion = orbits.Motion.from_spin(T_HANDLE, 0.5)
    for body, angle in ((motion, None), (T_HANDLE, 0.5)):
        with pytest.raises(orbits.errors.InputError) as caught:
            plotting.plot_herpolhode(ax, body, angle, periods=1e7)
        assert str(caught.value).startswith("the herpolhode over periods=1e+07 makes about 1.")
        assert "more than the 99999 a drawn curve may have" in str(caught.value)
    assert not ax.get_lines()


def _axes(projection=None):
    return new_figure().add_subplot(projection=projection)


@pytest.mark.parametrize(
    "draw, message",
    [
        (
            lambda: plotting.plot_phase_curves(_axes(), T_HANDLE, points=0),
            "points must be an integer >= 4",
        ),
        (
            lambda: plotting.plot_phase_curves(_axes(), T_HANDLE, points=1),
            "points must be an integer >= 4",
        ),
        (
            lambda: plotting.plot_phase_curves(_axes(), T_HANDLE, points=10**9),
            "points must be an integer <= 100000",
        ),
        (
            lambda: plotting.plot_total_phase(_axes(), T_HANDLE, n_levels=10**6),
            "n_levels must be an integer <= 1000",
        ),
        (
            lambda: plotting.plot_total_phase(_axes(), T_HANDLE, points=2),
            "points must be an integer >= 4",
        ),
        (
            lambda: plotting.plot_polhode_foliation(_axes("3d"), T_HANDLE, energy=-1),
            "energy must be positive and finite, got -1.0",
        ),
        (
            lambda: plotting.plot_polhode_foliation(_axes("3d"), T_HANDLE, cmap="nope"),
            "cmap 'nope' is not the name of a matplotlib colormap",
        ),
        (
            lambda: plotting.plot_omega_components(_axes(), T_HANDLE, 0.5, points=0),
            "points must be an integer >= 2",
        ),
        (
            lambda: plotting.plot_omega_components(_axes(), T_HANDLE, 0.5, points=10**9),
            "points must be an integer <= 10000000",
        ),
        (
            lambda: plotting.plot_omega_components(_axes(), T_HANDLE, 0.5, periods=0),
            "periods must be positive and finite, got 0.0",
        ),
        (
            lambda: plotting.plot_omega_components(_axes(), T_HANDLE, 0.5, periods=-2),
            "periods must be positive and finite, got -2.0",
        ),
        (
            lambda: plotting.plot_herpolhode(
                _axes(), orbits.Motion.from_spin(T_HANDLE, 0.5), periods=0
            ),
            "periods must be positive and finite, got 0.0",
        ),
        (
            lambda: plotting.plot_herpolhode(
                _axes(), orbits.Motion.from_spin(T_HANDLE, 0.5), points=1
            ),
            "points must be an integer >= 2",
        ),
        (
            lambda: plotting.plot_body_space(_axes(), resolution=0),
            "resolution must be an integer >= 2",
        ),
        (
            lambda: plotting.plot_body_space(_axes(), resolution=1),
            "resolution must be an integer >= 2",
        ),
        (
            lambda: plotting.plot_t_handle(_axes("3d"), 0, 0, 0),
            "T-handle l1 must be a finite positive number, got 0",
        ),
        (
            lambda: plotting.plot_t_handle(_axes("3d"), bars="wire"),
            "bars must be 'solid' or 'outline', got 'wire'",
        ),
        (
            lambda: plotting.plot_t_handle(_axes("3d"), shrink=0),
            "shrink must be positive and finite, got 0.0",
        ),
    ],
)
def test_bad_arguments_are_refused_up_front(draw, message):
    """Each was a NaN-limit ValueError, an IndexError, a TypeError, a
    ZeroDivisionError, a MemoryError, minutes of work, or silently accepted."""
    with pytest.raises(orbits.errors.OrbitsError) as caught:
        draw()
    assert str(caught.value).startswith(message), str(caught.value)


def test_the_foliation_axes_state_their_unit():
    ax = _axes("3d")
    plotting.plot_polhode_foliation(ax, T_HANDLE)
    names = sorted(text.get_text() for text in ax.texts)
    assert names == ["$M_1$ (J s)", "$M_2$ (J s)", "$M_3$ (J s)"]


@pytest.mark.parametrize(
    "draw",
    [
        lambda ax: plotting.plot_total_phase(ax, T_HANDLE, legend="no"),
        lambda ax: plotting.plot_phase_curves(ax, T_HANDLE, period_axis="no"),
        lambda ax: plotting.plot_body_space(ax, resolution=20, colorbar="no"),
    ],
)
def test_a_flag_that_is_not_a_bool_is_refused_before_drawing(draw):
    """("no" is a true string: the flag was taken for True.)"""
    ax = _axes()
    with pytest.raises(orbits.ArgumentTypeError, match="must be True or False"):
        draw(ax)
    assert not ax.get_lines() and not ax.collections and not ax.images


# ------------------------------------------------------------------------
# Each test below kills a mutant of orbits.plotting that passed the suite (a
# mutation audit, 2026-11-29: 47 mutants of the figure, plotting, cell and
# limit code; 14 survived, and 11 were caught only by the pixel baselines,
# which skip on other matplotlib/FreeType versions).


@pytest.fixture(scope="module")
def fig6_catalog():
    return orbits.closed_orbits(FIG6, n_max=3, q_max=2)


# M19: the direction arrow runs along the curve for 0.18 r_max of arc length
def test_direction_arrow_length_is_a_fraction_of_r_max(fig6_catalog):
    checked = 0
    for row in fig6_catalog.itertuples():
        r_min, r_max = plotting.herpolhode_radii(FIG6, dtheta=row.dtheta)
        if r_min > 0.8 * r_max:
            continue
        ax = new_figure().add_subplot()
        marks = figures.draw_closed_herpolhode(ax, FIG6, row)
        xy = marks["curve"].get_xydata()
        head = np.array(marks["arrow"].xy)
        k = int(np.flatnonzero((xy == head).all(axis=1))[0])
        steps = np.hypot(*np.diff(xy, axis=0).T)
        arc = steps[:k].sum()
        assert 0.18 * r_max <= arc <= 0.18 * r_max + steps.max() + 1e-15
        checked += 1
    assert checked


# M47: the total-phase plot spans theta over [0, pi/2], the whole curve in view
def test_total_phase_plot_spans_zero_to_half_pi():
    ax = new_figure().add_subplot()
    drawn = plotting.plot_total_phase(ax, FIG6, points=400)
    lo, hi = ax.get_xlim()
    assert lo == 0.0 and hi == pytest.approx(math.pi / 2, rel=1e-15)
    x = drawn["curve"].get_xdata()
    assert x.max() <= hi and x.max() > 1.5


# ---------------------------------------------------------------------------
# Data-level guards for mutants killed here only by the pixel baselines
# (tests/test_figure_images.py skips on any other matplotlib/FreeType pair).


def _numbers(text):
    return [float(x) for x in re.findall(r"-?\d+\.\d+(?:e[+-]?\d+)?", text)]


# M16, M25: a closed orbit's title: theta to 6 decimals, and odd n "closes after 1/2 T"
def test_orbit_label_theta_digits_and_half_period(fig6_catalog):
    for row in fig6_catalog.itertuples():
        text = plotting.orbit_label(row, "fig6")
        theta = re.search(r"\$\\theta\$ = ([0-9.]+)", text).group(1)
        assert len(theta.split(".")[1]) == 6 and abs(float(theta) - row.theta) <= 5e-7
        closes = {(3, 1): "1/2", (2, 1): None, (3, 2): "2", (5, 2): "2"}[(row.n, row.q)]
        if closes:
            assert f"closes after {closes} T" in text
        else:
            assert "closes after" not in text


# M24: the period axis of Fig. 5 is in seconds
def test_phase_curves_period_axis_unit():
    ax = new_figure().add_subplot()
    lines = plotting.plot_phase_curves(ax, Body.preset("t-handle"), points=200)
    assert lines["period_axes"].get_ylabel().startswith("period $T$ (s,")


# M43: theta_text switches to theta - theta_c only when theta rounds to theta_c at 5 decimals
def test_theta_text_switch_precision():
    theta_c = orbits.critical_angle(FIG6)
    dtheta = 2e-4  # 0.0002: differs at the 4th decimal, the same at 3
    assert plotting.theta_text(theta_c + dtheta, dtheta) == rf"$\theta$ = {theta_c + dtheta:.5f}"
