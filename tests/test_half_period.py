"""Half-period closure: omega(t + T/2) = D omega(t), R(t + T/2) = Rz(Delta alpha/2 + pi) R(t) D.

The herpolhode of a 2 pi p/q orbit therefore closes after q/2 periods when p
and q are both odd, else after q (the catalog column ``closes_after``).
Checked against the exact motion (elliptic functions, errors ~1e-15) and,
independently, against an integration of Euler's equations and of
dR/dt = R [omega]x (DOP853, rtol 1e-12: errors ~1e-11).
"""

from fractions import Fraction

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import orbits
from orbits import Body, Motion
from orbits.search import closes_after

BODIES = [Body.preset("fig6"), Body.preset("t-handle"), Body((0.3, 0.5, 0.7))]
MIRROR = {"SAM": np.diag([-1.0, -1.0, 1.0]), "LAM": np.diag([1.0, -1.0, -1.0])}


def rot_z(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def test_the_rule():
    assert closes_after(1, 1) == "1/2"
    assert closes_after(2, 1) == "1"
    assert closes_after(5, 3) == "3/2"
    assert closes_after(3, 2) == "2"
    assert closes_after(4, 3) == "3"
    assert list(closes_after([7, 8, 7], [5, 5, 2])) == ["5/2", "5", "2"]


@pytest.mark.parametrize("body", BODIES, ids=lambda b: b.name or "0.3,0.5,0.7")
def test_half_period_symmetry_of_the_exact_motion(body):
    table = orbits.closed_orbits(body, n_max=6, q_max=4)
    assert set(table["branch"]) == {"SAM", "LAM"} and table["q"].max() == 4
    for row in table.itertuples():
        motion = Motion.from_spin(body, dtheta=row.dtheta)
        half = 0.5 * motion.period
        t = np.linspace(0.0, motion.period, 9)
        now, later = motion.state(t), motion.state(t + half)
        mirror = MIRROR[row.branch]
        # body frame: the angular velocity is mirrored (Jacobi cn, sn -> -cn, -sn over 2K)
        np.testing.assert_allclose(later.omega, now.omega @ mirror, rtol=0, atol=1e-13)
        # space frame: turned about M by Delta alpha/2 + pi
        turn = rot_z(0.5 * row.total_phase + np.pi)
        np.testing.assert_allclose(
            later.rotation, turn @ now.rotation @ mirror, rtol=0, atol=1e-11
        )
        # the herpolhode closes after `closes_after` periods, and not before
        # (only whole half periods can close it: |omega|^2 has period T/2)
        periods = Fraction(row.closes_after)
        assert periods == Fraction(row.q, 2 if (row.n % 2 and row.q % 2) else 1)
        dense = np.linspace(0.0, motion.period, 201)
        start = motion.omega_space(dense)
        for halves in range(1, int(2 * periods) + 1):
            gap = np.abs(motion.omega_space(dense + halves * half) - start).max()
            if halves == 2 * periods:
                assert gap <= 1e-10, (row, halves, gap)
            else:
                assert gap >= 1e-3, (row, halves, gap)


def _integrate_half_period(motion):
    moments = motion.body.moments

    def rhs(_, y):
        w = y[:3]
        rotation = y[3:].reshape(3, 3)
        torque_free = np.array(
            [
                (moments[1] - moments[2]) * w[1] * w[2] / moments[0],
                (moments[2] - moments[0]) * w[2] * w[0] / moments[1],
                (moments[0] - moments[1]) * w[0] * w[1] / moments[2],
            ]
        )
        cross = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
        return np.concatenate([torque_free, (rotation @ cross).ravel()])

    start = motion.rotation(np.zeros(1))[0]
    solution = solve_ivp(
        rhs,
        (0.0, 0.5 * motion.period),
        np.concatenate([motion.omega0, start.ravel()]),
        method="DOP853",
        rtol=1e-12,
        atol=1e-14,
    )
    return start, solution.y[:3, -1], solution.y[3:, -1].reshape(3, 3)


@pytest.mark.parametrize("n, branch", [(3, "SAM"), (4, "SAM"), (3, "LAM"), (2, "LAM")])
def test_half_period_by_integrating_euler(n, branch):
    body = Body.preset("fig6")
    table = orbits.closed_orbits(body, n_max=4)
    row = table[(table["n"] == n) & (table["branch"] == branch)].iloc[0]
    motion = Motion.from_spin(body, dtheta=row["dtheta"])
    start, omega, rotation = _integrate_half_period(motion)
    mirror = MIRROR[branch]
    # integration error ~1e-11 over half a period; bounds 100x looser
    np.testing.assert_allclose(omega, mirror @ motion.omega0, atol=1e-9)
    turn = rot_z(0.5 * row["total_phase"] + np.pi)
    np.testing.assert_allclose(rotation, turn @ start @ mirror, atol=1e-9)
    # the space-frame omega: back at its start after T/2 exactly for odd n
    omega_space = rotation @ omega
    back = np.abs(omega_space - start @ motion.omega0).max()
    if n % 2:
        assert back <= 1e-9 and row["closes_after"] == "1/2"
    else:
        assert back >= 1e-2 and row["closes_after"] == "1"


def test_catalog_column_round_trips(tmp_path):
    table = orbits.closed_orbits(Body.preset("fig6"), n_max=5, q_max=3)
    path = tmp_path / "c.csv"
    orbits.write_catalog(table, path)
    back = orbits.read_catalog(path)
    assert back["closes_after"].tolist() == table["closes_after"].tolist()
    assert set(back["closes_after"]) == {"1/2", "1", "3/2", "2", "3"}
