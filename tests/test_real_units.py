"""Real units end to end (issue #21): nearest closed orbits of a real spin,
asteroids by their periods, real-time animations, the notebook reprs."""

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import orbits
from orbits import Body, Motion
from orbits.cli import main

RPM = 2.0 * math.pi / 60.0
EPS = np.finfo(float).eps
PHONE_THROW_RPM = (120.0, 2.0, 1.0)
FIG6_BODY = Body.preset("fig6")


def principal_motion(body, omega):
    """``Motion.from_omega`` of a spin along the principal axes."""
    return Motion.from_omega(body, omega, axes="principal")


def phone():
    return Body.box(0.071, 0.147, 0.0078, 0.17, name="phone")


def euler_rhs(moments):
    i1, i2, i3 = moments

    def rhs(t, w):
        return [
            (i2 - i3) / i1 * w[1] * w[2],
            (i3 - i1) / i2 * w[2] * w[0],
            (i1 - i2) / i3 * w[0] * w[1],
        ]

    return rhs


def check_nearest_rows(body, frame, throw_rpm, q_max):
    """Each row's spin fed back to Motion.from_omega: 2 pi n/q, period_s, the throw's |L|."""
    principal_throw = body.frame @ (np.array(throw_rpm) * RPM)
    throw_momentum = float(np.linalg.norm(body.moments * principal_throw))
    for row in frame.itertuples():
        own = np.array([row.omega_x, row.omega_y, row.omega_z]) * RPM
        principal = body.frame @ own
        motion = principal_motion(body, principal)
        target = 2.0 * math.pi * row.n / row.q
        assert row.q <= q_max
        assert abs(motion.total_phase() - target) <= 1e-9 * target
        # the period two ways: the closed form, and the unit catalog's period
        # (|I| = 1, momentum M_u) scaled to the body's |I| and the throw's |L|:
        # Euler's equations give T = T_u |I| M_u / |L| on the same orbit
        assert motion.period == pytest.approx(row.period_s, rel=1e-9)
        scale = np.linalg.norm(body.moments) * row.momentum / throw_momentum
        assert row.period * scale == pytest.approx(row.period_s, rel=1e-9)
        # ... and Euler's equations integrated over period_s bring omega back
        solution = solve_ivp(
            euler_rhs(body.moments),
            (0.0, row.period_s),
            principal,
            method="DOP853",
            rtol=1e-13,
            atol=1e-13 * np.linalg.norm(principal),
        )
        back = solution.y[:, -1]
        # (measured <= 1e-11 of |omega| on these rows; DOP853 at rtol 1e-13)
        assert np.linalg.norm(back - principal) <= 1e-9 * np.linalg.norm(principal)
        # |L| two ways: the Motion's, and |I omega| of the row's spin
        assert motion.momentum == pytest.approx(throw_momentum, rel=1e-12)
        assert np.linalg.norm(body.moments * principal) == pytest.approx(throw_momentum, rel=1e-12)


def test_phone_throw_nearest_three_closed_orbits(tmp_path):
    out = tmp_path / "near.csv"
    argv = ["catalog", "--box", "0.071", "0.147", "0.0078", "--mass", "0.17"]
    argv += ["--omega", *map(str, PHONE_THROW_RPM), "--units", "rpm", "--nearest", "3"]
    assert main([*argv, "--out", str(out)]) == 0
    frame = orbits.read_catalog(out)
    assert len(frame) == 3
    assert list(frame.columns[-4:]) == ["omega_x", "omega_y", "omega_z", "period_s"]
    check_nearest_rows(phone(), frame, PHONE_THROW_RPM, q_max=1)
    # the throw is on LAM with total phase 5.52 turns: the nearest are n = 6, 5, 7
    assert frame["branch"].tolist() == ["LAM"] * 3
    assert frame["n"].tolist() == [6, 5, 7]


def test_nearest_orbits_python_rational_ranked():
    body = phone()
    frame = orbits.nearest_orbits(body, PHONE_THROW_RPM, 4, q_max=3, units="rpm")
    check_nearest_rows(body, frame, PHONE_THROW_RPM, q_max=3)
    spin = principal_motion(body, body.frame @ (np.array(PHONE_THROW_RPM) * RPM))
    distance = np.abs(frame["total_phase"].to_numpy() - spin.total_phase())
    assert np.all(np.diff(distance) >= 0.0)
    # no orbit of the full search up to the farthest level is nearer and left out
    full = orbits.closed_orbits(body, n_max=8, q_max=3)
    full = full[full["branch"] == spin.branch]
    others = np.abs(full["total_phase"].to_numpy() - spin.total_phase())
    assert np.sort(others)[:4] == pytest.approx(distance, rel=1e-12)


@pytest.mark.parametrize(
    "scale, speed",
    [(2.0**-600, 1.0), (2.0**600, 2.0**-500), (1e-200, 1e100), (1e160, 1e-100), (1e-160, 1.0)],
)
def test_nearest_orbits_at_any_scale_of_doubles(scale, speed):
    """Moments beyond 1e+-154 (docs/conventions.md: any scale of doubles):
    the start spins were squared at the caller's scale (1e-160: 1e-4 off,
    not a closed orbit; 1e-200: ZeroDivisionError; 1e160: OverflowError)."""
    moments, omega = np.array([1.0, 2.0, 2.5]), np.array([1.0, 2.0, 3.0])
    base = orbits.nearest_orbits(Body(moments), omega, k=3)
    frame = orbits.nearest_orbits(Body(moments * scale), omega * speed, k=3)
    exact = math.frexp(scale)[0] == 0.5 and math.frexp(speed)[0] == 0.5  # powers of two
    starts = ["omega_x", "omega_y", "omega_z"]
    ratio = frame[starts].to_numpy() / speed / base[starts].to_numpy()
    assert np.abs(ratio - 1).max() <= (0 if exact else 32 * EPS)
    assert np.abs(frame["period_s"] * speed / base["period_s"] - 1).max() <= 4 * EPS
    assert frame["n"].tolist() == base["n"].tolist()
    # the unit moments are the same to rounding (exactly, for powers of two)
    gap = np.abs(frame["dtheta"].to_numpy() / base["dtheta"].to_numpy() - 1).max()
    assert gap <= (0 if exact else 1e-14)
    # each start is on its orbit: the motion from it has the row's total phase
    for row in frame.itertuples():
        spin = Motion.from_omega(Body(moments * scale), [row.omega_x, row.omega_y, row.omega_z])
        assert spin.total_phase() == pytest.approx(row.total_phase, rel=1e-13)


@pytest.mark.parametrize(
    "moments, omega",
    [
        ([0.9, 1.0, 1.9], [1e-9, 1.0, 1e-10]),  # a math domain error (flat body, near I2)
        ([0.9, 1.0, 1.9], [1e-4, 1.0, 1e-5]),  # starts 2.9e-8 off in period
        ([0.5, 1.0, 1.5], [1e-9, 1.0, 1e-10]),
        ([0.26, 0.55, 0.793662], [-1e-7, 1.0, 3e-8]),
        ([1.0, 1.0 + 1e-6, 1.5], [1e-3, 1.0, 1e-4]),
        # nearly symmetric: z^2 over I3 - I2, and theta_crit next to pi/2
        # (cos and tan of it rounded), put starts 2.8e-5 off in phase
        ([1.0, 2.0 - 1e-12, 2.0], [1.0, 8.99e-11, 1.75e-10]),
        ([1.0, 2.0 - 1e-12, 2.0], [0.3, 0.5, 0.2]),
        ([1.0, 1.0 + 1e-12, 2.0], [0.3, 0.5, 0.2]),
        ([1.0, 1.0 + 1e-12, 2.0], [1e-3, 1.0, 1e-3]),
    ],
)
def test_nearest_orbits_start_on_their_orbits_next_to_the_separatrix(moments, omega):
    """Next to I2 the start was solved from 2E and M^2, whose difference
    2EI2 - M^2 kept ~1e-16/|dtheta| of its digits: a square rounded below
    0 (ValueError), or a start whose orbit was 3e-8 off in period.  The
    invariants come from the row's angles in factored form now: the motion
    from each start has the row's period and total phase to rounding."""
    body = Body(moments)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no UnresolvedOrbitsWarning either
        frame = orbits.nearest_orbits(body, omega, k=3, q_max=2)
    for row in frame.itertuples():
        start = Motion.from_omega(body, [row.omega_x, row.omega_y, row.omega_z])
        assert start.period == pytest.approx(row.period_s, rel=1e-13)
        assert start.total_phase() == pytest.approx(row.total_phase, rel=1e-13)
        assert start.branch == row.branch
        assert np.sign(row.omega_x) == np.sign(omega[0]) and np.sign(row.omega_y) == 1


def test_nearest_orbits_never_skip_an_orbit_left_out_next_to_the_separatrix(capsys):
    """Levels above a branch's phase at |dtheta| = 2.2e-308 exist but cannot
    be stored; the search leaves them out.  nearest_orbits used to rank what
    was left: (1e-160, 1, 1e-160) on (1, 2, 2.5) got n = 504, 503, 502, 144
    rad from the spin's 3310 rad, with exit 0.  Now a ranking those orbits
    could change is refused, and one they cannot change is kept, silently
    (the orbits left out are farther than every row)."""
    moments = (1.0, 2.0, 2.5)

    def nearest_levels(omega, k):
        # the integer levels nearest the spin's total phase (spin_phases:
        # the vector route, not nearest_orbits' Motion); on the spin's branch
        # each level above it has an orbit, and these bodies' branches reach
        # far below the spin
        alpha = float(orbits.spin_phases(moments, omega)["total_phase"].iloc[0])
        n0 = round(alpha / (2 * math.pi))
        return sorted(range(n0 - k - 1, n0 + k + 2), key=lambda n: abs(2 * math.pi * n - alpha))[
            :k
        ]

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        frame = orbits.nearest_orbits(moments, (1e-152, 1.0, 1e-152), 3)
        assert frame["n"].tolist() == nearest_levels((1e-152, 1.0, 1e-152), 3) == [501, 500, 502]
        # 2 pi 505 is left out (the reach is 3172.5 rad), and is the third nearest
        frame = orbits.nearest_orbits(moments, (1e-153, 1.0, 1e-153), 2)
        assert frame["n"].tolist() == nearest_levels((1e-153, 1.0, 1e-153), 2) == [504, 503]
        # the spin lies between the reach and 2 pi 505: 504 is 3.02 rad away,
        # 505 (left out) 3.26: the ranking stands (a bound at the reach
        # itself, 2.78 rad away, refused it)
        spin = (6.672009257679572e-154, 1.0, 6.672009257679572e-154)
        frame = orbits.nearest_orbits(moments, spin, 1)
        assert frame["n"].tolist() == nearest_levels(spin, 1) == [504]
    assert nearest_levels((1e-153, 1.0, 1e-153), 3)[2] == 505
    with pytest.raises(
        orbits.InputError,
        match="the 3 closed orbits nearest it include Delta alpha = 2 pi 505 .*lower k",
    ):
        orbits.nearest_orbits(moments, (1e-153, 1.0, 1e-153), 3)
    # the spin itself is beyond what an orbit's double reaches: no k helps
    assert nearest_levels((1e-160, 1.0, 1e-160), 1) == [527]
    with pytest.raises(orbits.InputError, match="nearest it is Delta alpha = 2 pi 527 = ") as told:
        orbits.nearest_orbits(moments, (1e-160, 1.0, 1e-160), 1)
    assert "lower k" not in str(told.value)
    argv = ["catalog", "--moments", "1", "2", "2.5", "--omega", "1e-300", "1", "1e-300"]
    assert main([*argv, "--nearest", "1200", "--out", "-"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "2.2e-308" in err


def test_nearest_orbits_refuses_bad_input():
    with pytest.raises(orbits.InputError, match="unknown angular-velocity unit"):
        orbits.nearest_orbits(phone(), PHONE_THROW_RPM, 3, units="rps")
    with pytest.raises(orbits.AngleError):
        orbits.nearest_orbits(phone(), (1.0, np.nan, 0.0), 3)
    # not real numbers: an OrbitsError naming omega (were bare ValueError/TypeError)
    for omega in ([[120, 2], 1], ["a", 2, 1], [120j, 2, 1], "abc", None):
        with pytest.raises(orbits.OrbitsError, match="omega"):
            orbits.nearest_orbits(phone(), omega, 3)
    assert main(["catalog", "--preset", "fig6", "--nearest", "2", "--out", "-"]) == 2


# --------------------------------------------------------------- asteroids by their periods
APOPHIS = ("--moments", "0.61", "0.965", "1")


def test_apophis_from_its_periods(capsys):
    import io

    import pandas as pd

    argv = ["phase", *APOPHIS, "--periods", "263", "27.38", "--time-unit", "h", "--csv"]
    assert main(argv) == 0
    table = pd.read_csv(io.StringIO(capsys.readouterr().out), comment="#")
    sam = table[table["branch"] == "SAM"].iloc[0]
    # Pravec et al. (2014): E/E0 = 1.024 for Apophis on SAM
    assert round(sam["E_over_E0"], 4) == 1.0236
    assert sam["P_psi"] == pytest.approx(263.0, rel=1e-12)
    assert sam["P_phi"] == pytest.approx(27.38, rel=1e-9)
    # E/E0 a second way: 2 E I3 / M^2 from the printed spin vector itself
    body = Body((0.61, 0.965, 1.0))
    w = sam[["w1", "w2", "w3"]].to_numpy(dtype=float)
    two_e = float(np.sum(body.moments * w * w))
    m_sq = float(np.sum((body.moments * w) ** 2))
    assert two_e * 1.0 / m_sq == pytest.approx(sam["E_over_E0"], rel=1e-12)
    # the period ratio a second way: the closed-form total phase (cel), SAM
    total = orbits.total_phase(body, dtheta=sam["dtheta"])
    assert total / (2 * math.pi) + 1.0 == pytest.approx(263.0 / 27.38, rel=1e-10)
    # and the rotation period: T = P_psi at |omega0| in rad/h
    assert principal_motion(body, w).period == pytest.approx(263.0, rel=1e-12)
    # the text table names the units of the periods and the frame of omega
    assert main(["phase", *APOPHIS, "--periods", "263", "27.38", "--time-unit", "h"]) == 0
    text = capsys.readouterr().out
    assert "P_psi        [h]" in text and "[rad/h, principal axes I1<I2<I3]" in text


def test_periods_in_other_units_agree():
    hours = orbits.spins_with_periods((0.61, 0.965, 1.0), 263.0, 27.38)
    days = orbits.spins_with_periods((0.61, 0.965, 1.0), 263.0 / 24, 27.38 / 24)
    assert days["E_over_E0"].to_numpy() == pytest.approx(hours["E_over_E0"].to_numpy(), 1e-12)
    assert 24 * days["P_about_L"].to_numpy() == pytest.approx(hours["P_about_L"].to_numpy())


def test_time_unit_needs_periods(capsys):
    assert main(["phase", *APOPHIS, "--theta", "0.3", "--time-unit", "h"]) == 2
    assert "--time-unit applies to --periods" in capsys.readouterr().err


# --------------------------------------------------------------- units and words
def test_constants_unit_and_deprecated_unit(capsys):
    water = ("--rotational-constants", "835840.3", "435351.7", "278138.7")
    argv = ["phase", *water, "--defect", "flatten", "--theta", "0.3", "--csv"]
    assert main([*argv, "--constants-unit", "MHz"]) == 0
    new = capsys.readouterr()
    assert "deprecated" not in new.err
    assert main([*argv, "--unit", "MHz"]) == 0
    old = capsys.readouterr()
    assert old.out == new.out
    notes = [line for line in old.err.splitlines() if "deprecated" in line]
    assert notes == [
        "orbits: note: --unit is deprecated; use --constants-unit (the unit of "
        "--rotational-constants; --units is the unit of a spin)"
    ]


def test_deprecated_unit_with_a_spin_unit_names_units(capsys):
    """``--unit rad/s`` (meant as ``--units``) reached the hidden old name of
    --constants-unit and was refused as a choice of cm-1, MHz, GHz alone."""
    argv = ["animate", "--preset", "fig6", "--theta", "0.5", "--unit", "rad/s"]
    assert main([*argv, "--out", "never.gif"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "--unit is the old name of --constants-unit" in err[0]
    assert "the unit of a spin is --units" in err[0]


@pytest.mark.parametrize("command", ["phase", "catalog", "animate"])
def test_units_help_says_what_hz_is(command, capsys):
    """1 Hz as an angular velocity is one revolution per second (2 pi rad/s),
    which --help did not say (an audit: it could read as 1/s = 1 rad/s)."""
    assert main([command, "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "rpm and Hz are revolutions per minute and per second: 1 Hz = 2 pi rad/s" in text


def test_phase_omega_prints_units_frame_and_flip(capsys):
    argv = ["phase", "--box", "0.071", "0.147", "0.0078", "--mass", "0.17"]
    assert main([*argv, "--omega", "120", "2", "1", "--units", "rpm"]) == 0
    text = capsys.readouterr().out
    lines = {line.split()[0]: line for line in text.splitlines() if line.strip()}
    assert "[rad/s, principal axes I1<I2<I3]" in lines["w2"]
    assert "[J s]" in lines["momentum"] and "[s]" in lines["period"]
    period = float(lines["period"].split()[-1])
    assert f"every T/2 = {0.5 * period:.6g} s" in text and "flip" in text
    # a spin far from I2: no flip claimed
    assert main([*argv, "--omega", "0", "2", "100", "--units", "rpm"]) == 0
    assert "no flip is seen" in capsys.readouterr().out
    # exactly along z (the phone's I3): a steady spin, said so
    assert main([*argv, "--omega", "0", "0", "100", "--units", "rpm"]) == 0
    assert "steady spin about I3" in capsys.readouterr().out


def test_phase_omega_of_moments_near_the_largest_double(capsys):
    """2 E T / M was formed as it reads: 2 E T overflowed for moments near
    1e307 (exit 2, "not finite"), where spin_phases gives the phases."""

    def phases(scale):
        argv = ["phase", "--moments", *(str(v * scale) for v in (1.0, 1.5, 2.0))]
        assert main([*argv, "--omega", "1", "1", "1"]) == 0
        lines = capsys.readouterr().out.splitlines()
        return {
            name: float(line.split()[-1])
            for line in lines
            for name in ("dynamic_phase", "total_phase", "geometric_phase")
            if line.startswith(name + " ")
        }

    base, huge = phases(1.0), phases(1e307)
    assert set(huge) == {"dynamic_phase", "total_phase", "geometric_phase"}
    for name, value in base.items():
        assert huge[name] == pytest.approx(value, rel=8 * EPS)
    assert base["dynamic_phase"] - base["geometric_phase"] == pytest.approx(
        base["total_phase"], rel=4 * EPS
    )


def test_singular_and_plural(capsys, tmp_path):
    out = str(tmp_path / "c.csv")
    assert main(["catalog", "--preset", "fig6", "--n-max", "3", "--out", out]) == 0
    err = capsys.readouterr().err
    assert "of 1 body written" in err and "body(ies)" not in err


# --------------------------------------------------------------- flat limit of measured bodies
@pytest.mark.parametrize("option", ["--point-masses", "--mesh"])
def test_measured_bodies_pass_defect_flatten(option, tmp_path, capsys, monkeypatch):
    """``--defect flatten`` reaches the constructor as ``defect="flatten"`` and its
    warning (the excess removed) is printed as one line; the default passes none."""
    import warnings

    calls = []

    def fake(*args, **options):
        calls.append(options.get("defect"))
        if options.get("defect") == "flatten":
            warnings.warn(
                "excess 0.13 % of I3 removed: I3 set to I1 + I2 (flat body)", stacklevel=2
            )
        return Body((1.0, 2.0, 3.0))

    name = "from_point_masses" if option == "--point-masses" else "from_mesh"
    monkeypatch.setattr(Body, name, fake)
    path = tmp_path / "masses.csv"
    path.write_text("mass,x,y,z\n1,1,0,0\n1,-1,0,0\n2,0,0.5,0\n2,0,-0.5,0.1\n")
    argv = ["phase", option, str(path), "--theta", "0.3", "--csv"]
    assert main(argv) == 0
    assert main([*argv, "--defect", "flatten"]) == 0
    assert calls == [None, "flatten"]
    err = capsys.readouterr().err
    assert err.count("orbits: warning: excess 0.13 % of I3 removed") == 1


# --------------------------------------------------------------- a real throw, animated
def test_phone_throw_animates_in_real_time(tmp_path, capsys):
    from PIL import Image

    out = tmp_path / "throw.gif"
    argv = ["animate", "--box", "0.071", "0.147", "0.0078", "--mass", "0.17"]
    argv += ["--omega", *map(str, PHONE_THROW_RPM), "--units", "rpm", "--fps", "4"]
    assert main([*argv, "--out", str(out)]) == 0
    body = phone()
    motion = principal_motion(body, body.frame @ (np.array(PHONE_THROW_RPM) * RPM))
    frames = round(motion.period * 4) + 1  # one period T = 2.337 s at 4 frames/s
    with Image.open(out) as image:
        assert image.size[0] >= 960
        assert image.n_frames == frames
        assert image.info["duration"] == 250  # ms per frame: real time at 4 frames/s
    err = capsys.readouterr().err
    assert f"over {motion.period:.4g} s = 1 period at 4 frames/s (real time)" in err


def test_real_time_library_and_clock():
    from orbits import animate

    body = phone()
    motion = principal_motion(body, body.frame @ (np.array(PHONE_THROW_RPM) * RPM))
    drawn = animate.poinsot_animation(motion, seconds=1.0, fps=5, dpi=20)
    assert len(drawn.times) == 6 and drawn.times[-1] == pytest.approx(1.0, rel=1e-15)
    drawn.frame(5)
    assert drawn._clock.get_text() == f"t = 1.000 s = {1.0 / motion.period:.3f} T"
    assert drawn.figure.get_size_inches()[0] * animate.DEFAULT_DPI >= 960
    with pytest.raises(orbits.InputError, match="not both"):
        animate.poinsot_animation(motion, seconds=1.0, frames=5)


# --------------------------------------------------------------- notebooks
def test_html_reprs_carry_units():
    body = phone()
    html = body._repr_html_()
    assert "phone" in html and "kg m^2" in html and "7.227606667e-05" in html
    motion = principal_motion(body, body.frame @ (np.array(PHONE_THROW_RPM) * RPM))
    html = motion._repr_html_()
    assert "LAM" in html and f"{motion.period:.10g}" in html and "J s" in html
    assert f"{motion.total_phase():.10g}" in html and "principal axes" in html
    periods = motion.tumbling_periods()
    assert f"{periods.precession:.10g}" in periods._repr_html_()
    assert isinstance(periods, tuple) and periods.rotation == motion.period
    limits = orbits.phase_limits(body)
    assert f"{limits.theta_zero:.10g}" in limits._repr_html_() and "rad" in limits._repr_html_()
    report = orbits.verify(n_bodies=2, n_angles=2)
    assert repr(report).startswith("VerifyReport(passed=True, 4 initial conditions")
    assert "passed" in report._repr_html_()


def test_animation_html_shown_once():
    import matplotlib.pyplot as plt

    body = phone()
    motion = principal_motion(body, body.frame @ (np.array(PHONE_THROW_RPM) * RPM))
    drawn = orbits.poinsot_animation(motion, frames=3, dpi=20, pyplot=True)
    number = drawn.figure.number
    assert plt.fignum_exists(number)
    html = drawn._repr_html_()
    assert "<script" in html and "animation" in html.lower()
    assert not plt.fignum_exists(number)  # no second, static figure below the player
    assert {"poinsot_animation", "PoinsotAnimation", "flip_motion", "orbit_row"} <= set(
        orbits.__all__
    )


def test_the_notebook_player_holds_every_frame():
    """The default animation (120 frames) made a 21 MB player that held 68
    frames: matplotlib drops every frame past its 20 MB embed limit.  JPEG
    frames fit; past the limit a warning says how many frames are shown."""
    import re

    import matplotlib

    drawn = orbits.poinsot_animation(FIG6_BODY, 1.2)
    html = drawn._repr_html_()
    held = len(re.findall(r'frames\[\d+\] = "data:image/jpeg', html))
    assert held == len(drawn.times) == 120
    assert len(html) < 0.75 * matplotlib.rcParams["animation.embed_limit"] * 2**20
    # some frames held, then none (the first frame alone past the limit)
    for limit, held in ((0.05, r"[1-9]"), (0.001, "0")):
        small = orbits.poinsot_animation(FIG6_BODY, 1.2, frames=12, dpi=60)
        with matplotlib.rc_context({"animation.embed_limit": limit}):
            with pytest.warns(
                UserWarning, match=rf"holds {held} of the animation's 12 frames"
            ) as caught:
                small.to_html()
        assert caught[0].filename == __file__


def test_copies_of_results_stay_read_only_and_draw():
    """A pickled or deep-copied Body had writeable moments (an edit changed its
    repr and hash, not its phases); Motion.omega0 was writeable; an
    unpickled PoinsotAnimation could not render ("no attribute buffer_rgba")."""
    import copy
    import pickle

    body = phone()
    for twin in (pickle.loads(pickle.dumps(body)), copy.deepcopy(body)):
        assert twin == body and hash(twin) == hash(body)
        for array in (twin.moments, twin.unit_moments, twin.frame):
            with pytest.raises(ValueError, match="read-only"):
                array[0] = 0.7
    motion = Motion.from_spin(body, 0.3)
    for one in (motion, pickle.loads(pickle.dumps(motion)), copy.copy(motion)):
        with pytest.raises(ValueError, match="read-only"):
            one.omega0[0] = 0.1
    drawn = orbits.poinsot_animation(FIG6_BODY, 1.2, frames=4, dpi=40)
    first = drawn.render(2)
    drawn.to_html()  # its FuncAnimation (a lambda) is not carried along
    for twin in (pickle.loads(pickle.dumps(drawn)), copy.deepcopy(drawn)):
        assert np.array_equal(twin.render(2), first)


def test_a_body_shows_its_axes_where_they_are_not_the_callers():
    """Body([3, 1, 2]) showed as Body((1, 2, 3)), which it does not equal."""
    permuted = Body([3.0, 1.0, 2.0])
    shown = repr(permuted)
    assert shown == "Body((1, 2, 3), frame=((0.0, 1.0, 0.0), (0.0, 0.0, 1.0), (1.0, 0.0, 0.0)))"
    assert eval(shown, {"Body": Body}) == permuted != Body((1.0, 2.0, 3.0))
    assert repr(Body((1.0, 2.0, 3.0), name="a")) == "Body((1, 2, 3), name='a')"


# --------------------------------------------------------------- bodies beyond the doubles
def _unit_i1(text):
    return float(next(line for line in text.splitlines() if line.startswith("I1")).split()[-1])


def test_box_phases_do_not_depend_on_the_scale(capsys):
    """1e-160 m edges and 1e30 kg (moments 1e-290): the I1 of the 1 m box (0.231963)."""
    assert main(["phase", "--box", "1", "2", "3.5", "--theta", "0.5"]) == 0
    base = _unit_i1(capsys.readouterr().out)
    assert base == pytest.approx(0.231963, abs=5e-7)
    argv = ["phase", "--box", "1e-160", "2e-160", "3.5e-160", "--mass", "1e30", "--theta", "0.5"]
    assert main(argv) == 0
    assert _unit_i1(capsys.readouterr().out) == pytest.approx(base, rel=1e-14)


@pytest.mark.parametrize(
    "body, words",
    [
        (["--box", "1e-160", "2e-160", "3.5e-160"], "I_z = 4.17e-321: it underflows"),
        (["--cylinder", "1", "2", "1.5", "--mass", "1e-320"], "mass 1e-320 is below"),
        (["--t-handle", "1e-200", "2e-200", "3e-201"], "it underflows below"),
        (["--t-handle", "1e200", "4", "1"], "it overflows a double"),
        (
            ["--rotational-constants", "1e265", "2e265", "3e265"],
            "I_A = 9.33e-312 kg m^2: it underflows",
        ),
        (["--ellipsoid", "0", "0.3"], "needs 0 <= c < b < a"),
    ],
)
def test_bodies_beyond_the_doubles_exit_2(body, words, capsys):
    assert main(["phase", *body, "--theta", "0.5"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("orbits: error: ") and err.count("\n") == 1, err
    assert words in err
    # underflow is never called an overflow, nor the reverse
    assert ("overflow" in err) == ("overflows" in words)


def test_point_masses_at_1e200_exit_2_without_traceback(tmp_path):
    """Positions ~1e200 ended in numpy's LinAlgError (exit 1); now one line, exit 2."""
    import os
    import subprocess
    import sys

    path = tmp_path / "far.csv"
    path.write_text("mass,x,y,z\n1,0,0,0\n2,1e200,2e199,0\n3,3e199,1.4e200,5e199\n")
    root = os.path.dirname(os.path.dirname(os.path.abspath(orbits.__file__)))
    env = dict(os.environ, PYTHONPATH=root)
    argv = [sys.executable, "-m", "orbits", "phase", "--point-masses", str(path), "--theta", "0.5"]
    done = subprocess.run(argv, capture_output=True, text=True, env=env, timeout=300)
    assert done.returncode == 2, done.stderr
    assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr
    assert "I3 = 3.68e+400: it overflows a double" in done.stderr


def test_molecules_and_point_masses_show_si_units_in_notebooks():
    """A body whose constructor knows its moments' unit labels E, |L| and D in
    J, J s and kg m^2 (a molecule's were shown as 'I rad^2/s^2')."""
    import re

    def text(motion):
        return " ".join(re.sub("<[^>]+>", " ", motion._repr_html_()).split())

    molecule = Body.from_rotational_constants(10, 5, 4, unit="GHz")
    masses = Body.from_point_masses([1.0, 2.0, 3.0], np.eye(3))
    assert molecule.moment_unit == "kg m^2"
    assert masses.moment_unit == Body.box(1, 2, 3).moment_unit
    assert masses.moment_unit.startswith("kg m^2")
    assert Body((1.0, 2.0, 2.5)).moment_unit is None
    shown = text(Motion.from_spin(molecule, 0.3, speed=1e3))
    assert re.search(
        r"energy E \S+ J angular momentum \|L\| \S+ J s D = M\^2 / \(2E\) \S+ kg m\^2 ", shown
    ), shown
    # a solid's moments are in its inputs' units: SI only for lengths in m
    # and mass in kg (a phone in cm and g was shown with its energy in "J")
    for body in (masses, Body.box(7.1, 14.7, 0.78, mass=170)):
        shown = text(Motion.from_spin(body, 0.3, speed=1e3))
        when = r" \(lengths in m, mass in kg\)"
        assert re.search(
            rf"energy E \S+ J{when} angular momentum \|L\| \S+ J s{when} "
            rf"D = M\^2 / \(2E\) \S+ kg m\^2{when}",
            shown,
        ), shown
    for body in (molecule, masses):
        assert "kg m^2" in " ".join(re.sub("<[^>]+>", " ", body._repr_html_()).split())
    plain = text(Motion.from_spin(Body((1.0, 2.0, 2.5)), 0.3))
    assert "I rad^2/s^2" in plain and " J " not in plain


def test_too_many_nearest_orbits_name_the_options_that_apply(capsys):
    """--nearest 1000000000 was refused with "lower --n-max or --q-max",
    and --n-max does not apply with --nearest."""
    argv = ["catalog", "--preset", "fig6", "--omega", "1", "2", "3", "--nearest", "1000000000"]
    assert main([*argv, "--out", "-"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--n-max" not in err[0], err
    assert err[0].startswith(
        "orbits: error: the 1000000000 closed orbits nearest this spin need a search up to "
        "n = 1000000002 ("
    )
    assert err[0].endswith(
        "beyond this machine; lower k (--nearest) or --q-max, or take a spin farther from "
        "the separatrix"
    )


def test_time_units_in_seconds():
    from orbits.units import TIME_UNITS, time_factor

    assert [time_factor(u) for u in ("s", "min", "h", "d")] == [1.0, 60.0, 3600.0, 86400.0]
    assert list(TIME_UNITS) == ["s", "min", "h", "d"]
    with pytest.raises(orbits.InputError, match="unknown time unit 'yr'"):
        time_factor("yr")
