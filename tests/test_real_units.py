"""Real units end to end (issue #21): nearest closed orbits of a real spin,
asteroids by their periods, real-time animations, the notebook reprs."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import orbits
from orbits import Body, Motion
from orbits.cli import main

RPM = 2.0 * math.pi / 60.0
PHONE_THROW_RPM = (120.0, 2.0, 1.0)


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
        motion = Motion.from_omega(body, principal)
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
        assert np.linalg.norm(back - principal) <= 1e-6 * np.linalg.norm(principal)
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
    spin = Motion.from_omega(body, body.frame @ (np.array(PHONE_THROW_RPM) * RPM))
    distance = np.abs(frame["total_phase"].to_numpy() - spin.total_phase())
    assert np.all(np.diff(distance) >= 0.0)
    # no orbit of the full search up to the farthest level is nearer and left out
    full = orbits.closed_orbits(body, n_max=8, q_max=3)
    full = full[full["branch"] == spin.branch]
    others = np.abs(full["total_phase"].to_numpy() - spin.total_phase())
    assert np.sort(others)[:4] == pytest.approx(distance, rel=1e-12)


def test_nearest_orbits_refuses_bad_input():
    with pytest.raises(orbits.InputError, match="unknown angular-velocity unit"):
        orbits.nearest_orbits(phone(), PHONE_THROW_RPM, 3, units="rps")
    with pytest.raises(orbits.AngleError):
        orbits.nearest_orbits(phone(), (1.0, np.nan, 0.0), 3)
    assert main(["catalog", "--preset", "fig6", "--nearest", "2", "--out", "-"]) == 2
