"""Exact motion: against DOP853, against mpmath, conventions and curves."""

import math

import mpmath as mp
import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

import orbits
from orbits import AngleError, Body, InputError, Motion, SeparatrixError
from orbits.checks import exact_motion_mpmath
from orbits.core.ode import euler_rhs
from orbits.phases import fold_angle

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


def test_speed_is_kept_for_any_theta_and_l_is_i_omega_at_any_scale():
    """from_spin folds theta outside [0, pi/2] and keeps |omega0| = speed (a
    fold that dropped the speed gave |omega0| = 1, a period 10x too long);
    angular_momentum is I omega0 in the moments' own units (it lost the
    moments' power-of-two scale, 2**-11 for a box in kg m^2, unseen for
    bodies with I3 in [1/2, 1))."""
    body = Body([1.0, 2.0, 3.0])
    for theta in (2.0, -0.7, 4.0):
        spun = Motion.from_spin(body, theta, phi=0.3, speed=10.0)
        folded = Motion.from_spin(body, float(fold_angle(theta)), phi=0.3, speed=10.0)
        assert np.linalg.norm(spun.omega0) == pytest.approx(10.0, rel=1e-15)
        assert spun.period == pytest.approx(folded.period, rel=1e-14)
        assert spun.energy == pytest.approx(folded.energy, rel=1e-14)
    for body in (
        Body([1.0, 2.0, 3.0]),
        Body.box(0.15, 0.07, 0.008, 0.2),
        Body([1e-200, 2e-200, 2.5e-200]),
    ):
        motion = Motion.from_omega(body, [0.1, 0.2, 0.3])
        np.testing.assert_allclose(
            motion.angular_momentum(0.0), body.moments * [0.1, 0.2, 0.3], rtol=1e-15
        )
        scale = body.moments[2]  # |L| / I3: no square underflows at 1e-200
        moment = motion.angular_momentum(np.array([0.0, 1.3, 7.0])) / scale
        lengths = np.linalg.norm(moment, axis=1)
        np.testing.assert_allclose(lengths, motion.momentum / scale, rtol=1e-14)


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


# ---------------------------------------------------------------------------
# The start of the motion (issue 20, item 1): omega(0) = omega0 for every
# accepted spin, and omega(t + T) = omega(t)
# ---------------------------------------------------------------------------
START_BODIES = [
    Body((0.4, 0.7, 0.9)),
    FIG6,
    T_HANDLE,
    Body((0.1, 0.5, 0.55)),  # close to prolate
    Body((0.3, 0.31, 0.6)),  # close to oblate
]


def ulps_apart(a, b):
    """``|a - b|`` in units of the spacing of doubles at ``b``, componentwise."""
    return np.abs(np.asarray(a) - b) / np.spacing(np.abs(b))


def offset_spin(draw_sign, exponent, body, phi):
    """A dtheta of magnitude 10**exponent on one side, inside [0, pi/2]."""
    theta_c = body.critical_angle(phi)
    room = theta_c if draw_sign < 0 else np.pi / 2 - theta_c
    return draw_sign * min(10.0**exponent, 0.99 * room)


@settings(max_examples=300, deadline=None, suppress_health_check=list(HealthCheck))
@given(
    body=st.sampled_from(START_BODIES),
    side=st.sampled_from([-1.0, 1.0]),
    exponent=st.floats(-300.0, -0.3),
    phi=st.floats(-np.pi, np.pi),
)
@example(body=START_BODIES[0], side=-1.0, exponent=-40.0, phi=1.2)  # the audit's case
@example(body=START_BODIES[0], side=1.0, exponent=-300.0, phi=1.2)
@example(body=FIG6, side=-1.0, exponent=-300.0, phi=np.pi / 2 - 1e-9)  # near the I2 axis
def test_start_is_omega0_for_every_spin(body, side, exponent, phi):
    """omega(0) = omega0 to a few ulps, dtheta down to 1e-300, both branches.

    The issue's bound is 1e-13 relative; measured over 3000 random spins
    the worst is 5.6e-16 relative and 43 ulps in a component.  Before the
    start was formed from (sin, cos) with quarter periods kept apart, the
    audit's case (dtheta = -1e-40, phi = 1.2) started at the saddle
    (relative error 0.46).
    """
    dtheta = offset_spin(side, exponent, body, phi)
    motion = Motion.from_spin(body, dtheta=dtheta, phi=phi)
    start = motion.omega(0.0)
    assert np.linalg.norm(start - motion.omega0) <= 1e-15 * np.linalg.norm(motion.omega0)
    assert ulps_apart(start, motion.omega0).max() <= 256


@settings(max_examples=150, deadline=None, suppress_health_check=list(HealthCheck))
@given(
    body=st.sampled_from(START_BODIES),
    side=st.sampled_from([-1.0, 1.0]),
    exponent=st.floats(-300.0, -0.3),
    phi=st.floats(-np.pi, np.pi),
    fraction=st.floats(0.0, 1.0),
)
def test_omega_is_periodic_for_every_spin(body, side, exponent, phi, fraction):
    """omega(t + T) = omega(t) to 1e-11 relative (measured: 3e-13)."""
    motion = Motion.from_spin(body, dtheta=offset_spin(side, exponent, body, phi), phi=phi)
    t = fraction * motion.period
    omega = motion.omega(np.array([t, t + motion.period]))
    assert np.linalg.norm(omega[1] - omega[0]) <= 1e-11 * np.linalg.norm(motion.omega0)


@settings(max_examples=300, deadline=None, suppress_health_check=list(HealthCheck))
@given(
    body=st.sampled_from(START_BODIES[:4]),
    w1=st.floats(-300.0, -1.0),
    w3=st.floats(-300.0, -1.0),
    w2=st.floats(0.5, 2.0),
    signs=st.tuples(*[st.sampled_from([-1.0, 1.0])] * 3),
)
@example(body=FIG6, w1=-20.0, w3=-8.0, w2=1.0, signs=(1.0, 1.0, 1.0))
@example(body=FIG6, w1=-16.21, w3=-16.21, w2=1.0, signs=(1.0, 1.0, 1.0))
def test_start_near_the_unstable_axis_componentwise(body, w1, w3, w2, signs):
    """A spin near I2 through from_omega: every component within 11,126 ulps.

    (Principia's bound for its own round trip.)  Components down to 1e-300
    of a unit spin; measured worst over 6000 spins: 12 ulps.
    """
    omega0 = np.array([signs[0] * 10.0**w1, signs[1] * w2, signs[2] * 10.0**w3])
    motion = Motion.from_omega(Body(body.normalized_moments), omega0)
    assert ulps_apart(motion.omega(0.0), omega0).max() <= 11126


def mp_spin_omega(body, dtheta, phi, times, dps):
    """omega(t) of the spin at exactly theta_c + dtheta in mpmath (eqn:Omegas).

    The spin is formed at ``dps`` digits from the angles (not from the
    rounded omega0), so its orbit is that of the ideal spin down to any
    dtheta; sn, cn, dn and F are mpmath's.  Uses the body's unit moments
    (exact powers of two of the given ones) as the kernels do.
    """
    with mp.workdps(dps):
        i1, i2, i3 = (mp.mpf(float(v)) for v in body.unit_moments)
        phi = mp.mpf(float(phi))
        a, b = i3 * (i3 - i2), i1 * (i2 - i1) * mp.cos(phi) ** 2
        theta = mp.atan2(mp.sqrt(a), mp.sqrt(b)) + mp.mpf(float(dtheta))
        w = (mp.sin(theta) * mp.cos(phi), mp.sin(theta) * mp.sin(phi), mp.cos(theta))
        two_e = i1 * w[0] ** 2 + i2 * w[1] ** 2 + i3 * w[2] ** 2
        m_sq = i1**2 * w[0] ** 2 + i2**2 * w[1] ** 2 + i3**2 * w[2] ** 2
        gap_m1, gap_3m = m_sq - two_e * i1, two_e * i3 - m_sq
        sam = dtheta < 0
        if sam:
            k2 = (i2 - i1) * gap_3m / ((i3 - i2) * gap_m1)
            rate = mp.sqrt((i3 - i2) * gap_m1 / (i1 * i2 * i3))
            sign = 1 if w[2] >= 0 else -1
            amp = (
                mp.sqrt(gap_3m / (i1 * (i3 - i1))),
                sign * mp.sqrt(gap_3m / (i2 * (i3 - i2))),
                sign * mp.sqrt(gap_m1 / (i3 * (i3 - i1))),
            )
            am0 = mp.atan2(w[1] / amp[1], w[0] / amp[0])
        else:
            k2 = (i3 - i2) * gap_m1 / ((i2 - i1) * gap_3m)
            rate = mp.sqrt((i2 - i1) * gap_3m / (i1 * i2 * i3))
            sign = 1 if w[0] >= 0 else -1
            amp = (
                sign * mp.sqrt(gap_3m / (i1 * (i3 - i1))),
                sign * mp.sqrt(gap_m1 / (i2 * (i2 - i1))),
                mp.sqrt(gap_m1 / (i3 * (i3 - i1))),
            )
            am0 = mp.atan2(w[1] / amp[1], w[2] / amp[2])
        tau0 = mp.ellipf(am0, k2)
        rows = []
        for t in times:
            u = tau0 + rate * mp.mpf(float(t))
            sn, cn, dn = (mp.ellipfun(kind, u, m=k2) for kind in ("sn", "cn", "dn"))
            if sam:
                rows.append([amp[0] * cn, amp[1] * sn, amp[2] * dn])
            else:
                rows.append([amp[0] * dn, amp[1] * sn, amp[2] * cn])
        return np.array(rows, dtype=float), float(4 * mp.ellipk(k2) / rate)


@settings(max_examples=12, deadline=None, suppress_health_check=list(HealthCheck))
@given(
    body=st.sampled_from(START_BODIES),
    side=st.sampled_from([-1.0, 1.0]),
    exponent=st.floats(-300.0, -0.3),
    phi=st.floats(-np.pi, np.pi),
    fractions=st.lists(st.floats(0.0, 2.0), min_size=2, max_size=2),
)
@example(
    body=START_BODIES[0], side=-1.0, exponent=-40.0, phi=1.2, fractions=[0.0, 0.31]
)  # the audit's case
@example(
    body=T_HANDLE, side=-1.0, exponent=-295.0, phi=0.0, fractions=[0.0, 2.0]
)  # 2.05 eps |u| from the reference
def test_motion_near_the_separatrix_matches_mpmath(body, side, exponent, phi, fractions):
    """omega(t) over two periods against mpmath from the ideal spin.

    Working precision 30 digits more than the spin's distance from the
    separatrix.  The kernel's argument ``u = D t`` (``4 K`` a period)
    carries an absolute rounding of a few ``eps |u|``, and ``|u|`` reaches
    8 K ~ 2800 at dtheta = 1e-300: the bound is ``6 eps (1 + |u|)`` of
    |omega0| = 1 (a fixed 1e-12 was below it: 1.27e-12 = 2.05 eps |u| at
    dtheta = -1e-295, t = 2 T, a case hypothesis found).
    """
    from scipy.special import ellipkm1

    dtheta = offset_spin(side, exponent, body, phi)
    motion = Motion.from_spin(body, dtheta=dtheta, phi=phi)
    times = np.array(fractions) * motion.period
    dps = 30 + int(-math.log10(abs(dtheta)))
    reference, period = mp_spin_omega(body, dtheta, phi, times, dps)
    assert motion.period == pytest.approx(period, rel=1e-13)
    u = 4.0 * float(ellipkm1(motion.one_minus_m)) * max(fractions)
    bound = 6.0 * np.finfo(float).eps * (1.0 + u)
    assert bound <= 5e-12  # |u| <= 8 K ~ 2800
    assert np.abs(motion.omega(times) - reference).max() <= bound


def test_audit_case_matches_integration():
    """The audit's spin (1 - m = 1.3e-40) against DOP853 of Euler's equations.

    Before the fix the exact motion started at the saddle, omega(0) =
    (1.5e-4, 0.986, 1.3e-4) instead of omega0 = (0.347, 0.894, 0.284).
    The integration is checked over the first approach to the saddle
    (t < 10, where it is well conditioned): to 1e-12.
    """
    body = START_BODIES[0]
    motion = Motion.from_spin(body, dtheta=-1e-40, phi=1.2)
    times = np.linspace(0.0, 10.0, 41)
    omega, _ = integrate(motion, times)
    assert np.abs(motion.omega(times) - omega).max() <= 1e-12
    assert np.abs(motion.omega(0.0) - [0.347468830754, 0.893742518, 0.283707]).max() < 1e-6


# ---------------------------------------------------------------------------
# The frame of Motion.from_omega (issue 20): principal or the body's own axes
# ---------------------------------------------------------------------------
def test_from_omega_axes_body_and_principal_agree():
    """axes="body" turns the spin with Body.frame, as the CLI's --omega does."""
    phone = Body.box(0.071, 0.147, 0.0078, mass=0.17)
    spin = np.array([120.0, 2.0, 1.0]) * 2 * np.pi / 60  # along the phone's x, y, z
    by_body = Motion.from_omega(phone, spin, axes="body")
    by_principal = Motion.from_omega(phone, phone.frame @ spin, axes="principal")
    np.testing.assert_array_equal(by_body.omega0, by_principal.omega0)
    assert by_body.period == by_principal.period
    # the phone's x (width) is its intermediate axis: the principal omega0
    # has the 120 rpm along I2, and back in the phone's axes it is the spin
    assert by_body.omega0[1] == pytest.approx(spin[0], rel=1e-15)
    np.testing.assert_allclose(phone.frame.T @ by_body.omega0, spin, rtol=1e-15)
    # the same numbers taken in the other axes are another motion
    other = Motion.from_omega(phone, spin, axes="principal")
    assert abs(other.period - by_body.period) > 0.1 * by_body.period


def test_from_omega_without_axes_warns_only_where_it_matters():
    phone = Body.box(0.071, 0.147, 0.0078, mass=0.17)
    with pytest.warns(orbits.AxesWarning, match="axes='body'"):
        motion = Motion.from_omega(phone, [0.1, 12.0, 0.2])
    np.testing.assert_array_equal(motion.omega0, [0.1, 12.0, 0.2])  # taken as principal
    # ascending moments: the body's axes are the principal axes, no warning
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Motion.from_omega(FIG6, [0.1, 1.0, 0.2])
        Motion.from_omega(Body((0.9, 0.4, 0.7)), [0.1, 1.0, 0.2], axes="body")
    for axes in ("space", np.array(["body"]), ["body"]):  # an array: ValueError (truth value)
        with pytest.raises(InputError, match="axes must be"):
            Motion.from_omega(FIG6, [0.1, 1.0, 0.2], axes=axes)


def test_from_omega_body_axes_of_unsorted_moments():
    """Moments given as (I_x, I_y, I_z) = (0.9, 0.4, 0.7): a spin about x is about I3."""
    body = Body((0.9, 0.4, 0.7))
    motion = Motion.from_omega(body, [1.0, 0.0, 0.01], axes="body")
    assert abs(motion.omega0[2]) == 1.0 and abs(motion.omega0[1]) == 0.01
    assert motion.branch == "SAM"
    np.testing.assert_array_equal(body.frame.T @ motion.omega0, [1.0, 0.0, 0.01])


@pytest.mark.parametrize(
    "omega0", [(1.9e-161, 1.26, 7.5e-162), (-1e-162, 1.0, -1e-162), (1e-300, -1.0, 3e-300)]
)
def test_spin_within_1e300_of_the_unstable_axis(omega0):
    """Components with subnormal squares: the start to a few ulps, phi(t)
    finite and against mpmath over a period (before: a ZeroDivisionError, or
    the smallest component 23 % off for the first spin).  The period is
    ~2000 time units and phi reaches ~4500 rad, so omega in space carries
    phi's rounding eps |phi| ~ 1e-12: bound 1e-11 (measured 4e-12)."""
    body = Body((0.1, 0.5, 0.55))
    motion = Motion.from_omega(body, omega0)
    assert ulps_apart(motion.omega(0.0), omega0).max() <= 64
    times = np.linspace(0.0, motion.period, 5)
    assert_matches_mpmath(motion, times, 1e-11, dps=700)


@pytest.mark.parametrize(
    "omega0",
    [(3e-158, 1.0, 1e-158), (1e-157, 1.0, 3e-157), (2e-150, 1.0, 1e-150), (1e-145, -1.0, 1e-145)],
    ids=["LAM-1e-158", "SAM-1e-157", "1e-150", "1e-145"],
)
def test_phi_next_to_the_unstable_axis_where_cn_and_dn_are_tiny(omega0):
    """Within 1e-140 of the I2 axis the R_J of phi(t) is formed from cn and dn,
    not from their squares (core.motion._TINY_ROOT); a threshold moved to
    1e-160 put phi(1) 8.7e-9 off on LAM and 2.7e-11 on SAM with every other
    test passing.  Here omega stays along I2 to ~1e-150 for these times, so
    dphi/dt = M / I2 to rounding and phi(t) = (M / I2) t; also mpmath at 700
    digits (the squares of the small components are ~1e-316)."""
    body = Body(FIG6.normalized_moments)
    motion = Motion.from_omega(body, omega0)
    times = np.array([0.0, 1e-3, 1.0, 10.0])
    euler, state = assert_matches_mpmath(motion, times, 1e-13, dps=700)
    # phi's own rate: dphi/dt = M (I1 w1^2 + I2 w2^2) / (I1^2 w1^2 + I2^2 w2^2)
    rate = motion.momentum / body.moments[1]
    assert state.euler[1:, 0] == pytest.approx(rate * times[1:], rel=1e-14)


def test_times_beyond_the_resolution_of_the_period_are_refused():
    """Up to 2^50 periods the unwrapped angles follow their drift; beyond, the
    quarter-period count of the elliptic argument is no longer exact (at 2^62
    periods psi came back as +1.45e19 for either sign of t), so such times are
    an InputError, never a wrong orientation."""
    motion = orbits.Motion.from_spin(orbits.Body([1.0, 2.0, 3.0]), 0.5, phi=0.2)
    period = motion.period
    t = 2.0**50 * period
    phi, _, psi = motion.euler_angles(t)
    # SAM about I3: psi winds by -2 pi per period; phi by its mean rate
    assert psi / (-2.0 * np.pi * 2.0**50) == pytest.approx(1.0, rel=1e-12)
    rate = motion.euler_angles(period)[0] / period
    assert phi / t == pytest.approx(rate, rel=1e-12)
    for bad in (2.0**51 * period, -1e20, [0.0, 1e300]):
        with pytest.raises(orbits.InputError, match=r"beyond the 1\.13e\+15 periods"):
            motion.euler_angles(bad)


# ---------------------------------------------------------------------------
# Thin rods (e, 1, 1 + e): phi(t) against Landau's dphi/dt by quadrature
# ---------------------------------------------------------------------------
def landau_motion(moments, omega0, times, dps=30):
    """Total phase and ``(phi, theta, psi)`` at ``times`` from Landau's dphi/dt.

    An mpmath reference independent of eqn:fullphi and of any ``Pi``:
    Landau & Lifshitz Sec. 37, ``dphi/dt = M (I1 w1^2 + I2 w2^2) / (I1^2
    w1^2 + I2^2 w2^2)``, with omega from mpmath's Jacobi functions (SAM
    ``w1, w2 ~ cn, sn``, LAM ``dn, sn``), integrated with ``mp.quad`` over
    the amplitude ``am`` (``dt = d am / (D dn)``), whose integrand is
    elementary and pi-periodic.  It peaks at ``sin am = 0`` with a width
    ``~ I1 |a1| / (I2 |a2|)`` (``~ e`` on a thin rod) and, near the
    separatrix, at ``cos am = 0`` with a width ``~ sqrt(1 - m)``: both are
    cut by breakpoints at geometric distances.  Theta and psi from omega
    (eqn:eulerangles, psi in (-pi, pi]).  From the double omega0 and
    moments as given, at ``dps`` digits (no cancellation: the integrand is
    positive).
    """
    with mp.workdps(dps):
        i1, i2, i3 = (mp.mpf(float(v)) for v in sorted(moments))
        w1, w2, w3 = (mp.mpf(float(v)) for v in omega0)
        two_e = i1 * w1**2 + i2 * w2**2 + i3 * w3**2
        m_sq = i1**2 * w1**2 + i2**2 * w2**2 + i3**2 * w3**2
        momentum = mp.sqrt(m_sq)
        gap_m1, gap_3m = m_sq - two_e * i1, two_e * i3 - m_sq
        sam = m_sq > two_e * i2
        if sam:
            k2 = (i2 - i1) * gap_3m / ((i3 - i2) * gap_m1)
            rate = mp.sqrt((i3 - i2) * gap_m1 / (i1 * i2 * i3))
            sign = 1 if w3 >= 0 else -1
            a1 = mp.sqrt(gap_3m / (i1 * (i3 - i1)))
            a2 = sign * mp.sqrt(gap_3m / (i2 * (i3 - i2)))
            a3 = sign * mp.sqrt(gap_m1 / (i3 * (i3 - i1)))
            am0 = mp.atan2(w2 / a2, w1 / a1)
        else:
            k2 = (i3 - i2) * gap_m1 / ((i2 - i1) * gap_3m)
            rate = mp.sqrt((i2 - i1) * gap_3m / (i1 * i2 * i3))
            sign = 1 if w1 >= 0 else -1
            a1 = sign * mp.sqrt(gap_3m / (i1 * (i3 - i1)))
            a2 = sign * mp.sqrt(gap_m1 / (i2 * (i2 - i1)))
            a3 = mp.sqrt(gap_m1 / (i3 * (i3 - i1)))
            am0 = mp.atan2(w2 / a2, w3 / a3)

        def integrand(am):
            s, c = mp.sin(am), mp.cos(am)
            dn_sq = 1 - k2 * s * s
            x = a1 * a1 * (c * c if sam else dn_sq)
            y = (a2 * s) ** 2
            return momentum * (i1 * x + i2 * y) / ((i1**2 * x + i2**2 * y) * mp.sqrt(dn_sq))

        def geometric(width):
            out = []
            width = min(width, mp.mpf(1) / 4)
            while width < 1:
                out.append(width)
                width *= 16
            return out

        near_zero = geometric(i1 * abs(a1) / (i2 * abs(a2)))
        near_half = geometric(mp.sqrt(abs(1 - k2)))

        def integral(lo, hi):  # lo <= hi, within one half turn of each other
            inner = [lo, hi]
            for j in range(int(mp.floor(lo / mp.pi)), int(mp.ceil(hi / mp.pi)) + 1):
                inner += [j * mp.pi + side * h for h in near_zero for side in (-1, 1)]
                inner += [(j + 0.5) * mp.pi + side * h for h in near_half for side in (-1, 1)]
                inner += [j * mp.pi, (j + 0.5) * mp.pi]
            return mp.quad(integrand, sorted(p for p in set(inner) if lo <= p <= hi))

        half_turn = 2 * integral(mp.mpf(0), mp.pi / 2)
        total = 2 * half_turn / rate - (2 * mp.pi if sam else 0)
        u0 = mp.ellipf(am0, k2)
        quarter = mp.ellipk(k2)
        rows = []
        for t in times:
            u = u0 + rate * mp.mpf(float(t))
            j = mp.nint(u / (2 * quarter))
            parity = -1 if int(j) % 2 else 1
            sn, cn, dn = (mp.ellipfun(kind, u, m=k2) for kind in ("sn", "cn", "dn"))
            am = j * mp.pi + mp.atan2(parity * sn, parity * cn)
            turns = mp.floor((am - am0) / mp.pi)
            phi = (turns * half_turn + integral(am0, am - turns * mp.pi)) / rate
            if sam:
                w = (a1 * cn, a2 * sn, a3 * dn)
            else:
                w = (a1 * dn, a2 * sn, a3 * cn)
            theta = mp.atan2(mp.hypot(i1 * w[0], i2 * w[1]), i3 * w[2])
            rows.append((phi, theta, mp.atan2(i1 * w[0], i2 * w[1])))
        return total, rows


def mp_rotation(phi, theta, psi):
    """``Rz(phi) Rx(theta) Rz(psi)`` in mpmath, as doubles."""
    with mp.workdps(30):
        cf, sf, ct, st, cp, sp = (f(a) for a in (phi, theta, psi) for f in (mp.cos, mp.sin))
        rows = [
            [cf * cp - sf * ct * sp, -cf * sp - sf * ct * cp, sf * st],
            [sf * cp + cf * ct * sp, -sf * sp + cf * ct * cp, -cf * st],
            [st * sp, st * cp, ct],
        ]
        return np.array([[float(v) for v in row] for row in rows])


def compare_with_landau(motion, fractions, dps=30):
    """Errors of total phase, phi, theta and R against :func:`landau_motion`.

    Returns the relative error of the total phase and, per time, the error
    of phi relative to ``max(1, |phi|)``, of theta, and the largest of R.
    """
    times = np.asarray(fractions) * motion.period
    total, rows = landau_motion(motion.body.moments, motion.omega0, times, dps)
    state = motion.state(times)
    total = float(total)
    phi = np.array([float(r[0]) for r in rows])
    theta = np.array([float(r[1]) for r in rows])
    rotation = np.array([mp_rotation(*r) for r in rows])
    return (
        abs(motion.total_phase() - total) / abs(total),
        np.abs(state.euler[:, 0] - phi) / np.maximum(1.0, np.abs(phi)),
        np.abs(state.euler[:, 1] - theta),
        np.abs(state.rotation - rotation).max(axis=(1, 2)),
    )


THIN_RODS = [Body([e, 1.0, 1.0 + e]) for e in (1e-6, 1e-9, 1e-12, 1e-15)] + [
    Body([1e-300, 1.0, 1.0000000000000002])  # the flat rod (2^-52, 1, 1 + 2^-52)
]


@pytest.mark.parametrize(
    "spin, branch",
    [
        (dict(theta=0.3), "SAM"),
        (dict(theta=1.2), "LAM"),
        (dict(theta=0.6, phi=0.4), "SAM"),
    ],
    ids=["SAM", "LAM", "SAM-phi"],
)
@pytest.mark.parametrize("body", THIN_RODS, ids=["1e-6", "1e-9", "1e-12", "1e-15", "2^-52"])
def test_thin_rod_matches_landau(body, spin, branch):
    """phi(t), total phase and orientation of a thin rod ``(e, 1, 1 + e)``.

    ``theta_c`` is ~pi/4: 0.3 and 0.6 are SAM, 1.2 LAM.  Before the fix,
    ``Pi(n; .)`` with ``n ~ -1/e^2`` was formed as ``F + (n/3) s^3 R_J``,
    whose terms cancel to ``~ e F``, and ``D T`` rounded against ``4 K`` was
    amplified by ``dphi/du ~ 1/e``: the total phase was off by 1e-10 (e =
    1e-6), 2e-7 (1e-9), 4e-4 (1e-12), 0.5 (1e-15) and 1.4 (2^-52), and so
    were phi(t) and R(t).  Measured now: total phase and phi within 5e-16
    (relative; phi to ``max(1, |phi|)``), theta and R within 5e-15.

    phi (and psi) alone are checked only away from ``sin am = 0``: there
    (t = 0, T/2, T of a spin with phi = 0) the I3 axis passes within ~e of
    M, phi and psi turn by ~pi over a time ~e/M, and one rounding of ``u =
    D t`` (``eps K``) moves them by ``eps K / e`` (1e-2 at e = 1e-15) in
    opposite directions; the orientation, which depends on ``phi + psi``
    there, is checked at every time.
    """
    motion = Motion.from_omega(body, Motion.from_spin(body, **spin).omega0)
    assert motion.branch == branch
    fractions = [0.1, 0.37, 2.7, 0.5, 1.0]
    away = slice(0, 3)  # phi alone away from sin(am) = 0 (see docstring)
    total, phi, theta, rotation = compare_with_landau(motion, fractions)
    assert total <= 1e-14
    assert phi[away].max() <= 1e-14
    assert theta.max() <= 1e-13
    assert rotation.max() <= 1e-13
    # phi(T) is the total phase (eqn:alphaproto): whole periods are exact
    turn = 2.0 * np.pi if branch == "SAM" else 0.0
    assert motion.euler_angles(motion.period)[0] == pytest.approx(
        motion.total_phase() + turn, rel=1e-15
    )


@pytest.mark.parametrize("body", [FIG6, T_HANDLE], ids=["fig6", "t-handle"])
@pytest.mark.parametrize(
    "spin",
    [dict(dtheta=-0.3), dict(dtheta=0.3, phi=0.4), dict(dtheta=-1e-12), dict(dtheta=1e-12)],
    ids=["SAM", "LAM", "SAM-1e-12", "LAM-1e-12"],
)
def test_ordinary_bodies_match_landau(body, spin):
    """The same reference for ordinary bodies and spins 1e-12 off the separatrix.

    (Pi of eqn:fullphi now comes from the cancellation-free form for every
    ``n < -1``, which includes these bodies.)  Near the separatrix the
    orbit of the double omega0 is followed (``from_omega``; the orbit of
    the exact ``dtheta`` differs from it by ~1e-7 in the total phase).
    Measured: total phase, phi and theta within 5e-16 (phi relative to
    ``max(1, |phi|)``), R within 2.4e-15, and 1.4e-14 near the separatrix
    (before the change: 1.3e-13, from the rounding of ``D t`` at whole
    periods).
    """
    motion = Motion.from_omega(body, Motion.from_spin(body, **spin).omega0)
    near = abs(spin["dtheta"]) < 1e-6
    total, phi, theta, rotation = compare_with_landau(motion, [0.1, 0.37, 0.5, 1.0, 2.7])
    assert total <= 1e-14
    assert phi.max() <= 1e-14
    assert theta.max() <= 1e-14
    assert rotation.max() <= (2e-13 if near else 5e-14)


def test_pi_far_matches_mpmath():
    """The cancellation-free ``Pi(n; am | m)`` for ``n < -1`` (kernel pi_far).

    Against ``mp.ellippi`` at 60 digits (more than the 31 that ``F + (n/3)
    s^3 R_J`` loses at ``n = -1e31`` in mpmath too), for ``-n`` from 1 to
    1e40, ``m`` from 0 to 1 - 1e-12 and amplitudes up to pi/2: within 8e-15
    relative (measured 6.2e-16).  The former form ``F + (n/3) s^3 R_J``
    lost ~``eps sqrt(-n)`` (5e-4 at ``n = -1e24``).
    """
    from orbits.core.motion import pi_far, pi_far_complete

    rng = np.random.default_rng(7)
    worst = 0.0
    with mp.workdps(60):
        for _ in range(60):
            big_n = 10.0 ** rng.uniform(0.0, 40.0)
            kc = float(10.0 ** rng.uniform(-6.0, 0.0)) if rng.random() < 0.8 else 1.0
            m = (1.0 - kc) * (1.0 + kc)
            am = rng.uniform(-0.5, 0.5) * np.pi
            s, c = math.sin(am), math.cos(am)
            dn = math.sqrt(c * c + (kc * s) ** 2)
            ratio = m / big_n
            width = math.sqrt(1.0 + big_n) * math.sqrt(1.0 + ratio)
            n_mp, m_mp = -mp.mpf(big_n), (1 - mp.mpf(kc)) * (1 + mp.mpf(kc))
            ref = mp.ellippi(n_mp, mp.atan2(s, c), m_mp)
            worst = max(worst, abs(pi_far(s, c, dn, ratio, width) / ref - 1))
            ref = mp.ellippi(n_mp, m_mp)
            worst = max(worst, abs(pi_far_complete(kc, ratio, width) / ref - 1))
    assert worst <= 8e-15


@pytest.mark.parametrize("dtheta", [2.0, -1.5, 1e300])
def test_dtheta_out_of_range_is_said_as_total_phase_says_it(dtheta):
    """Motion.from_spin (and so orbits animate --dtheta) refuses a dtheta that
    takes theta out of [0, pi/2] with the message of total_phase: the sum
    theta_c + dtheta, and that dtheta is not folded."""
    with pytest.raises(AngleError) as from_motion:
        Motion.from_spin(FIG6, dtheta=dtheta)
    with pytest.raises(AngleError) as from_phase:
        orbits.total_phase(FIG6, dtheta=dtheta)
    assert str(from_motion.value) == str(from_phase.value)
    assert "theta_c + dtheta" in str(from_motion.value) and "not folded" in str(from_motion.value)


def _mp_period_and_phase(moments, omega, dps=800):
    """T (eqn:TK) and Delta alpha (eqn:GeometricPhase) of a spin vector, in mpmath."""
    with mp.workdps(dps):
        i1, i2, i3 = (mp.mpf(float(v)) for v in moments)
        w = [mp.mpf(float(v)) for v in omega]
        two_e = i1 * w[0] ** 2 + i2 * w[1] ** 2 + i3 * w[2] ** 2
        m_sq = i1**2 * w[0] ** 2 + i2**2 * w[1] ** 2 + i3**2 * w[2] ** 2
        gap_m1, gap_3m = m_sq - two_e * i1, two_e * i3 - m_sq
        if m_sq > two_e * i2:  # SAM
            rate = mp.sqrt((i3 - i2) * gap_m1 / (i1 * i2 * i3))
            m = (i2 - i1) * gap_3m / ((i3 - i2) * gap_m1)
            n, shift = -i3 * (i2 - i1) / (i1 * (i3 - i2)), -2 * mp.pi
        else:
            rate = mp.sqrt((i2 - i1) * gap_3m / (i1 * i2 * i3))
            m = (i3 - i2) * gap_m1 / ((i2 - i1) * gap_3m)
            n, shift = -i3 * gap_m1 / (i1 * gap_3m), 0
        period = 4 * mp.ellipk(m) / rate
        momentum = mp.sqrt(m_sq)
        total = momentum * period / i3 + shift
        total += 4 * momentum * (i3 - i1) / (i1 * i3) * mp.ellippi(n, m) / rate
        return float(period), float(total)


@pytest.mark.parametrize("moments", [(1.0, 2.0, 2.5), (1.0, 2.0, 3.0)])
@pytest.mark.parametrize("tilt", [1e-300, 2.2e-308, 1e-310, 2e-311])
def test_spin_vectors_a_subnormal_tilt_from_i2(moments, tilt):
    """(e, 1, e) for e down to 2e-311: period and phase within 4e-15 of mpmath
    (800 digits).  Below, kc = sqrt(1 - k^2) is a subnormal of few digits:
    e = 1e-320 was 5e-7 off, 1e-323 a ZeroDivisionError, 5e-324 called the
    separatrix; they are refused (SeparatrixError), see the next test."""
    omega = (tilt, 1.0, tilt)
    period, total = _mp_period_and_phase(moments, omega)
    motion = Motion(moments, omega)
    assert motion.period == pytest.approx(period, rel=4e-15)
    assert motion.total_phase() == pytest.approx(total, rel=4e-15)
    row = orbits.spin_phases(moments, omega).iloc[0]
    assert row["period"] == pytest.approx(period, rel=4e-15)
    assert row["total_phase"] == pytest.approx(total, rel=4e-15)


@pytest.mark.parametrize("tilt", [1e-313, 1e-320, 1e-323, 5e-324])
def test_spin_vectors_beyond_a_doubles_reach_of_the_separatrix(tilt):
    for call in (
        lambda: Motion((1.0, 2.0, 3.0), (tilt, 1.0, tilt)),
        lambda: orbits.spin_phases((1.0, 2.0, 3.0), (tilt, 1.0, tilt)),
        lambda: orbits.flip_motion(offset=tilt),
    ):
        with pytest.raises(SeparatrixError, match="cannot hold its orbit"):
            call()


def test_outputs_are_not_the_callers_arrays():
    """Motion.omega0, MotionState.t, PoinsotAnimation.times and spin_phases'
    w1..w3 were the caller's arrays (or read-only views of them): an edit
    of the input changed a Motion whose period stayed the old one's."""
    omega = np.array([0.3, 0.2, 0.9])
    motion = Motion((1.0, 2.0, 3.0), omega)
    frame = orbits.spin_phases((1.0, 2.0, 3.0), omega)
    times = np.linspace(0.0, 1.0, 5)
    state = motion.state(times)
    animation = orbits.PoinsotAnimation(motion, times)
    omega[0], times[1] = 5.0, 0.7
    assert motion.omega0.tolist() == [0.3, 0.2, 0.9] and frame["w1"].iloc[0] == 0.3
    assert state.t[1] == 0.25 and animation.times[1] == 0.25
    frame.loc[0, "w1"] = 1.0  # a frame of its own, writable (was: read-only ValueError)


def _turn_about_momentum(motion, t):
    """The angle of ``R(t) R(0)^T`` about the space z axis (along L), radians."""
    rotation = motion.rotation([0.0, t])
    relative = rotation[1] @ rotation[0].T
    return math.atan2(relative[1, 0], relative[0, 0]), relative


@pytest.mark.parametrize("w3", [1.0, -1.0, -3.0, 2.5])
def test_a_steady_spin_about_i3_turns_forwards_about_l(w3):
    """A spin exactly along -I3 (L along the body's -I3) turned the body the
    wrong way at the wrong rate (psi = -elapsed holds only at theta = 0):
    1.6 rad off after 2 s on fig6.  R(t) R(0)^T is Rz(|w3| t), exactly."""
    motion = Motion.from_omega(FIG6, [0.0, 0.0, w3])
    for t in (0.2, 2.0, 7.5):
        angle, relative = _turn_about_momentum(motion, t)
        want = math.remainder(abs(w3) * t, 2.0 * math.pi)
        assert abs(math.remainder(angle - want, 2.0 * math.pi)) <= 1e-14
        assert relative[2, 2] == pytest.approx(1.0, abs=1e-15)


def test_a_phone_thrown_flat_turns_about_its_momentum():
    """Body.box's frame maps the phone's thickness axis to -I3: a throw about
    it was the case above (-2.45 rad instead of +1.0 after 0.2 s)."""
    phone = Body.box(0.071, 0.147, 0.0078, mass=0.17)
    motion = Motion.from_omega(phone, [0.0, 0.0, 5.0], axes="body")
    assert motion.omega0[2] == -5.0
    angle, _ = _turn_about_momentum(motion, 0.2)
    assert angle == pytest.approx(1.0, abs=1e-14)


@pytest.mark.parametrize("small", [1e-150, 1e-158, 1e-161, 1e-200, 1e-300])
@pytest.mark.parametrize(
    "direction", [(1.0, 1.0, 2.0), (-1.0, 1.0, -3.0), (3.0, -2.0, -1.0), (3.0, 2.0, 1.0)]
)
def test_tiny_transverse_components_keep_their_digits(small, direction):
    """Within 1e-154 of I3 (or I1) the squares of the small components are
    subnormal: omega(0) came back 0.18 off at 1e-161 of |omega|, and the
    orientation 7.5e-3 rad off.  Now every component within 2 ulps, and the
    body turns about L at |omega| to rounding (the wobble is far below it)."""
    a, b, c = direction
    axis_first = abs(c) > 1.5  # the big component along I1 (LAM) or I3 (SAM)
    omega = (
        np.array([a, small * b, small * c]) if axis_first else np.array([small * a, small * b, c])
    )
    motion = Motion.from_omega(FIG6, omega)
    back = motion.state(np.array([0.0])).omega[0]
    assert np.all(np.abs(back - omega) <= 2 * np.spacing(np.abs(omega)))
    speed = float(np.linalg.norm(omega))
    for t in (0.7, 3.0):
        angle, _ = _turn_about_momentum(motion, t)
        want = math.remainder(speed * t, 2.0 * math.pi)
        assert abs(math.remainder(angle - want, 2.0 * math.pi)) <= 1e-14
    # the herpolhode point (omega in space, from the node formula) is R omega:
    # w1 w2 and 2EI3 - M^2 went subnormal in it (0.37 off at 1e-200)
    state = motion.state(np.array([0.7, 3.0]))
    turned = np.einsum("kij,kj->ki", state.rotation, state.omega)
    assert np.all(np.abs(state.omega_space - turned) <= 1e-14 * np.abs(turned))


def test_the_herpolhode_of_a_spin_a_subnormal_away_from_i3():
    """1/mu overflowed for mu below 5.6e-309: an InputError ("does not fit a
    double") from herpolhode(theta=1e-308); the points are (~0, ~0, 1)."""
    _, points = orbits.herpolhode(Body([1.0, 2.0, 3.0]), theta=1e-308)
    assert np.all(np.isfinite(points)) and np.all(np.abs(points[:, :2]) < 1e-307)
    np.testing.assert_array_equal(points[:, 2], 1.0)
    # and at 1e-200 of |omega| (w1 w2 = 6e-400 flushed the node's x to 0)
    for small in (1e-158, 1e-200, 1e-300):
        motion = Motion.from_omega(Body([1.0, 2.0, 3.0]), [3 * small, 2 * small, 1.0])
        state = motion.state(np.array([0.7]))
        turned = state.rotation[0] @ state.omega[0]
        assert np.all(np.abs(state.omega_space[0] - turned) <= 1e-14 * np.abs(turned))
