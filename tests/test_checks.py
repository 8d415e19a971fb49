"""Independent checks: the paper's numbers, their agreement, and that they can fail."""

import json
import math

import mpmath as mp
import numpy as np
import pytest
from mp_formulas import period_and_total_phase

import orbits
from orbits import Body, checks
from orbits.atomic import csv_float_options
from orbits.cli import main
from orbits.errors import InputError

T_HANDLE = Body.t_handle(8, 4, 1)
FIG6 = Body.preset("fig6")
SPIN = dict(theta=math.pi / 2 - 0.15, phi=math.pi / 2 - 0.2)  # Fig. 3


class TestTHandle:
    """Sec. II.D: all three checks give 2.68074 (mod 2 pi), i.e. 21.5303."""

    @pytest.mark.parametrize("engine", ["scipy", "compiled"])
    def test_ode_rotation(self, engine):
        result = checks.rotation_by_integration(T_HANDLE, **SPIN, engine=engine)
        assert round(result.angle, 5) == 2.68074
        assert result.error <= 1e-10
        assert result.off_axis <= 1e-10
        assert result.period == pytest.approx(23.8181, abs=5e-5)

    def test_montgomery(self):
        result = checks.montgomery(T_HANDLE, **SPIN)
        assert round(result.solid_angle, 5) == 2.12519  # not the paper's 2.1253
        assert round(result.dynamic_phase, 4) == 23.6555
        assert round(result.total_phase, 4) == 21.5303
        assert result.total_phase == pytest.approx(orbits.total_phase(T_HANDLE, **SPIN), abs=1e-12)

    def test_exact_motion(self):
        value = checks.motion_phase(T_HANDLE, **SPIN)
        assert round(value % (2 * math.pi), 5) == 2.68074
        assert value == pytest.approx(orbits.total_phase(T_HANDLE, **SPIN), abs=1e-12)


def test_montgomery_solid_angle_by_brute_force():
    """Omega as the area of the cap the polhode bounds, from the polhode
    points alone (spherical polygon, many vertices)."""
    t, momentum = orbits.polhode(T_HANDLE, **SPIN, points=20001)
    unit = momentum / np.linalg.norm(momentum, axis=1)[:, None]
    # signed area of the spherical polygon about the I3 pole (SAM)
    phi = np.unwrap(np.arctan2(unit[:, 1], unit[:, 0]))
    cap = np.trapezoid(1.0 - unit[:, 2], phi)
    assert cap == pytest.approx(2.12519, abs=5e-6)


@pytest.mark.parametrize("theta", [0.3, 0.9, 1.0, 1.05, 1.3, 1.55])
def test_montgomery_sign_and_geometric_phase(theta):
    row = orbits.phases(FIG6, theta).iloc[0]
    result = checks.montgomery(FIG6, theta)
    assert np.sign(result.solid_angle) == (1 if row.branch == "SAM" else -1)
    assert result.solid_angle == pytest.approx(row.geometric_phase, abs=1e-11)
    assert result.period == pytest.approx(row.period, rel=1e-13)


@pytest.mark.parametrize("theta, phi", [(0.4, 0.0), (1.2, 0.0), (0.7, 1.1), (1.45, -0.6)])
def test_compiled_dop853_agrees_with_solve_ivp(theta, phi):
    a = checks.rotation_by_integration(FIG6, theta, phi=phi, engine="scipy")
    b = checks.rotation_by_integration(FIG6, theta, phi=phi, engine="compiled")
    assert b.period == pytest.approx(a.period, rel=1e-11)
    assert checks.circular_distance(a.angle, b.angle) <= 1e-10
    assert a.error <= 1e-9 and b.error <= 1e-9


def test_several_periods():
    result = checks.rotation_by_integration(FIG6, 1.2, periods=3, engine="compiled")
    assert result.error <= 1e-9
    assert result.expected == pytest.approx(
        (3 * orbits.total_phase(FIG6, 1.2)) % (2 * math.pi), abs=1e-12
    )


def test_checks_detect_the_printed_lam_formula():
    """The checks can fail: eqn:alphatheta as printed (beta in the LAM
    characteristic) disagrees with Montgomery by far more than the tolerance."""
    theta = 1.2
    i1, i2, i3 = (mp.mpf(float(v)) for v in FIG6.moments)
    beta = i1 * (i2 - i1) / (i3 * (i3 - i2))
    cot2 = 1 / mp.tan(theta) ** 2
    pre = 4 * mp.sqrt(i2 * (i1**2 + i3**2 * cot2) / (i1**2 * i3 * (i3 - i1) * (i2 - i1)))
    m = cot2 / beta
    printed = float(
        pre * (i1 * mp.ellipk(m) + (i3 - i1) * mp.ellippi(-(i3**2) * cot2 * beta / i1**2, m))
    )
    assert abs(printed - checks.montgomery(FIG6, theta).total_phase) > 1e-3


def test_verify_small_run_and_report():
    report = checks.verify(20, 5)
    assert report.passed
    assert report.summary["initial_conditions"] == 100
    assert len(report.table) == 100
    assert set(report.table["branch"]) == {"SAM", "LAM"}
    for name in ("montgomery", "ode_rotation", "exact_motion"):
        assert 0.0 <= report.summary["checks"][name]["max_abs_error"] <= 1e-9


def test_verify_fails_on_impossible_tolerance():
    report = checks.verify(5, 3, tolerance=1e-18)
    assert not report.passed


@pytest.mark.parametrize("bodies, expected", [(None, 6446), ("2930", 64460)])
def test_cli_verify_paper_count_and_ten_times(capsys, bodies, expected):
    argv = ["verify", "--json", "--no-progress"] + (["--bodies", bodies] if bodies else [])
    code = main(argv)
    out = json.loads(capsys.readouterr().out)
    assert code == 0
    assert out["initial_conditions"] == expected
    assert set(out["checks"]) == {"montgomery", "ode_rotation", "exact_motion"}
    for check in out["checks"].values():
        assert check["max_abs_error"] <= 1e-9


def test_cli_verify_exit_code_and_table(capsys, tmp_path):
    path = tmp_path / "ics.csv"
    assert (
        main(
            [
                "verify",
                "--bodies",
                "3",
                "--angles",
                "2",
                "--tolerance",
                "1e-18",
                "--no-progress",
                "--table",
                str(path),
            ]
        )
        == 1
    )
    out = capsys.readouterr().out
    assert "FAIL" in out
    import pandas as pd

    table = pd.read_csv(path, **csv_float_options())
    assert len(table) == 6 and "montgomery_error" in table


def test_cli_verify_bad_arguments(capsys):
    assert main(["verify", "--bodies", "0"]) == 2
    assert "must be an integer >= 1" in capsys.readouterr().err
    assert main(["verify", "--bodies", "2", "--table", "/nonexistent/dir/x.csv"]) == 2
    assert "does not exist" in capsys.readouterr().err


def _strict_json(text):
    """json.loads that refuses NaN and Infinity (as strict parsers do)."""

    def refuse(constant):
        raise ValueError(f"non-strict JSON constant {constant}")

    return json.loads(text, parse_constant=refuse)


def test_verify_nearly_symmetric_body_is_finite_strict_and_labelled(capsys):
    """Moments 1, 1 + 1e-8, 1 + 2e-8: the period is ~4e9 / |w0| (~1e9 turns).

    The ODE check cannot integrate that within its step budget: it is
    reported not applicable with a reason (never NaN); the exact motion
    agrees with the closed form to a few spacings of doubles at 4e9 rad.
    """
    code = main(
        ["verify", "--moments", "1", "1.00000001", "1.00000002", "--angles", "1", "--json"]
    )
    out = _strict_json(capsys.readouterr().out)
    assert code == 1  # 1e-9 rad cannot be resolved at 4e9 rad
    assert out["body"] == "moments(1, 1.00000001, 1.00000002)"
    assert out["moments"] == [1.0, 1.00000001, 1.00000002]
    ode = out["checks"]["ode_rotation"]
    assert ode["max_abs_error"] is None and ode["not_applicable"] == 1
    assert "did not complete one period within 10,000,000 steps" in ode["reason"]
    assert out["ode_period_max_abs_error"] is None
    # theta = pi/4: Delta alpha ~ 3.9e9 rad, where doubles are 4.8e-7 apart
    assert 3.8e9 < out["max_abs_phase"] < 4.0e9
    assert out["phase_resolution"] == np.spacing(out["max_abs_phase"])
    motion = out["checks"]["exact_motion"]
    assert motion["failed_to_evaluate"] == 0 and motion["reason"] is None
    assert 0.0 <= motion["max_abs_error"] <= 4 * out["phase_resolution"]
    assert math.isfinite(out["checks"]["montgomery"]["max_abs_error"])


def test_verify_summary_has_no_nan_and_explains_missing_values():
    """_summarize on a hand-made table: NaN never reaches the summary."""
    import pandas as pd

    nan = float("nan")
    table = pd.DataFrame(
        {
            "closed_form": [1.0, 2.0, nan],
            "period": [6.0, 7.0, nan],
            "montgomery_error": [1e-12, nan, nan],
            "motion_error": [2e-12, 3e-12, nan],
            "ode_error": [nan, 5e-11, nan],
            "ode_period_error": [nan, 1e-10, nan],
        }
    )
    exhausted = np.array([True, False, False])
    summary = checks._summarize(table, 1e-9, exhausted)
    json.dumps(summary, allow_nan=False)
    assert not summary["passed"]  # a separatrix row and a missing Montgomery value
    montgomery = summary["checks"]["montgomery"]
    assert montgomery["max_abs_error"] == 1e-12 and montgomery["failed_to_evaluate"] == 1
    ode = summary["checks"]["ode_rotation"]
    assert ode["max_abs_error"] == 5e-11 and ode["not_applicable"] == 1
    assert "closed-form period up to 6 / |w0|" in ode["reason"]
    assert "1 initial condition(s) on the separatrix" in ode["reason"]
    assert summary["ode_period_max_abs_error"] == 1e-10
    assert summary["max_abs_phase"] == 2.0
    # the ODE check alone not applicable is no failure
    first = table.iloc[:1].assign(montgomery_error=[1e-12])
    ok = checks._summarize(first, 1e-9, exhausted[:1])
    assert ok["passed"] and ok["checks"]["ode_rotation"]["not_applicable"] == 1
    assert ok["checks"]["ode_rotation"]["max_abs_error"] is None
    # an ODE value missing for any other reason than the step budget fails
    failed = checks._summarize(first, 1e-9, np.array([False]))
    ode = failed["checks"]["ode_rotation"]
    assert not failed["passed"]
    assert ode["not_applicable"] == 0 and ode["failed_to_evaluate"] == 1
    assert ode["reason"] == "no value (not finite) at 1 initial condition(s)"


def test_rotation_by_integration_refuses_a_period_beyond_its_budget():
    """No NaN: the nearly symmetric body's period (~4e9 / |w0|) is beyond both engines."""
    body = orbits.Body((1.0, 1.00000001, 1.00000002))
    with pytest.raises(InputError, match="did not reach the end of period 1 within 10,000,000"):
        orbits.rotation_by_integration(body, 0.7, engine="compiled")
    # SciPy's engine refuses up front rather than stepping in Python for hours
    with pytest.raises(InputError, match=r"1\.2\d*e\+08 turns of omega, beyond the 10,000"):
        orbits.rotation_by_integration(body, 0.7, engine="scipy")


def test_rotation_after_periods_marks_the_step_budget():
    """The kernel's period is -1 when the steps ran out, a real period otherwise."""
    from orbits.core import checks as kernel

    body = orbits.Body((1.0, 1.00000001, 1.00000002))
    w = orbits.Motion.from_spin(body, 0.7).omega0
    period, angle, off_axis = kernel.rotation_after_periods(
        *body.moments, *w, 1, 1e-12, 1e-14, 1000
    )
    assert period == kernel.STEP_BUDGET_EXHAUSTED
    assert math.isnan(angle) and math.isnan(off_axis)
    fig = orbits.Body.preset("t-handle")
    w = orbits.Motion.from_spin(fig, 1.2).omega0
    period, angle, off_axis = kernel.rotation_after_periods(*fig.moments, *w, 1, 1e-12, 1e-14, 10)
    assert period == kernel.STEP_BUDGET_EXHAUSTED  # 10 steps are too few here too
    period, _, _ = kernel.rotation_after_periods(*fig.moments, *w, 1, 1e-12, 1e-14, 10**6)
    assert period > 0.0
    assert abs(period - orbits.Motion.from_spin(fig, 1.2).period) < 1e-9 * period


@pytest.mark.parametrize(
    "moments, theta",
    [
        ((1.0, 1.00000001, 1.00000002), 0.7),  # nearly symmetric: period ~8e8
        ((1.0, 1.0000001, 2.0), 0.3),
        ((1.0, 1.9999999, 2.0), 1.2),
        ((0.3, 0.7, 0.9), 0.5),
    ],
)
def test_montgomery_keeps_the_digits_moments_share(moments, theta):
    """Montgomery's 2ET/M - Omega against eqn:GeometricPhase in mpmath (40 digits),
    on the same double omega0: nearly equal moments must not cost digits (the
    quadrature's 1/Ii - 1/Ij are formed as (Ij - Ii)/(Ii Ij); the difference of
    rounded reciprocals was off by 0.36 rad for the first body)."""

    body = Body(moments)
    check = checks.montgomery(body, theta)
    w = orbits.Motion.from_spin(body, theta).omega0
    with mp.workdps(40):
        i1, i2, i3 = (mp.mpf(float(v)) for v in body.moments)
        w1, w2, w3 = (mp.mpf(float(v)) for v in w)
        two_e = i1 * w1**2 + i2 * w2**2 + i3 * w3**2
        m_sq = i1**2 * w1**2 + i2**2 * w2**2 + i3**2 * w3**2
        period, total = period_and_total_phase(i1, i2, i3, two_e, m_sq)
    assert check.period == pytest.approx(float(period), rel=1e-12)
    assert check.total_phase == pytest.approx(float(total), rel=1e-12)


@pytest.mark.parametrize("scale", [2.0**-700, 1e-200, 1e200, 2.0**700])
def test_checks_are_scale_free(scale):
    """The three checks on moments scaled by 1e-200 .. 1e200: the same numbers
    (Montgomery's bit for bit at powers of two), not a ZeroDivisionError or an
    overflow."""
    unit = Body((1.0, 2.0, 3.0))
    scaled = Body((scale, 2.0 * scale, 3.0 * scale))
    expected = checks.montgomery(unit, 0.7)
    got = checks.montgomery(scaled, 0.7)
    if math.frexp(scale)[0] == 0.5:  # a power of two: the same body, bit for bit
        assert got == expected
    else:  # 3 * 1e-200 rounds differently from 3: the body differs by an ulp
        for field in expected._fields:
            assert getattr(got, field) == pytest.approx(getattr(expected, field), rel=1e-14)
    rotation = checks.rotation_by_integration(scaled, 0.7, engine="compiled")
    assert rotation.error < 1e-9
    assert rotation.period == pytest.approx(expected.period, rel=1e-10)
    assert checks.motion_phase(scaled, 0.7) == pytest.approx(expected.total_phase, rel=1e-13)
