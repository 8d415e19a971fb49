"""Exact motion: against DOP853, against mpmath, conventions and curves."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

import orbits
from orbits import AngleError, Body, InputError, Motion, SeparatrixError
from orbits.checks import exact_motion_mpmath
from orbits.core.ode import euler_rhs

FIG6 = Body.preset("fig6")
T_HANDLE = Body.t_handle(8, 4, 1)


def euler_from_rotation(r):
    """(phi, theta, psi) of R = Rz(phi) Rx(theta) Rz(psi), componentwise.

    theta from atan2 of its sine and cosine (the third column), which is
    well conditioned at every theta; arccos(R33) would amplify rounding by
    1/sin(theta) near the I3 axis.
    """
    theta = np.arctan2(np.hypot(r[..., 0, 2], r[..., 1, 2]), r[..., 2, 2])
    phi = np.arctan2(r[..., 0, 2], -r[..., 1, 2])
    psi = np.arctan2(r[..., 2, 0], r[..., 2, 1])
    return phi, theta, psi


def circular(a, b):
    d = np.mod(a - b, 2 * np.pi)
    return np.minimum(d, 2 * np.pi - d)


# DOP853 at the tightest tolerance scipy accepts (100 eps); measured against
# the exact motion it stays within 6e-12 over ten periods on every case of
# test_matches_dop853_over_ten_periods, so it is >10x more accurate than
# that test's bound.
REFERENCE_RTOL = 2.5e-14
REFERENCE_ATOL = 1e-16


def integrate(motion, times, rtol=REFERENCE_RTOL):
    """DOP853 from the exact motion's initial omega and orientation."""
    inertia = motion.body.moments
    q0 = np.roll(Rotation.from_matrix(motion.rotation(np.array([0.0]))[0]).as_quat(), 1)

    def rhs(t, y):
        dy = np.empty(7)
        euler_rhs(inertia, y, dy)
        return dy

    solution = solve_ivp(
        rhs,
        (0.0, times[-1]),
        np.concatenate([motion.omega0, q0]),
        method="DOP853",
        rtol=rtol,
        atol=REFERENCE_ATOL,
        t_eval=times,
    )
    assert solution.success
    rotation = Rotation.from_quat(np.roll(solution.y[3:].T, -1, axis=-1)).as_matrix()
    return solution.y[:3].T, rotation


def random_cases():
    """Bodies over the region, both branches, near-separatrix and near-axis."""
    rng = np.random.default_rng(2024)
    bodies = orbits.bodies.region_sample(40)[::5]
    cases = []
    for k, moments in enumerate(bodies):
        body = Body(moments)
        theta_c = body.critical_angle()
        cases.append((body, dict(theta=rng.uniform(0.05, 0.95) * theta_c, phi=rng.uniform(-3, 3))))
        cases.append(
            (
                body,
                dict(
                    theta=theta_c + rng.uniform(0.05, 0.95) * (np.pi / 2 - theta_c),
                    phi=rng.uniform(-3, 3),
                ),
            )
        )
    cases += [
        (FIG6, dict(dtheta=-3e-3)),  # 1 - m ~ 1e-2, SAM
        (FIG6, dict(dtheta=3e-3)),  # LAM
        (T_HANDLE, dict(theta=1e-6)),  # near the I3 axis
        (T_HANDLE, dict(theta=np.pi / 2 - 1e-6)),  # near the I1 axis
        (T_HANDLE, dict(theta=np.pi / 2 - 0.15, phi=np.pi / 2 - 0.2)),
    ]
    return cases


@pytest.mark.parametrize("body, spin", random_cases())
def test_matches_dop853_over_ten_periods(body, spin):
    """omega, Euler angles and orientation agree with DOP853 to 1e-10.

    Both follow the orbit of the same double-precision omega0.  Closer to
    the separatrix (1 - m ~ 1e-4) the orbit itself amplifies the rounding
    of a double-precision integration to ~3e-10 over ten periods, whatever
    its tolerance, so DOP853 is no longer 10x more accurate than the
    bound; there the motion is checked against mpmath at 40 digits
    (test_matches_mpmath_down_to_one_minus_m_1e12).
    """
    motion = Motion.from_omega(body, Motion.from_spin(body, **spin).omega0)
    times = np.linspace(0.0, 10.0 * motion.period, 801)
    state = motion.state(times)
    omega, rotation = integrate(motion, times)
    bound = 1e-10
    assert np.abs(omega - state.omega).max() <= bound
    assert np.abs(rotation - state.rotation).max() <= bound
    phi, theta, psi = euler_from_rotation(rotation)
    assert np.abs(theta - state.euler[:, 1]).max() <= bound
    if np.sin(state.euler[:, 1]).min() > 1e-3:
        assert circular(phi, state.euler[:, 0]).max() <= bound
        assert circular(psi, state.euler[:, 2]).max() <= bound
    else:
        # near the I3 axis phi and psi turn about (almost) the same axis:
        # only their sum is defined by the orientation
        assert circular(phi + psi, state.euler[:, 0] + state.euler[:, 2]).max() <= bound


@pytest.mark.parametrize("branch_sign", [-1.0, 1.0], ids=["SAM", "LAM"])
@pytest.mark.parametrize("one_minus_m", [1e-6, 1e-9, 1e-12])
def test_matches_mpmath_down_to_one_minus_m_1e12(branch_sign, one_minus_m):
    # find the offset that gives this 1 - m (it is close to linear in dtheta)
    def gap(log_offset):
        motion = Motion.from_spin(FIG6, dtheta=branch_sign * 10.0**log_offset)
        return math.log10(motion.one_minus_m) - math.log10(one_minus_m)

    log_offset = brentq(gap, -20, -1, xtol=1e-3)
    seed = Motion.from_spin(FIG6, dtheta=branch_sign * 10.0**log_offset)
    motion = Motion.from_omega(FIG6, seed.omega0)
    assert 0.3 < motion.one_minus_m / one_minus_m < 3.0
    times = np.linspace(0.0, 10.0 * motion.period, 13)
    euler, state = assert_matches_mpmath(motion, times, 1e-12, dps=40)
    assert np.abs(state.euler[:, 1] - euler[:, 1]).max() <= 1e-12
    assert circular(state.euler[:, 2], euler[:, 2]).max() <= 1e-12


def assert_matches_mpmath(motion, times, bound, dps):
    """omega, omega in space and phi (relative to its size) within ``bound`` of mpmath."""
    omega, euler, omega_space = exact_motion_mpmath(
        motion.body.moments, motion.omega0, times, dps=dps
    )
    state = motion.state(times)
    assert np.abs(state.omega - omega).max() <= bound
    assert np.abs(state.omega_space - omega_space).max() <= bound
    assert np.abs(state.euler[:, 0] - euler[:, 0]).max() <= bound * max(1.0, abs(euler[-1, 0]))
    return euler, state


@pytest.mark.parametrize(
    "omega0",
    [
        (6.123233995736766e-17, 1.0, 6.123233995736766e-17),  # theta = phi = pi/2
        (1e-12, 1.0, -3e-12),
        (-1e-8, 1.0, 2e-8),
        (1e-5, -1.0, 1e-5),
        (2e-10, 1.0, -1e-10),  # LAM
        (-3e-16, -1.0, 1e-16),  # LAM
    ],
)
def test_spin_near_the_unstable_axis_matches_mpmath(omega0):
    """A spin within 1e-5..6e-17 of the I2 axis: the Dzhanibekov flip on time.

    The start argument u0 = F(am0) has am0 within ~1e-16 of pi/2, where
    the amplitude itself rounds; it is formed from the complementary
    amplitude.  (Before, ``(6e-17, 1, 6e-17)`` flipped at the wrong time:
    |omega| wrong by 1.2 after two periods; 1e-8 off the axis, by 1e-9.)
    Reference: mpmath at 60 digits from the same double omega0.
    """
    body = Body(FIG6.normalized_moments)
    motion = Motion.from_omega(body, omega0)
    assert_matches_mpmath(motion, np.linspace(0.0, 2.0 * motion.period, 41), 2e-13, dps=60)


def test_sign_convention_rotation_after_one_period():
    """R(T) = Rot(+M, Delta alpha) R(0): omega_space(T) = Rz(+Delta alpha) omega_space(0)."""
    for body, theta in ((FIG6, 0.7), (FIG6, 1.3), (T_HANDLE, 1.2)):
        motion = Motion.from_spin(body, theta)
        alpha = orbits.total_phase(body, theta)
        state = motion.state(np.array([0.0, motion.period]))
        rz = Rotation.from_rotvec([0.0, 0.0, alpha]).as_matrix()
        np.testing.assert_allclose(state.rotation[1], rz @ state.rotation[0], atol=1e-12)
        np.testing.assert_allclose(state.omega_space[1], rz @ state.omega_space[0], atol=1e-12)
        # space z is along M
        momentum = motion.body.moments * state.omega
        np.testing.assert_allclose(
            np.einsum("nij,nj->ni", state.rotation, momentum),
            [[0, 0, motion.momentum]] * 2,
            atol=1e-13,
        )


def test_herpolhode_closes_on_a_whole_turn():
    # an independent root of Delta alpha = 4 pi on the fig6 SAM branch
    theta = brentq(lambda t: orbits.total_phase(FIG6, t) - 4 * np.pi, 0.5, 1.0, xtol=1e-15)
    t, omega = orbits.herpolhode(FIG6, theta, points=4001)
    assert np.abs(omega[-1] - omega[0]).max() <= 1e-9
    # and does not close half-way round the next turn
    theta_half = brentq(lambda t: orbits.total_phase(FIG6, t) - 5 * np.pi, 0.5, 1.01)
    t, omega = orbits.herpolhode(FIG6, theta_half)
    assert np.abs(omega[-1] - omega[0]).max() > 0.1


def test_herpolhode_grid_and_plane():
    t, omega = orbits.herpolhode(FIG6, 0.9, periods=3, points=301)
    motion = Motion.from_spin(FIG6, 0.9)
    assert t.shape == (301,) and omega.shape == (301, 3)
    assert t[0] == 0.0 and t[-1] == pytest.approx(3 * motion.period, rel=1e-15)
    np.testing.assert_allclose(np.diff(t), t[1] - t[0], rtol=1e-12)
    # the invariable plane: omega . M^ = 2E/M
    assert np.abs(omega[:, 2] - 2 * motion.energy / motion.momentum).max() <= 1e-14
    # the in-plane figure is the same as from the full rotation
    full = motion.state(t).omega_space
    assert np.abs(full - omega).max() <= 1e-13
    # scale-free: the same curve for scaled moments
    _, scaled = orbits.herpolhode(FIG6.moments * 37.0, 0.9, periods=3, points=301)
    assert np.abs(scaled - omega).max() <= 1e-13


def test_polhode_lies_on_sphere_and_binet_ellipsoid():
    t, momentum = orbits.polhode(T_HANDLE, 1.2, points=501)
    body = T_HANDLE.normalized_moments
    row = orbits.phases(T_HANDLE, 1.2).iloc[0]
    np.testing.assert_allclose(np.linalg.norm(momentum, axis=1), row.momentum, rtol=1e-14)
    np.testing.assert_allclose((momentum**2 / body).sum(axis=1), 2 * row.energy, rtol=1e-14)


def test_initial_state_and_general_phi():
    motion = Motion.from_spin(T_HANDLE, 1.1, phi=2.3, speed=3.0)
    w0 = 3.0 * np.array([np.sin(1.1) * np.cos(2.3), np.sin(1.1) * np.sin(2.3), np.cos(1.1)])
    state = motion.state(np.array([0.0]))
    np.testing.assert_allclose(state.omega[0], w0, atol=1e-15)
    assert state.euler[0, 0] == 0.0


def test_dzhanibekov_flip():
    """The T-handle spin of Fig. 3: omega_2 reverses twice per period."""
    motion = Motion.from_spin(T_HANDLE, np.pi / 2 - 0.15, phi=np.pi / 2 - 0.2)
    times = np.linspace(0.0, motion.period, 20001)
    w2 = motion.omega(times)[:, 1]
    crossings = np.count_nonzero(np.diff(np.sign(w2)) != 0)
    assert crossings == 2
    assert motion.period == pytest.approx(23.8181, abs=5e-5)


def test_quaternion_is_continuous():
    for theta in (0.4, 1.4):
        motion = Motion.from_spin(FIG6, theta)
        q = motion.quaternion(np.linspace(0.0, 5 * motion.period, 20001))
        assert np.abs(np.diff(q, axis=0)).max() < 0.01
        np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-15)
        r = Rotation.from_quat(np.roll(q, -1, axis=-1)).as_matrix()
        np.testing.assert_allclose(
            r, motion.rotation(np.linspace(0.0, 5 * motion.period, 20001)), atol=1e-13
        )


def test_scaling_omega_scales_time_only():
    motion = Motion.from_spin(FIG6, 0.8)
    fast = Motion.from_omega(FIG6, 2.5 * motion.omega0)
    assert fast.period == pytest.approx(motion.period / 2.5, rel=1e-14)
    assert fast.total_phase() == pytest.approx(motion.total_phase(), rel=1e-14)
    t = np.linspace(0, motion.period, 50)
    np.testing.assert_allclose(fast.omega(t / 2.5), 2.5 * motion.omega(t), atol=1e-14)


def test_steady_spins():
    # about I3 (theta = 0): a plain rotation about z at rate w3
    motion = Motion.from_spin(FIG6, 0.0)
    t = np.linspace(0, 20, 7)
    expected = Rotation.from_rotvec(np.outer(t, [0, 0, 1.0])).as_matrix()
    np.testing.assert_allclose(motion.rotation(t), expected, atol=1e-13)
    # about I1 (theta = pi/2): omega constant along I1
    motion = Motion.from_spin(FIG6, np.pi / 2)
    np.testing.assert_allclose(motion.omega(t), [[1, 0, 0]] * 7, atol=1e-15)


def test_phase_from_motion_matches_closed_form_to_1e300():
    for dtheta in (-1e-300, 1e-300, -1e-30, 1e-5):
        motion = Motion.from_spin(FIG6, dtheta=dtheta)
        assert motion.total_phase() == pytest.approx(
            orbits.total_phase(FIG6, dtheta=dtheta), rel=1e-13
        )


@pytest.mark.parametrize(
    "make, error",
    [
        (lambda: Motion.from_omega(FIG6, [0.0, 1.0, 0.0]), SeparatrixError),
        (lambda: Motion.from_omega(FIG6, [0.0, 0.0, 0.0]), AngleError),
        (lambda: Motion.from_omega(FIG6, [np.nan, 0.0, 1.0]), AngleError),
        (lambda: Motion.from_spin(FIG6, dtheta=0.0), SeparatrixError),
        (lambda: Motion.from_spin(FIG6, dtheta=2.0), AngleError),
        (lambda: Motion.from_spin(FIG6, np.inf), AngleError),
        (lambda: Motion.from_spin(FIG6, 0.5, speed=-1.0), AngleError),
        (lambda: Motion.from_spin(FIG6, 0.5).omega([np.nan]), InputError),
        (lambda: orbits.herpolhode(FIG6, 0.5, points=1), InputError),
        (lambda: orbits.herpolhode(FIG6, 0.5, periods=0), InputError),
    ],
)
def test_bad_input(make, error):
    with pytest.raises(error):
        make()
