"""Geometric phase Omega (signed solid angle of the polhode) to full precision.

``orbits.core.solid_angle`` evaluates Omega as one Bulirsch ``cel``; these
tests compare it with references that do not use that closed form:

* the committed mpmath table (``2ET/M - Delta alpha`` of the paper's
  formulas, precision raised until Omega has converged to 1e-25);
* live mpmath, the same difference at a precision raised until it converges;
* a direct quadrature of the solid angle enclosed by the polhode (the
  geometric definition, no elliptic integral at all);
* the exact limit on the separatrix, where the polhode becomes two great
  circles through the I2 axis and Omega is a lune: ``4 chi`` on SAM and
  ``4 chi - 2 pi`` on LAM with ``tan chi = sqrt(I1 (I3-I2) / (I3 (I2-I1)))``.
"""

import io
import math
from contextlib import redirect_stdout
from pathlib import Path

import mpmath as mp
import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mp_formulas import elliptic_parameters, period_and_total_phase

import orbits
from orbits import Body
from orbits.atomic import csv_float_options
from orbits.cli import main as cli_main

REFERENCE = Path(__file__).parent / "reference" / "phase_reference.csv"
NEAR_SPHERE = (1.0, 1.0 + 1e-12, 1.0 + 2e-12)
T_HANDLE = Body.t_handle(8, 4, 1)
FIG6 = (0.26, 0.55, 0.793662)
BOUND = 1e-13


def relative_error(got, want):
    """|got/want - 1|, and |got| where the exact value is 0 (on an axis)."""
    got, want = np.asarray(got, float), np.asarray(want, float)
    scale = np.where(want == 0.0, 1.0, np.abs(want))
    return np.abs(got - want) / scale


# --------------------------------------------------------------------------
# mpmath references, independent of the closed form under test
# --------------------------------------------------------------------------
def _mp_invariants(moments, w):
    i1, i2, i3 = (mp.mpf(float(v)) for v in sorted(moments))
    w1, w2, w3 = w
    two_e = i1 * w1**2 + i2 * w2**2 + i3 * w3**2
    m_sq = i1**2 * w1**2 + i2**2 * w2**2 + i3**2 * w3**2
    return i1, i2, i3, two_e, m_sq


def _mp_montgomery(moments, w):
    """``2ET/M - Delta alpha`` from eqn:TK and eqn:GeometricPhase literally."""
    i1, i2, i3, two_e, m_sq = _mp_invariants(moments, w)
    mom = mp.sqrt(m_sq)
    if elliptic_parameters(i1, i2, i3, two_e, m_sq)[0] == 0:  # on an axis: a point
        return mp.mpf(0)
    period, total = period_and_total_phase(i1, i2, i3, two_e, m_sq)
    return two_e * period / mom - total


def _mp_spin(moments, phi, theta=None, dtheta=None):
    """The unit spin at the current precision; theta or dtheta exact."""
    i1, i2, i3 = (mp.mpf(float(v)) for v in sorted(moments))
    phi = mp.mpf(phi)
    if theta is None:
        theta = mp.atan2(
            mp.sqrt(i3 * (i3 - i2)), mp.sqrt(i1 * (i2 - i1)) * abs(mp.cos(phi))
        ) + mp.mpf(dtheta)
    else:
        theta = mp.mpf(theta)
    return (mp.sin(theta) * mp.cos(phi), mp.sin(theta) * mp.sin(phi), mp.cos(theta))


def mp_omega(moments, phi=0.0, theta=None, dtheta=None, omega=None):
    """Omega by eqn:montgomery at a precision doubled until it converges (1e-20).

    The spin is ``omega`` (doubles, taken as exact) or the unit spin of
    ``theta``/``dtheta`` (doubles, taken as exact).
    """
    dps = 40 + (0 if dtheta is None else int(-math.log10(abs(dtheta))))
    previous = None
    while dps < 5000:
        with mp.workdps(dps):
            w = (
                tuple(mp.mpf(float(c)) for c in omega)
                if omega is not None
                else _mp_spin(moments, phi, theta, dtheta)
            )
            value = _mp_montgomery(moments, w)
            if previous is not None and abs(value - previous) <= 1e-20 * abs(value):
                return float(value)
            previous = value
        dps *= 2
    raise RuntimeError("mpmath reference did not converge")


def mp_cap(moments, omega, dps=30):
    """Omega as the area of the polhode's cap: int (1 - cos t) d(azimuth).

    The polhode is the sphere |M| = M cut by the cone
    ``sum_k (1/I_k - 2E/M^2) M_k^2 = 0``.  On SAM it circles I3 and on LAM
    I1; in polar angle t about that axis and azimuth s the cone is
    ``tan^2 t = c0 / (ca cos^2 s + cb sin^2 s)``.  Sign: + on SAM, - on LAM.
    """
    with mp.workdps(dps):
        w = tuple(mp.mpf(float(c)) for c in omega)
        i1, i2, i3, two_e, m_sq = _mp_invariants(moments, w)
        c = [1 / i - two_e / m_sq for i in (i1, i2, i3)]
        if m_sq > two_e * i2:  # SAM: about I3
            c0, ca, cb, sign = -c[2], c[0], c[1], 1
        else:  # LAM: about I1
            c0, ca, cb, sign = c[0], -c[1], -c[2], -1

        def one_minus_cos(s):
            tan_sq = c0 / (ca * mp.cos(s) ** 2 + cb * mp.sin(s) ** 2)
            root = mp.sqrt(1 + tan_sq)
            return tan_sq / (root * (1 + root))

        return float(sign * 4 * mp.quad(one_minus_cos, mp.linspace(0, mp.pi / 2, 9)))


# --------------------------------------------------------------------------
# The committed table
# --------------------------------------------------------------------------
@pytest.fixture(scope="module")
def reference():
    return pd.read_csv(REFERENCE, comment="#", **csv_float_options())


def table_omega(rows, mode):
    args = (
        {"dtheta": rows["dtheta"].to_numpy()}
        if mode == "dtheta"
        else {"theta": rows["theta"].to_numpy()}
    )
    got = orbits.phases(rows[["m1", "m2", "m3"]].to_numpy(), phi=rows["phi"].to_numpy(), **args)
    return got["geometric_phase"].to_numpy()


@pytest.mark.parametrize("mode", ["theta", "dtheta"])
def test_reference_table(reference, mode):
    """Every row of the table: relative error <= 1e-13 (measured ~1e-15)."""
    rows = reference[reference["mode"] == mode]
    error = relative_error(table_omega(rows, mode), rows["geometric_phase"])
    worst = int(np.argmax(error))
    assert error.max() <= BOUND, rows.iloc[worst].to_dict()


def test_reference_table_covers_the_hard_cases(reference):
    sphere = reference[reference["kind"] == "near_sphere"]
    assert len(sphere) >= 500
    moments = np.sort(sphere[["m1", "m2", "m3"]].to_numpy(), axis=1)
    assert (moments[:, 2] / moments[:, 0] - 1).min() < 2e-12
    offsets = sphere.loc[sphere["mode"] == "dtheta", "dtheta"].abs()
    assert offsets.min() < 1e-295
    thetas = reference.loc[reference["mode"] == "theta", "theta"]
    assert ((thetas > 0) & (thetas < 1e-10)).sum() >= 20
    assert (np.pi / 2 - thetas[thetas < np.pi / 2] < 1e-10).sum() >= 20
    # the old route, 2ET/M - Delta alpha in doubles, fails on these rows
    rows = sphere[sphere["mode"] == "dtheta"]
    got = orbits.phases(
        rows[["m1", "m2", "m3"]].to_numpy(),
        phi=rows["phi"].to_numpy(),
        dtheta=rows["dtheta"].to_numpy(),
    )
    old = got["dynamic_phase"] - got["total_phase"]
    assert relative_error(old, rows["geometric_phase"]).max() > 1e-3


def test_montgomery_identity_holds_to_rounding(reference):
    """Delta alpha = 2ET/M - Omega, to the rounding of 2ET/M."""
    rows = reference[reference["mode"] == "dtheta"]
    got = orbits.phases(
        rows[["m1", "m2", "m3"]].to_numpy(),
        phi=rows["phi"].to_numpy(),
        dtheta=rows["dtheta"].to_numpy(),
    )
    gap = got["dynamic_phase"] - got["total_phase"] - got["geometric_phase"]
    assert (gap.abs() <= 1e-13 * got["dynamic_phase"].abs()).all()


# --------------------------------------------------------------------------
# The issue's cases and exact limits
# --------------------------------------------------------------------------
@pytest.mark.parametrize("dtheta", [1e-200, -1e-200, -0.3, 0.3, 1e-300, -1e-300])
def test_nearly_spherical_body(dtheta):
    """I3/I1 - 1 = 2e-12: 2ET/M ~ 1e15 there, Omega ~ 1 (issue: -3.375)."""
    got = orbits.phases(NEAR_SPHERE, dtheta=[dtheta])["geometric_phase"].iloc[0]
    assert got == pytest.approx(mp_omega(NEAR_SPHERE, dtheta=dtheta), rel=BOUND)


def test_issue_value():
    got = orbits.phases(NEAR_SPHERE, dtheta=[1e-200])["geometric_phase"].iloc[0]
    assert got == pytest.approx(-3.1418147031, abs=1e-10)


@pytest.mark.parametrize(
    "moments",
    [
        NEAR_SPHERE,
        FIG6,
        T_HANDLE.moments,
        (1e-3, 1.0, 1.0005),
        (0.3, 0.5, 0.8 - 1e-9),
        (0.5, 0.5 + 1e-9, 0.9),
    ],
)
def test_separatrix_limit_is_a_lune(moments):
    """At |dtheta| = 1e-300 the polhode is the separatrix to 1e-300."""
    i1, i2, i3 = sorted(moments)
    chi = math.atan2(math.sqrt(i1 * (i3 - i2)), math.sqrt(i3 * (i2 - i1)))
    sam, lam = orbits.phases(moments, dtheta=[-1e-300, 1e-300])["geometric_phase"]
    assert sam == pytest.approx(4 * chi, rel=1e-14)
    assert lam == pytest.approx(-4 * (math.pi / 2 - chi), rel=1e-14)
    assert sam - lam == pytest.approx(2 * math.pi, rel=1e-15)


def test_zero_on_the_axes():
    assert orbits.phases(FIG6, [0.0])["geometric_phase"].tolist() == [0.0]
    # the double nearest pi/2 is 6.1e-17 short of the I1 axis
    end = orbits.phases(FIG6, [math.pi / 2])["geometric_phase"].iloc[0]
    assert end == pytest.approx(mp_omega(FIG6, theta=math.pi / 2), rel=BOUND)
    assert -1e-30 < end < 0.0
    spins = orbits.spin_phases(FIG6, [[0.0, 0.0, 2.0], [3.0, 0.0, 0.0]])
    assert spins["geometric_phase"].tolist() == [0.0, 0.0]


@pytest.mark.parametrize("moments", [FIG6, NEAR_SPHERE, (1e-3, 1.0, 1.0005)])
@pytest.mark.parametrize("theta", [1e-150, 1e-40, 1e-8, math.pi / 2 - 1e-8, math.pi / 2 - 1e-15])
def test_near_the_axes(moments, theta):
    """Omega ~ theta^2 (or (pi/2 - theta)^2) keeps its relative precision."""
    got = orbits.phases(moments, theta)["geometric_phase"].iloc[0]
    assert got == pytest.approx(mp_omega(moments, theta=theta), rel=BOUND)


# --------------------------------------------------------------------------
# Direct quadrature of the solid angle (the geometric definition)
# --------------------------------------------------------------------------
QUADRATURE_CASES = [
    (
        T_HANDLE.moments,
        (
            math.cos(math.pi / 2 - 0.2) * math.sin(math.pi / 2 - 0.15),
            math.sin(math.pi / 2 - 0.2) * math.sin(math.pi / 2 - 0.15),
            math.cos(math.pi / 2 - 0.15),
        ),
    ),
    (FIG6, (0.3, 0.0, 1.0)),
    (FIG6, (1.0, 0.2, 0.4)),
    (FIG6, (0.2, 0.9, 1.0)),
    (NEAR_SPHERE, (0.4, 0.1, 1.0)),
    (NEAR_SPHERE, (1.0, 0.5, 0.2)),
    ((1e-3, 1.0, 1.0005), (0.1, 0.3, 1.0)),
    ((1e-3, 1.0, 1.0005), (1.0, 1e-3, 1e-2)),
    (FIG6, (1e-6, 2e-7, 1.0)),
    (FIG6, (1.0, 3e-7, -1e-6)),
]


@pytest.mark.parametrize("moments, omega", QUADRATURE_CASES)
def test_direct_quadrature_of_the_cap(moments, omega):
    got = orbits.spin_phases(moments, omega)["geometric_phase"].iloc[0]
    assert got == pytest.approx(mp_cap(moments, omega), rel=BOUND)


def test_t_handle_paper_value():
    """Sec. II.D: 2ET/M - Delta alpha = 23.6555 - 21.5303; the paper's own
    quadrature gave the coarser 2.1253 (erratum 8)."""
    moments, omega = QUADRATURE_CASES[0]
    got = orbits.spin_phases(moments, omega)["geometric_phase"].iloc[0]
    assert got == pytest.approx(2.12519, abs=5e-6)


# --------------------------------------------------------------------------
# CLI: orbits phase --omega takes Omega from spin_phases
# --------------------------------------------------------------------------
def test_cli_omega_nearly_spherical():
    out = io.StringIO()
    with redirect_stdout(out):
        code = cli_main(
            [
                "phase",
                "--moments",
                "1",
                "1.000000000001",
                "1.000000000002",
                "--omega",
                "1",
                "0.2",
                "0.3",
                "--csv",
            ]
        )
    assert code == 0
    row = pd.read_csv(io.StringIO(out.getvalue()), comment="#", **csv_float_options()).iloc[0]
    want = mp_omega(NEAR_SPHERE, omega=(1.0, 0.2, 0.3))
    assert row["geometric_phase"] == pytest.approx(want, rel=BOUND)
    assert row["geometric_phase"] < 0 and row["branch"] == "LAM"


# --------------------------------------------------------------------------
# Hypothesis: bodies from the rod corner to the sphere, offsets to 1e-300
# --------------------------------------------------------------------------
def _as_computed(body):
    """The moments the library computes with: a body drawn just beyond the flat
    edge by rounding (fl(a + b) > a + b) is moved exactly onto it."""
    return tuple(float(v) for v in orbits.Body(body).moments)


@st.composite
def near_bodies(draw):
    """``(a, a + a 10^x, a + a 10^x + a 10^y)``: gaps from 1e-12 to the edges."""
    a = draw(st.floats(1e-3, 1e3))
    x = draw(st.floats(-12.0, 1.0))
    y = draw(st.floats(-12.0, 0.0))
    i2 = a + a * 10.0**x
    i3 = i2 + a * 10.0**y
    if not (a < i2 < i3 <= a + i2):
        i3 = np.nextafter(a + i2, 0.0)
    return (a, i2, i3)


@settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck))
@given(
    body=near_bodies(),
    side=st.sampled_from([-1.0, 1.0]),
    exponent=st.floats(-300.0, 0.0),
    phi=st.sampled_from([0.0, 0.7, 2.0]),
)
def test_hypothesis_dtheta(body, side, exponent, phi):
    theta_c = orbits.critical_angle(body, phi)
    room = theta_c if side < 0 else math.pi / 2 - theta_c
    # within 1% of an axis theta = theta_c + dtheta is rounded to ulp(theta_c),
    # i.e. ulp(theta_c)/theta relatively (Omega ~ theta^2): pass theta there
    dtheta = side * min(10.0**exponent, 0.99 * room)
    got = orbits.phases(body, dtheta=[dtheta], phi=phi)["geometric_phase"].iloc[0]
    assert got == pytest.approx(mp_omega(_as_computed(body), phi, dtheta=dtheta), rel=BOUND)


@settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))
@given(
    body=near_bodies(),
    theta=st.one_of(
        st.floats(0.0, math.pi / 2),
        st.floats(-150.0, -1.0).map(lambda e: 10.0**e),
        st.floats(-15.0, -1.0).map(lambda e: math.pi / 2 - 10.0**e),
    ),
)
def test_hypothesis_theta(body, theta):
    theta_c = orbits.critical_angle(body)
    if abs(theta - theta_c) <= 8 * np.spacing(theta_c):
        return  # theta_c is known to a few ulps: the branch itself is uncertain
    got = orbits.phases(body, [theta])["geometric_phase"].iloc[0]
    assert got == pytest.approx(mp_omega(_as_computed(body), theta=theta), rel=BOUND)


@settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))
@given(
    body=near_bodies(),
    omega=st.tuples(
        *[
            st.tuples(st.sampled_from([-1.0, 1.0]), st.floats(-40.0, 2.0)).map(
                lambda t: t[0] * 10.0 ** t[1]
            )
        ]
        * 3
    ),
)
def test_hypothesis_spin_vectors(body, omega):
    """Any spin vector (the spin_phases path, taken as exact doubles)."""
    try:
        got = orbits.spin_phases(body, omega)["geometric_phase"].iloc[0]
    except orbits.SeparatrixError:
        return
    assert got == pytest.approx(mp_omega(_as_computed(body), omega=omega), rel=BOUND)


# ------------------------------------------------------------------------
# Each test below kills a mutant of orbits/core/solid_angle.py that passed the suite (a
# mutation audit of the core kernels, 2026-11-29: 49 mutants, 11 survivors
# that changed an output).

FIG6_UNIT = Body(Body.preset("fig6").normalized_moments)


@pytest.mark.parametrize("omega", [[1e-3, 0.0, 1.0], [0.3, 0.2, 0.9]])
@pytest.mark.parametrize("scale", [3e-154, 1.3e154])
def test_geometric_phase_of_a_spin_vector_is_scale_free(omega, scale):
    """S5: solid_angle_from_vector_array must scale the spin by 2**-speed
    (mutant: speed 0).  Omega does not depend on |omega|; at |omega| ~ 3e-154
    the unscaled gaps are subnormal (mutant: 1.0e-10 relative error near I3)."""
    import orbits

    omega = np.asarray(omega)
    unit = float(np.asarray(orbits.spin_phases(FIG6_UNIT, omega)["geometric_phase"])[0])
    scaled = float(np.asarray(orbits.spin_phases(FIG6_UNIT, omega * scale)["geometric_phase"])[0])
    assert scaled == pytest.approx(unit, rel=1e-14, abs=0)
