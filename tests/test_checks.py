"""Independent checks: the paper's numbers, their agreement, and that they can fail."""

import json
import math
import os

import mpmath as mp
import numpy as np
import pytest
from mp_formulas import period_and_total_phase
from verify_faults import wrong_closed_form

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


@pytest.mark.parametrize("engine", ["scipy", "compiled"])
def test_ode_rotation_error_is_against_the_closed_form(engine, monkeypatch):
    """The check has teeth: a closed form 0.1 rad off is an error of 0.1
    (an error computed from the integrated angle against itself read 1e-12
    and passed every test)."""
    original = checks.motion_closed_form
    monkeypatch.setattr(checks, "motion_closed_form", lambda motion: original(motion) + 0.1)
    result = checks.rotation_by_integration(T_HANDLE, **SPIN, engine=engine)
    assert result.error == pytest.approx(0.1, abs=1e-9)
    assert round(result.angle, 5) == 2.68074  # the integration itself unchanged


def _circular(angle):
    return abs((angle + math.pi) % (2 * math.pi) - math.pi)


@pytest.mark.parametrize("dtheta", [0.05, -0.2, 3e-4, -5e-5])
@pytest.mark.parametrize("periods", [1, 2])
def test_closure_errors_of_orbits_that_do_not_close(dtheta, periods):
    """On an orbit that is not closed, the closure error is the angle q
    Delta alpha reduced to [0, pi] (both paths: the direct integration for
    |dtheta| >= 1e-3, the quarter period closer in); a direct path that
    integrated half the angle still flagged such orbits, with wrong values."""
    alpha = float(orbits.total_phase(FIG6, dtheta=dtheta))
    expected = _circular(periods * alpha)
    assert expected > 0.05  # not closed
    got = checks.closure_errors(FIG6.moments, dtheta, periods)
    assert got == pytest.approx(expected, abs=1e-9)


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


def test_verify_at_a_tiny_tolerance_holds_each_check_to_its_own_floor(monkeypatch):
    """At tolerance 1e-18 (below what doubles can hold) each check is held to
    its floor: (b), (c) to 16 ulps of the phase, (a) to its integrator's error
    (it used to fail there on the ODE check alone, 6e-12 off at rtol 1e-12);
    a closed form 1e-12 (relative) wrong still fails (b) and (c)."""
    report = checks.verify(5, 3, tolerance=1e-18)
    assert report.passed
    spacing = np.spacing(report.table["closed_form"].abs())
    for column in ("montgomery_error", "motion_error"):
        assert (report.table[column] <= checks.PHASE_ULPS * spacing).all()
    ode = report.summary["checks"]["ode_rotation"]
    assert ode["within_integrator_error_only"] == 15 and ode["max_fraction_of_allowance"] < 0.1
    wrong_closed_form(monkeypatch, 1.0 + 1e-12)
    report = checks.verify(5, 3, tolerance=1e-18)
    assert not report.passed
    for name in ("montgomery", "exact_motion"):
        assert report.summary["checks"][name]["beyond_tolerance"] == 15


@pytest.mark.parametrize("bodies, expected", [(None, 6446), ("2930", 64460)])
def test_cli_verify_paper_count_and_ten_times(capsys, bodies, expected):
    argv = ["verify", "--json", "--no-progress"] + (["--bodies", bodies] if bodies else [])
    code = main(argv)
    out = json.loads(capsys.readouterr().out)
    assert code == 0
    assert out["initial_conditions"] == expected
    assert set(out["checks"]) == {
        "montgomery",
        "ode_rotation",
        "exact_motion",
        "theta_orbit",
        "closed_form_routes",
    }
    for check in out["checks"].values():
        assert check["max_abs_error"] <= 1e-9 and check["passed"]
    # the public routes agree with the scalar closed form to a few ulps
    routes = out["checks"]["closed_form_routes"]
    assert routes["max_ulps"] <= 16
    assert set(routes["routes"]) == {name for name, _ in checks.ROUTES}


def test_cli_verify_exit_code_and_table(capsys, tmp_path, monkeypatch):
    path = tmp_path / "ics.csv"
    wrong_closed_form(monkeypatch, 1.0 + 1e-9)
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


def test_cli_verify_bad_arguments(capsys, tmp_path):
    assert main(["verify", "--bodies", "0"]) == 2
    assert "must be an integer >= 1" in capsys.readouterr().err
    assert main(["verify", "--bodies", "2", "--table", str(tmp_path / "missing/x.csv")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


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
    # 1e-9 rad cannot be resolved at 4e9 rad: PHASE_ULPS spacings of doubles pass
    # (exit 1 before, for results correct to the last bits)
    assert code == 0 and out["passed"]
    assert out["phase_ulps"] == checks.PHASE_ULPS == 16
    assert out["largest_allowance"] == 16 * out["phase_resolution"]
    assert out["body"] == "moments(1, 1.00000001, 1.00000002)"
    assert out["moments"] == [1.0, 1.00000001, 1.00000002]
    ode = out["checks"]["ode_rotation"]
    assert ode["max_abs_error"] is None and ode["not_applicable"] == 1
    # refused before integrating (it ran 10^7 steps, 4 to 7 s, to find that out)
    assert "one period needs more than 10,000,000 steps at 1 initial" in ode["reason"]
    assert "which were not integrated (at least 1e+09 steps" in ode["reason"]
    assert out["ode_period_max_abs_error"] is None
    # theta = pi/4: Delta alpha ~ 3.9e9 rad, where doubles are 4.8e-7 apart
    assert 3.8e9 < out["max_abs_phase"] < 4.0e9
    assert out["phase_resolution"] == np.spacing(out["max_abs_phase"])
    motion = out["checks"]["exact_motion"]
    assert motion["failed_to_evaluate"] == 0 and motion["reason"] is None
    assert 0.0 <= motion["max_abs_error"] <= 4 * out["phase_resolution"]
    # Montgomery's quadrature keeps the last bits too (it was 160 ulps off here)
    montgomery = out["checks"]["montgomery"]
    assert 0.0 <= montgomery["max_abs_error"] <= 4 * out["phase_resolution"]
    assert montgomery["max_ulps"] <= 4


def test_verify_summary_has_no_nan_and_explains_missing_values():
    """_summarize on a hand-made table: NaN never reaches the summary."""
    import pandas as pd

    nan = float("nan")
    table = pd.DataFrame(
        {
            "closed_form": [1.0, 2.0, nan],
            "closed_form_theta": [1.0, 2.0, nan],
            "period": [6.0, 7.0, nan],
            "montgomery_error": [1e-12, nan, nan],
            "motion_error": [2e-12, 3e-12, nan],
            "ode_error": [nan, 5e-11, nan],
            "ode_period_error": [nan, 1e-10, nan],
            "routes_error": [0.0, 0.0, nan],
            "theta_orbit_error": [0.0, 0.0, nan],
            **{f"route_{name}": [1.0, 2.0, nan] for name, _ in checks.ROUTES},
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


# ------------------------------------------------ argument checks (API)

BAD_COUNTS = [0, -1, 1.5, float("nan"), float("inf"), None, "2", True]


@pytest.mark.parametrize("chunk", [0, -1, -7, 1.5, float("nan"), float("inf"), None, "8", True])
def test_verify_refuses_a_bad_chunk_before_any_work(chunk, monkeypatch):
    """chunk=-1 checked nothing and passed (np.empty read as zeros); 0 and 1.5
    were a ValueError and a TypeError."""
    _no_kernels(monkeypatch)
    with pytest.raises(orbits.OrbitsError, match="chunk"):
        checks.verify(3, 2, chunk=chunk)
    with pytest.raises(orbits.OrbitsError, match="chunk"):
        checks.verify_body(FIG6, 2, chunk=chunk)


def test_verify_never_reads_a_row_the_kernel_did_not_write(monkeypatch):
    """A kernel that writes nothing must not give a report (np.full(nan) and a
    count of the rows done; np.empty gave zeros, and so passed=True)."""
    from orbits.core import checks as kernel

    monkeypatch.setattr(kernel, "check_batch", lambda *args: None)
    with pytest.raises(AssertionError, match="not evaluated"):
        checks.verify(300, 22)
    with pytest.raises(AssertionError, match="not evaluated"):
        checks.verify_body(FIG6, 5)


@pytest.mark.parametrize("value", BAD_COUNTS)
def test_verify_refuses_bad_counts(value, monkeypatch):
    _no_kernels(monkeypatch)
    with pytest.raises(orbits.OrbitsError, match="n_bodies"):
        checks.verify(value, 2)
    with pytest.raises(orbits.OrbitsError, match="n_angles"):
        checks.verify(2, value)
    with pytest.raises(orbits.OrbitsError, match="n_angles"):
        checks.verify_body(FIG6, value)


@pytest.mark.parametrize("value", [0.0, -1.0, float("nan"), float("inf"), "1e-9", None, True])
def test_verify_refuses_a_bad_tolerance(value, monkeypatch):
    """-1 and nan gave passed=False silently, inf passed, text was a TypeError."""
    _no_kernels(monkeypatch)
    with pytest.raises(orbits.OrbitsError, match="tolerance"):
        checks.verify(2, 2, tolerance=value)
    with pytest.raises(orbits.OrbitsError, match="tolerance"):
        checks.verify_body(FIG6, 2, tolerance=value)


def test_verify_refuses_a_progress_that_is_not_callable(monkeypatch):
    _no_kernels(monkeypatch)
    with pytest.raises(orbits.ArgumentTypeError, match="progress"):
        checks.verify(2, 2, progress="yes")


def test_verify_refuses_more_conditions_than_memory_holds(monkeypatch):
    _no_kernels(monkeypatch)
    with pytest.raises(InputError, match="memory"):
        checks.verify(1, 10**15)
    with pytest.raises(InputError, match="memory"):
        checks.verify_body(FIG6, 10**15)


def _no_kernels(monkeypatch):
    """Replace every integrator and quadrature with one that fails the test:
    bad arguments must be refused before compiled code (where a bad
    tolerance hung for minutes, uninterruptibly)."""
    from orbits.core import checks as kernel

    def entered(*args, **kwargs):
        raise AssertionError("a compiled check was entered with bad arguments")

    for module, name in [
        (kernel, "check_batch"),
        (kernel, "montgomery_phase"),
        (kernel, "rotation_after_periods"),
        (kernel, "closure_batch"),
        (checks, "_rotation_scipy"),
        (checks, "region_sample"),
    ]:
        monkeypatch.setattr(module, name, entered)


BAD_TOLERANCES = [
    0.0,
    -1.0,
    float("nan"),
    float("inf"),
    1e-300,
    0.5,
    "1e-12",
    None,
    True,
    [1e-12, 1e-12],
]


@pytest.mark.parametrize("rtol", BAD_TOLERANCES + [1e-16])
def test_montgomery_refuses_a_bad_rtol(rtol, monkeypatch):
    """rtol 0, -1 and nan hung in the quadrature (minutes, uninterruptible)."""
    _no_kernels(monkeypatch)
    with pytest.raises(orbits.OrbitsError, match="rtol"):
        checks.montgomery(FIG6, 0.5, rtol=rtol)


@pytest.mark.parametrize("engine", ["scipy", "compiled"])
@pytest.mark.parametrize("name", ["rtol", "atol"])
@pytest.mark.parametrize("value", BAD_TOLERANCES)
def test_rotation_by_integration_refuses_bad_tolerances(engine, name, value, monkeypatch):
    """rtol nan hung both engines; rtol = atol = 0 was a ZeroDivisionError,
    atol -1 a garbage result, rtol 'x' a numpy error, rtol = atol = 1e-300
    ran for minutes."""
    _no_kernels(monkeypatch)
    with pytest.raises(orbits.OrbitsError, match=name):
        checks.rotation_by_integration(FIG6, 0.5, engine=engine, **{name: value})


def test_rotation_by_integration_tolerance_floors(monkeypatch):
    """Below SciPy's own floor (100 eps, which it would raise rtol to
    silently) and below 1e-100 for atol (SciPy's error norm overflows)."""
    _no_kernels(monkeypatch)
    low_rtol, _ = checks.ODE_RTOL_RANGE
    low_atol, _ = checks.ODE_ATOL_RANGE
    assert low_rtol == 100 * np.finfo(float).eps and low_atol == 1e-100
    with pytest.raises(InputError, match="rtol"):
        checks.rotation_by_integration(FIG6, 0.5, rtol=np.nextafter(low_rtol, 0))
    with pytest.raises(InputError, match="atol"):
        checks.rotation_by_integration(FIG6, 0.5, atol=1e-101)


def test_the_tolerance_floors_are_met():
    """At the floors both engines still finish, quickly, and agree."""
    low_rtol, _ = checks.ODE_RTOL_RANGE
    low_atol, _ = checks.ODE_ATOL_RANGE
    for engine in ("scipy", "compiled"):
        result = checks.rotation_by_integration(
            FIG6, 0.5, rtol=low_rtol, atol=low_atol, engine=engine
        )
        assert result.error <= 1e-12
    low, _ = checks.MONTGOMERY_RTOL_RANGE
    assert checks.montgomery(FIG6, 0.5, rtol=low).total_phase == pytest.approx(
        orbits.total_phase(FIG6, 0.5), rel=1e-15
    )


@pytest.mark.parametrize("rtol", [0.0, 1e-300, 1e-20, float("nan"), 1e-2, "x"])
def test_closure_errors_refuses_an_rtol_it_cannot_meet(rtol, monkeypatch):
    """rtol 1e-300 hung near the separatrix (the quarter-period integration's
    tolerance below rounding); 1e-20 took 3 s for four orbits."""
    _no_kernels(monkeypatch)
    with pytest.raises(orbits.OrbitsError, match="rtol"):
        checks.closure_errors(FIG6.moments, [1e-4, 0.01], [1, 1], rtol=rtol)


def test_closure_errors_of_one_orbit_given_as_scalars_is_a_float():
    """A scalar dtheta and q for one body gave an array of shape (1,), as
    its budget did; an array argument keeps one entry per orbit."""
    one = checks.closure_errors(FIG6.moments, -0.05, 1)
    many = checks.closure_errors(FIG6.moments, [-0.05, 1e-4], [1, 1])
    assert isinstance(one, float)
    assert one == many[0]
    assert checks.closure_errors(FIG6.moments, [-0.05], 1).shape == (1,)
    assert checks.closure_errors(FIG6.moments, -0.05, [1]).shape == (1,)
    assert checks.closure_errors([FIG6.moments], -0.05, 1).shape == (1,)
    budget = checks.closure_error_budget(FIG6.moments, 1e-4, 1)
    assert isinstance(budget, float)
    assert budget == checks.closure_error_budget(FIG6.moments, [-0.05, 1e-4], [1, 1])[1] > 0.0


@pytest.mark.parametrize("periods", [0, -1, 1.5, float("nan"), float("inf"), True, "1", 10**6])
def test_rotation_by_integration_refuses_bad_periods(periods, monkeypatch):
    """nan and inf were a ValueError and an OverflowError, True ran 1 period."""
    _no_kernels(monkeypatch)
    with pytest.raises(orbits.OrbitsError, match="periods"):
        checks.rotation_by_integration(FIG6, 0.5, periods=periods)


@pytest.mark.parametrize("engine", ["x", None, 1, ["scipy"], np.array(["scipy", "compiled"])])
def test_rotation_by_integration_refuses_a_bad_engine(engine, monkeypatch):
    _no_kernels(monkeypatch)
    with pytest.raises(InputError, match="engine"):
        checks.rotation_by_integration(FIG6, 0.5, engine=engine)


def test_cli_verify_refuses_an_empty_table_name(capsys):
    """--table '' was taken as not given (exit 0, no file written)."""
    assert main(["verify", "--bodies", "2", "--angles", "1", "--table", ""]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "--table" in err


@pytest.mark.parametrize("json_flag", [[], ["--json"]])
def test_cli_verify_refuses_a_table_on_standard_output(capsys, json_flag):
    """--table - wrote the CSV after the summary on stdout: with --json the
    output was no longer JSON (exit 0).  Refused before any work."""
    argv = ["verify", "--bodies", "2", "--angles", "1", "--table", "-", *json_flag]
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.strip().splitlines() == [
        "orbits: error: orbits verify: --table - would mix the table into the summary on "
        "standard output (and break --json): give --table a file"
    ]


def test_a_fifo_table_or_figure_is_refused_without_a_stdout_hint(tmp_path, capsys):
    """verify --table and a figure set have no standard-output form: their
    refusal of a FIFO said "(use '--out -' for standard output)"."""
    os.mkfifo(tmp_path / "t.csv")
    assert (
        main(["verify", "--bodies", "1", "--angles", "1", "--table", str(tmp_path / "t.csv")]) == 2
    )
    (tmp_path / "f").mkdir()
    os.mkfifo(tmp_path / "f" / "contact_sheet.png")
    argv = ["figures", "--preset", "fig6", "--n-max", "3", "--formats", "png"]
    assert main([*argv, "--out", str(tmp_path / "f")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2, err
    for line in err:
        assert "it is a FIFO (named pipe)" in line and "--out -" not in line, line


def test_cli_help_quotes_the_allowances_checks_applies(capsys):
    """The help quotes the allowances before importing orbits.checks: one
    definition (orbits.limits) serves both."""
    from orbits import limits

    assert (checks.PHASE_ULPS, checks.ROUTE_ULPS) == (limits.PHASE_ULPS, limits.ROUTE_ULPS)
    assert main(["verify", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert f"within {limits.PHASE_ULPS} spacings of doubles" in text
    assert f"agrees with it to {limits.ROUTE_ULPS} ulps" in text


# ---------------------------------------- verify checks the public routes


def _scaled_total(module, name, where, factor=1.0 + 1e-6):
    """A copy of kernel ``module.name`` whose total phases are ``factor`` too large."""
    kernel = getattr(module, name)

    def mutated(*args):
        result = kernel(*args)
        where(args)[...] *= factor
        return result

    return mutated


def _route_mutations():
    from orbits.core import phase, phase_table

    total = phase_table.COLUMNS.index("total_phase")
    return {
        # orbits.total_phase, many bodies / one body (SIMD kernels)
        "total_phase_many": (phase, "total_phase_many", lambda a: a[7]),
        "total_phase_one_body": (phase, "total_phase_one_body", lambda a: a[7]),
        # orbits.phases: the table of 'orbits phase --theta'
        "phases_columns": (phase_table, "phases_columns", lambda a: a[7][total]),
        # orbits.spin_phases
        "parts_from_vector_array": (phase, "parts_from_vector_array", lambda a: a[7][:, 6]),
    }


@pytest.mark.parametrize(
    "route",
    ["total_phase_many", "total_phase_one_body", "phases_columns", "parts_from_vector_array"],
)
def test_verify_fails_when_a_public_route_is_wrong(route, monkeypatch, capsys):
    """A route users get, wrong by 1e-6 relative, must fail verify (exit 1).

    verify used to check only its own copy of the closed form: with
    parts_from_spin 1e-6 off, 'orbits phase --theta' printed 21.5303163 for
    21.5302948 and 'orbits verify' still said ok, exit 0.
    """
    module, name, where = _route_mutations()[route]
    before = {
        "one": orbits.total_phase(T_HANDLE, [0.3, 1.3]),
        "many": orbits.total_phase(np.array([FIG6.moments, T_HANDLE.moments]), [0.3, 1.3]),
        "phases": orbits.phases(T_HANDLE, [0.3, 1.3])["total_phase"].to_numpy(),
        "spin": orbits.spin_phases(T_HANDLE, [0.6, 0.0, 0.8])["total_phase"].to_numpy(),
    }
    monkeypatch.setattr(module, name, _scaled_total(module, name, where))
    after = {
        "one": orbits.total_phase(T_HANDLE, [0.3, 1.3]),
        "many": orbits.total_phase(np.array([FIG6.moments, T_HANDLE.moments]), [0.3, 1.3]),
        "phases": orbits.phases(T_HANDLE, [0.3, 1.3])["total_phase"].to_numpy(),
        "spin": orbits.spin_phases(T_HANDLE, [0.6, 0.0, 0.8])["total_phase"].to_numpy(),
    }
    changed = [key for key in before if not np.array_equal(before[key], after[key])]
    assert len(changed) == 1  # the mutation is visible on exactly one public route
    key = changed[0]
    assert after[key] / before[key] - 1 == pytest.approx(1e-6, rel=1e-6)
    # both forms of the command fail, naming the routes check
    for argv in (
        ["verify", "--bodies", "3", "--angles", "2", "--no-progress"],
        ["verify", "--preset", "t-handle", "--angles", "2", "--no-progress"],
    ):
        assert main(argv) == 1
        out = capsys.readouterr().out
        line = next(row for row in out.splitlines() if row.startswith("public routes"))
        assert line.endswith("FAIL")
        for label in ("(b) Montgomery", "(a) ODE rotation", "(c) exact motion"):
            assert next(row for row in out.splitlines() if row.startswith(label)).endswith("ok")
    report = checks.verify_body(T_HANDLE, 2)
    routes = report.summary["checks"]["closed_form_routes"]
    assert not report.passed and not routes["passed"]
    assert routes["max_ulps"] > 1e8  # 1e-6 relative is ~4e9 ulps
    assert routes["beyond_tolerance"] == 2


def test_verify_fails_when_the_orbit_of_theta_is_wrong(tmp_path):
    """The orbit of theta (angle_triplet: total_phase, phases, 'orbits phase')
    1e-9 relative off in its offset from theta_c passed 'orbits verify': the
    routes were compared with that same path only.  In a copy of the package
    with the one-line mutation (compiled afresh, ~20 s)."""
    import re
    import shutil
    import subprocess
    import sys
    from pathlib import Path

    copy = tmp_path / "orbits"
    shutil.copytree(
        Path(orbits.__file__).parent, copy, ignore=shutil.ignore_patterns("__pycache__")
    )
    source = copy / "core" / "phase.py"
    text, count = re.subn(
        r"dtheta = (theta - theta_c|co_theta_c - co_theta)\n",
        r"dtheta = (\1) * (1.0 + 1e-9)\n",
        source.read_text(),
    )
    assert count == 2
    source.write_text(text)
    env = {**os.environ, "PYTHONPATH": str(tmp_path), "NUMBA_CACHE_DIR": str(tmp_path / "nb")}
    argv = [sys.executable, "-m", "orbits", "verify", "--bodies", "3", "--angles", "2"]
    done = subprocess.run(
        argv + ["--no-progress", "--json"],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,  # not the repository's own orbits
        timeout=600,
    )
    assert done.returncode == 1, done.stderr[-2000:]
    report = json.loads(done.stdout)
    failed = {name for name, check in report["checks"].items() if not check["passed"]}
    assert failed == {"theta_orbit"}
    assert report["checks"]["theta_orbit"]["beyond_tolerance"] == 6


def test_the_orbit_of_theta_agrees_with_that_of_omega0():
    """Unmutated: within the rounding of omega0 (0.22 of the allowance at
    most, measured over verify(29300, 22))."""
    for report in (checks.verify(50, 7), checks.verify_body(T_HANDLE, 11)):
        check = report.summary["checks"]["theta_orbit"]
        assert check["passed"] and check["max_fraction_of_allowance"] <= 0.5


def test_the_routes_agree_to_a_few_ulps():
    """Unmutated, the public routes match the scalar closed form to <= 16 ulps
    (ROUTE_ULPS = 64 leaves a margin of 4), on both verify paths."""
    for report in (checks.verify(50, 7), checks.verify_body(T_HANDLE, 11)):
        routes = report.summary["checks"]["closed_form_routes"]
        assert routes["passed"] and routes["max_ulps"] <= 16
        assert all(value <= 16 for value in routes["routes"].values())
        table = report.table
        for name, _ in checks.ROUTES:
            assert np.isfinite(table[f"route_{name}"]).all()


# --------------------------------------------- Montgomery near the separatrix


def _mp_orbit(unit, theta_of, dps):
    """T, Delta alpha and Omega (mpmath) for the spin at polar angle
    ``theta_of(theta_c)`` (phi = 0) of the body ``unit`` (exact doubles)."""
    with mp.workdps(dps):
        i1, i2, i3 = (mp.mpf(float(v)) for v in unit)
        theta_c = mp.atan(mp.sqrt(i3 * (i3 - i2) / (i1 * (i2 - i1))))
        theta = theta_of(theta_c)
        w1, w3 = mp.sin(theta), mp.cos(theta)
        two_e = i1 * w1**2 + i3 * w3**2
        m_sq = i1**2 * w1**2 + i3**2 * w3**2
        period, total = period_and_total_phase(i1, i2, i3, two_e, m_sq)
        return period, total, two_e * period / mp.sqrt(m_sq) - total


@pytest.mark.parametrize("body", [FIG6, T_HANDLE], ids=["fig6", "t-handle"])
@pytest.mark.parametrize("dtheta", [1e-10, -1e-10, 1e-50, -1e-50, 1e-300, -1e-300])
def test_montgomery_resolves_the_offset_from_the_separatrix(body, dtheta):
    """montgomery(dtheta=d) gave the same 154.752 for d = +-1e-50 and -1e-300
    (the rounded omega0 lost the offset; 1e-8 relative off already at 1e-10).
    Against mpmath at 360 digits (the gap ~1e-300 needs 300 of them)."""
    period, total, solid = _mp_orbit(body.unit_moments, lambda tc: tc + mp.mpf(dtheta), 360)
    check = checks.montgomery(body, dtheta=dtheta)
    assert check.total_phase == pytest.approx(float(total), rel=1e-14)
    assert check.period == pytest.approx(float(period), rel=1e-14)
    assert check.solid_angle == pytest.approx(float(solid), rel=1e-14)
    # and it is the orbit total_phase evaluates
    assert check.total_phase == pytest.approx(
        float(orbits.total_phase(body, dtheta=dtheta)), rel=1e-14
    )


@pytest.mark.parametrize("eps", [1e-6, 1e-9, 1e-12, 1e-15])
@pytest.mark.parametrize("theta", [0.3, 0.7, 1.2])
def test_montgomery_at_the_thin_rod_corner(eps, theta):
    """Rods (eps, 1, 1 + eps): 5e-8 relative off at eps = 1e-9 and 0.04 at
    1e-15 (cos u near pi/2 lost the small scale); now a few 1e-16."""
    body = Body((eps, 1.0, 1.0 + eps))
    period, total, _ = _mp_orbit(body.unit_moments, lambda tc: mp.mpf(theta), 60)
    check = checks.montgomery(body, theta)
    assert check.total_phase == pytest.approx(float(total), rel=1e-14)
    assert check.period == pytest.approx(float(period), rel=1e-14)


@pytest.mark.parametrize("theta", [math.pi / 12, math.pi / 4, 5 * math.pi / 12])
def test_montgomery_near_the_sphere_keeps_the_last_bits(theta):
    """(1, 1 + 1e-7, 1 + 2e-7) at verify's three angles: Delta alpha up to 3.6e8
    rad, where doubles are 6e-8 apart; the quadrature was 160 ulps off (9.6e-6
    rad), now <= 4.  As verify runs it: the orbit through the double omega0
    (theta = pi/4 is 5e-8 from theta_c, where the orbit of the exact theta and
    that of the rounded omega0 differ by 1e-2 rad)."""
    from orbits.core import checks as kernel
    from orbits.core import phase

    body = Body((1.0, 1.0000001, 1.0000002))
    unit = [float(v) for v in body.unit_moments]
    omega = [float(v) for v in orbits.Motion.from_spin(body, theta).omega0]
    with mp.workdps(60):
        i1, i2, i3 = (mp.mpf(v) for v in unit)
        w1, w2, w3 = (mp.mpf(v) for v in omega)
        two_e = i1 * w1**2 + i2 * w2**2 + i3 * w3**2
        m_sq = i1**2 * w1**2 + i2**2 * w2**2 + i3**2 * w3**2
        total = float(period_and_total_phase(i1, i2, i3, two_e, m_sq)[1])
    gap = phase.vector_gap(*unit, *omega)
    value = kernel.montgomery_phase(*unit, *omega, *gap, 1e-14)[0]
    assert abs(value - total) <= 4 * np.spacing(total)
    if abs(theta - body.critical_angle()) > 0.1:  # well conditioned in theta
        _, exact, _ = _mp_orbit(body.unit_moments, lambda tc: mp.mpf(theta), 60)
        check = checks.montgomery(body, theta)
        assert abs(check.total_phase - float(exact)) <= 4 * np.spacing(float(exact))


def test_cli_verify_thin_rod_montgomery_passes(capsys):
    """'verify --moments 1e-9 1 1.000000001 --angles 6' said Montgomery 3.8e-7 FAIL
    for a closed form right to 6e-16."""
    main(["verify", "--moments", "1e-9", "1", "1.000000001", "--angles", "6", "--json"])
    out = _strict_json(capsys.readouterr().out)
    for name in ("montgomery", "ode_rotation", "closed_form_routes"):
        assert out["checks"][name]["passed"]
    assert out["checks"]["montgomery"]["max_abs_error"] <= 1e-14


# ------------------------------------ the ulp allowance, the body, the table


def test_summary_allows_ulps_but_not_more():
    """Near the sphere (Delta alpha 3.6e8, doubles 6e-8 apart) 2 ulps pass any
    tolerance; 160 ulps (the earlier quadrature) fail; the routes must be
    within ROUTE_ULPS whatever the tolerance."""
    import pandas as pd

    phase = 364174065.72149247
    ulp = float(np.spacing(phase))
    table = pd.DataFrame(
        {
            "closed_form": [phase, phase],
            "closed_form_theta": [phase, phase],
            "period": [1e8, 1e8],
            "montgomery_error": [2 * ulp, 160 * ulp],
            "motion_error": [ulp, 16 * ulp],
            "ode_error": [np.nan, np.nan],
            "ode_period_error": [np.nan, np.nan],
            "routes_error": [0.0, 65 * ulp],
            "theta_orbit_error": [ulp, 65 * ulp],
            **{f"route_{name}": [phase, phase + 65 * ulp] for name, _ in checks.ROUTES},
        }
    )
    exhausted = np.array([True, True])
    summary = checks._summarize(table.iloc[:1], 1e-9, exhausted[:1])
    assert summary["passed"]
    assert summary["largest_allowance"] == 16 * ulp
    summary = checks._summarize(table, 1e-9, exhausted)
    assert not summary["passed"]
    assert not summary["checks"]["montgomery"]["passed"]
    assert summary["checks"]["montgomery"]["max_ulps"] == 160
    assert summary["checks"]["exact_motion"]["passed"]  # 16 ulps: the allowance
    assert not summary["checks"]["closed_form_routes"]["passed"]
    assert not summary["checks"]["theta_orbit"]["passed"]  # 65 ulps, past 64
    # a loose tolerance relaxes the checks but not the routes or theta's orbit
    loose = checks._summarize(table, 1e-3, exhausted)
    assert loose["checks"]["montgomery"]["passed"]
    assert not loose["checks"]["theta_orbit"]["passed"]
    assert not loose["checks"]["closed_form_routes"]["passed"]


def test_verify_checks_the_body_named_not_a_rounded_one():
    """(1e-300, 1, 1 + 2^-52) is the flat rod with theta_c = pi/4; normalised
    by |I| with rounding it became a body with theta_c = 0.8716.  The table
    lists the moments as given and marks the grid angle pi/4 as on the
    separatrix (it showed LAM with empty values)."""
    body = Body((1e-300, 1.0, 1.0000000000000002))
    report = checks.verify_body(body, 3)
    table = report.table
    assert (table[["I1", "I2", "I3"]].to_numpy() == body.moments).all()
    assert table["theta"][1] == math.pi / 4
    assert list(table["branch"]) == ["SAM", "separatrix", "LAM"]
    assert table.loc[1, ["closed_form", "montgomery", "motion"]].isna().all()
    assert not report.passed and report.summary["on_separatrix"] == 1
    # the other rows are checked on the body named
    assert table["montgomery_error"][0] <= 1e-14 and table["motion_error"][2] <= 1e-14


def test_separatrix_rows_are_labelled_in_the_cli_table(tmp_path, capsys):
    import pandas as pd

    path = tmp_path / "sep.csv"
    argv = ["verify", "--moments", "1", "2", "2.414213562373095", "--angles", "1"]
    assert main(argv + ["--table", str(path), "--no-progress"]) == 1
    out = capsys.readouterr().out
    assert out.count("on the separatrix") == 1
    table = pd.read_csv(path, **csv_float_options())
    assert list(table["branch"]) == ["separatrix"]


# ------------------------- check (a) is allowed its integrator's own error

NEAR_SPHERE = Body((1.0, 1.0001, 1.0002))


def test_cli_verify_passes_where_only_the_integrators_error_exceeds_the_tolerance(capsys):
    """'orbits verify --moments 1 1.0001 1.0002': phases of 4e4 to 9e4 rad
    (7,000 to 15,000 turns).  DOP853 at rtol 1e-12 is 1.3e-8 rad (985 ulps)
    off there, ~1e-13 relative, and that error falls tenfold per decade of
    rtol: the integrator's, not the closed form's ((b) and (c) agree to 5
    ulps).  It printed 'ODE rotation 1.283e-08 985 FAIL', exit 1."""
    code = main(["verify", "--moments", "1", "1.0001", "1.0002", "--json", "--no-progress"])
    out = _strict_json(capsys.readouterr().out)
    assert code == 0 and out["passed"]
    assert out["ode_rtol"] == checks.VERIFY_ODE_RTOL == 1e-12
    assert out["ode_error_factor"] == checks.ODE_ERROR_FACTOR == 6.0
    ode = out["checks"]["ode_rotation"]
    assert ode["passed"] and ode["beyond_tolerance"] == 0
    # measured 1.283e-8 rad, 985 ulps: beyond the tolerance at all 22 angles
    assert 1.0e-8 <= ode["max_abs_error"] <= 1.6e-8 and ode["max_ulps"] > 500
    assert ode["within_integrator_error_only"] == 22
    # allowed 6 x 1e-12 x |w0| T, T up to 94491 (the longest period): 5.67e-7 rad
    assert ode["largest_allowance"] == pytest.approx(6e-12 * 94490.9994537, rel=1e-6)
    # the error uses 2.3% of that (0.136 rtol |w0| T, the factor is 6)
    assert ode["max_fraction_of_allowance"] <= 0.05
    # the other checks keep the tolerance, and meet it by far
    for name in ("montgomery", "exact_motion"):
        check = out["checks"][name]
        assert check["largest_allowance"] == 1e-9 and check["max_abs_error"] <= 1e-10
        assert check["max_ulps"] <= 8
    assert out["checks"]["closed_form_routes"]["max_ulps"] <= 16
    # the text says why the row passed
    assert main(["verify", "--moments", "1", "1.0001", "1.0002", "--no-progress"]) == 0
    text = capsys.readouterr().out
    line = next(row for row in text.splitlines() if row.startswith("(a) ODE rotation"))
    assert line.split()[-2:] == ["985", "ok"]
    assert (
        "note: (a) ODE rotation: 22 discrepancy(ies) beyond the tolerance are within the "
        "integrator's own error, 6 x rtol (1e-12) x |w0| T" in text
    )
    assert "here up to 5.67e-07 rad; the largest discrepancy is 0.023 of its allowance" in text


@pytest.mark.parametrize("body", [FIG6, NEAR_SPHERE], ids=["fig6", "1, 1.0001, 1.0002"])
def test_check_a_still_catches_a_closed_form_wrong_by_1e9(body, monkeypatch):
    """The closed form 1e-9 (relative) too large: check (a) fails at every
    angle.  Its integrator allowance is at most 1/100 of such an error on
    both bodies (measured 1/130 on Fig. 6, 1/167 near the sphere); on
    Fig. 6 (Delta alpha 6.6 to 21.6 rad) the allowance is the tolerance,
    1e-9, 6.6 to 21.6 times smaller than the error."""
    clean = checks.verify_body(body, 22)
    assert clean.passed
    table = clean.table
    shift = 1e-9 * table["closed_form"].abs()
    budget = checks.ode_error_budget(table["ode_period"])
    assert (budget <= 0.01 * shift).all()
    assert (table["ode_allowance"] == np.maximum(1e-9, budget)).all()
    if body is FIG6:
        assert (table["ode_allowance"] == 1e-9).all()
        assert (table["ode_allowance"] <= shift / 6.5).all()
        assert (table["ode_allowance"] <= shift / 10)[table["closed_form"].abs() >= 10].all()
    wrong_closed_form(monkeypatch, 1.0 + 1e-9)
    wrong = checks.verify_body(body, 22)
    ode = wrong.summary["checks"]["ode_rotation"]
    assert not wrong.passed and not ode["passed"]
    assert ode["beyond_tolerance"] == 22 and ode["within_integrator_error_only"] == 0
    assert ode["max_fraction_of_allowance"] >= (100.0 if body is NEAR_SPHERE else 6.5)
    # the ODE's own error is unchanged; only the closed form moved
    assert (wrong.table["ode_angle"] == table["ode_angle"]).all()


def test_summary_allows_check_a_its_integrators_error_and_no_more():
    """_summarize on a hand-made row near the sphere: check (a) passes within
    6 x rtol x |w0| T of the period it found, fails beyond; (b), (c) are
    still held to the tolerance (16 ulps of 9.4e4 rad is 2.3e-10)."""
    import pandas as pd

    phase, period = 94432.080879, 94434.814154
    budget = 6e-12 * period  # 5.67e-7 rad
    table = pd.DataFrame(
        {
            "closed_form": [phase, phase],
            "closed_form_theta": [phase, phase],
            "period": [period, period],
            "ode_period": [period, period],
            "montgomery_error": [1e-10, 1e-10],
            "motion_error": [1e-10, 2e-9],
            "ode_error": [0.9 * budget, 1.1 * budget],
            "ode_period_error": [1e-9, 1e-9],
            "routes_error": [0.0, 0.0],
            "theta_orbit_error": [0.0, 0.0],
            **{f"route_{name}": [phase, phase] for name, _ in checks.ROUTES},
        }
    )
    no = np.array([False])
    ok = checks._summarize(table.iloc[:1], 1e-9, no)
    assert ok["passed"]
    ode = ok["checks"]["ode_rotation"]
    assert ode["largest_allowance"] == pytest.approx(budget, rel=1e-15)
    assert ode["max_fraction_of_allowance"] == pytest.approx(0.9, rel=1e-12)
    assert ode["within_integrator_error_only"] == 1
    both = checks._summarize(table, 1e-9, np.array([False, False]))
    assert not both["passed"]
    assert both["checks"]["ode_rotation"]["beyond_tolerance"] == 1
    assert both["checks"]["exact_motion"]["beyond_tolerance"] == 1  # 2e-9 > 1e-9
    assert both["checks"]["exact_motion"]["largest_allowance"] == 1e-9
    # without the period the integration found there is no integrator allowance
    bare = checks._summarize(table.iloc[:1].drop(columns="ode_period"), 1e-9, no)
    assert not bare["checks"]["ode_rotation"]["passed"]


@pytest.mark.parametrize(
    "moments",
    [(1.0, 2.0, 3.0), (1e-9, 1.0, 1.000000001), (1.0, 1.9999, 2.0), (1.0, 1.001, 1.002)],
)
def test_step_prediction_is_a_lower_bound_with_a_margin(moments):
    """ode_steps_at_least (which lets verify skip a period longer than its
    10^7 steps) is at least 9 times below the steps DOP853 takes: counted by
    the least budget that completes the period (measured 2.6 to 250 steps
    per unit of T sqrt(2E/I3); the bound assumes 0.26)."""
    from orbits.core import checks as kernel

    unit = [float(v) for v in Body(moments).unit_moments]
    for theta in (0.02, 0.7, 1.3, 1.55):
        w = [float(v) for v in orbits.Motion.from_spin(Body(moments), theta).omega0]
        period = float(orbits.Motion.from_spin(Body(moments), theta).period)

        def completes(steps):
            return kernel.rotation_after_periods(*unit, *w, 1, 1e-12, 1e-14, steps)[0] > 0

        low, high = 1, 2
        while not completes(high):
            low, high = high, 2 * high
        while high - low > 1:
            middle = (low + high) // 2
            low, high = (low, middle) if completes(middle) else (middle, high)
        bound = kernel.ode_steps_at_least(*unit, *w, period)
        assert 0.0 < 9.0 * bound <= high, (theta, bound, high)


def test_verify_does_not_integrate_a_period_beyond_the_step_budget():
    """(1, 1 + 1e-8, 1 + 2e-8): the kernel marks the rows STEP_BUDGET_PREDICTED
    without integrating (each took 4 to 7 s of steps to run out); a body whose
    period fits is still integrated, and a NaN period predicts nothing."""
    from orbits.core import checks as kernel

    report = checks.verify_body(Body((1.0, 1.00000001, 1.00000002)), 3)
    ode = report.summary["checks"]["ode_rotation"]
    assert report.passed and ode["not_applicable"] == 3
    assert report.table["ode_period"].isna().all()
    unit = np.array([[1.0, 1.00000001, 1.00000002]])
    out = np.full((1, len(kernel.CHECK_COLUMNS)), np.nan)
    kernel.check_batch(unit, np.array([0.7]), np.array([0.0]), 1e-12, 1e-14, 1e-14, out)
    assert out[0, kernel.CHECK_COLUMNS.index("ode_period")] == kernel.STEP_BUDGET_PREDICTED
    assert kernel.ode_steps_at_least(1.0, 1.5, 2.0, 0.6, 0.0, 0.8, float("nan")) == 0.0
    near = checks.verify_body(NEAR_SPHERE, 2)
    assert near.summary["checks"]["ode_rotation"]["not_applicable"] == 0


def test_cli_help_quotes_check_a_error_budget(capsys):
    """The help states check (a)'s criterion with the constants verify applies
    (one definition in orbits.limits, which the help reads without SciPy)."""
    from orbits import limits
    from orbits.cli import verify as command

    assert command.ODE_ERROR_FACTOR is checks.ODE_ERROR_FACTOR is limits.ODE_ERROR_FACTOR
    assert command.GAP_ROUNDING_FACTOR is checks.GAP_ROUNDING_FACTOR is limits.GAP_ROUNDING_FACTOR
    assert command.VERIFY_ODE_RTOL is checks.VERIFY_ODE_RTOL is limits.VERIFY_ODE_RTOL
    assert main(["verify", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert f"(DOP853, rtol {checks.VERIFY_ODE_RTOL:g})" in text
    assert f"for (a) also {checks.ODE_ERROR_FACTOR:g} x rtol x |w0| T" in text
    assert (
        f"separatrix {checks.GAP_ROUNDING_FACTOR:g} x eps / g x |d Delta alpha / d ln g|" in text
    )


# ----------------- check (a) next to the separatrix: the rounding of the state

# bodies 13692 and 27145 of region_sample(29300), angles 15 and 16 of 22:
# rows 301239 and 597206 of 'orbits verify --bodies 29300', which failed
# check (a) with 3.0e-9 and 2.7e-9 rad before gap_rounding_allowance
NEXT_TO_THE_SEPARATRIX = (
    ((0.4044077164787258, 0.5161479020358949, 0.7550137363494831), 15),
    ((0.4392895888977981, 0.5071558459719937, 0.7414968678170091), 16),
)


@pytest.mark.parametrize("moments, angle", NEXT_TO_THE_SEPARATRIX)
def test_check_a_is_allowed_the_rounding_of_its_state_next_to_the_separatrix(
    monkeypatch, moments, angle
):
    """Within ~3e-7 (relative gap) of the separatrix a double state holds the
    orbit only to eps / g in ln g, and DOP853's result moves with it
    (not with rtol): check (a) is allowed GAP_ROUNDING_FACTOR times what
    that moves the phase.  Without that term the row fails; checks (b) and
    (c) still hold the closed form there to 1e-11."""
    report = checks.verify_body(Body(moments), 22)
    row = report.table.iloc[angle]
    assert report.passed
    assert 2e-9 < row["ode_error"] < 4e-9  # beyond the tolerance, 1e-9
    assert row["relative_gap"] < 2e-6
    term = checks.gap_rounding_allowance(row["relative_gap"], row["gap_slope"])
    assert row["ode_allowance"] == term and row["ode_error"] < 0.2 * term
    assert row["montgomery_error"] < 1e-11 and row["motion_error"] < 1e-11
    ode = report.summary["checks"]["ode_rotation"]
    assert ode["within_integrator_error_only"] == 1
    assert report.summary["gap_rounding_factor"] == checks.GAP_ROUNDING_FACTOR == 20.0
    monkeypatch.setattr(checks, "GAP_ROUNDING_FACTOR", 0.0)
    again = checks.verify_body(Body(moments), 22)
    assert not again.passed
    assert again.summary["checks"]["ode_rotation"]["beyond_tolerance"] == 1


def test_gap_rounding_allowance_is_negligible_away_from_the_separatrix():
    """Far from the separatrix, and near the sphere (where the gap's two
    terms are small too), the term stays near or below the tolerance: the
    check keeps its teeth (a closed form 1e-9 relative wrong still fails
    everywhere, test_check_a_still_catches_a_closed_form_wrong_by_1e9)."""
    for body in (FIG6, Body((1.0, 2.0, 2.9))):
        table = checks.verify_body(body, 22).table
        far = table["relative_gap"] > 1e-3
        term = checks.gap_rounding_allowance(table["relative_gap"], table["gap_slope"])
        assert far.sum() >= 18 and (term[far] < 3e-10).all()
    # near the sphere the phases reach 1e5 rad, but g stays >= 0.07: at most
    # 1.1e-9 rad, a five-hundredth of the integrator's own allowance there
    table = checks.verify_body(NEAR_SPHERE, 22).table
    term = checks.gap_rounding_allowance(table["relative_gap"], table["gap_slope"])
    assert table["relative_gap"].min() > 0.05 and term.max() < 1.2e-9
    assert (term < 0.01 * checks.ode_error_budget(table["ode_period"])).all()
    assert np.isnan(checks.gap_rounding_allowance(0.0, 5.0))


@pytest.mark.parametrize("moments, angle", NEXT_TO_THE_SEPARATRIX + (((1.0, 1.7, 2.3), 5),))
def test_relative_gap_and_gap_slope_against_mpmath(moments, angle):
    """The kernel's relative gap and |d Delta alpha / d ln g| against eqn:GeometricPhase
    in mpmath at 40 digits, from the same double spin: the gap exactly, and
    the slope by a central difference in M^2 at fixed 2E (h = 1e-12)."""
    from orbits.core import checks as kernel

    unit = np.array([[float(v) for v in Body(moments).unit_moments]])
    theta = np.array([(angle + 0.5) * np.pi / 44])
    out = np.full((1, len(kernel.CHECK_COLUMNS)), np.nan)
    kernel.check_batch(unit, theta, np.zeros(1), 1e-12, 1e-14, 1e-14, out)
    column = {name: out[0, k] for k, name in enumerate(kernel.CHECK_COLUMNS)}
    with mp.workdps(40):
        i1, i2, i3 = (mp.mpf(float(v)) for v in unit[0])
        w1, w2, w3 = (mp.mpf(column[name]) for name in ("w1", "w2", "w3"))
        two_e = i1 * w1**2 + i2 * w2**2 + i3 * w3**2
        m_sq = (i1 * w1) ** 2 + (i2 * w2) ** 2 + (i3 * w3) ** 2
        gap = m_sq - two_e * i2
        terms = i3 * (i3 - i2) * w3**2 + i1 * (i2 - i1) * w1**2
        assert float(abs(gap) / terms) == pytest.approx(column["relative_gap"], rel=1e-14)
        sam = gap > 0
        h = mp.mpf("1e-12")
        up = period_and_total_phase(i1, i2, i3, two_e, m_sq + h * abs(gap), sam)[1]
        down = period_and_total_phase(i1, i2, i3, two_e, m_sq - h * abs(gap), sam)[1]
        slope = float(abs(up - down) / (2 * h))
    # next to the separatrix the log term dominates and both ways agree
    # closely; far from it (g ~ 1) the kernel's slope (the gap alone moved)
    # and this one (M^2 moved) differ by O(1), which is not used there
    rel = 1e-4 if column["relative_gap"] < 1e-5 else 1.0
    assert column["gap_slope"] == pytest.approx(slope, rel=rel)


@pytest.mark.parametrize("rod", [1e-6, 1e-9])
def test_closure_errors_on_thin_rods_within_their_own_budget(rod):
    """Near the separatrix of a thin rod the quarter path's error is about
    rtol * I3/I1 a period (phi turns at up to M/I1 at w2 = 0); forced short
    steps all along the quarter drifted it further (6.4e-7 rad at a 1e-6
    rod, 3-7 s a row) and did not finish at dtheta = 1e-300 (reported as
    'outside [0, pi/2]').  Reference: the closed form, |Delta alpha| reduced
    to [0, pi] (orbits.total_phase, 1e-15 against mpmath)."""
    moments = np.array([rod, 1.0, 1.0 + rod])
    dtheta = np.array([-0.000999, -1e-5, 1e-5, 1e-9, -1e-12, 1e-300])
    periods = np.array([1, 1, 2, 1, 3, 1])
    got = orbits.closure_errors(moments, dtheta, periods)
    phase = np.asarray(orbits.total_phase(moments, dtheta=dtheta)) * periods
    expected = np.abs(phase - 2 * np.pi * np.floor(phase / (2 * np.pi) + 0.5))
    budget = orbits.checks.closure_error_budget(moments, dtheta, periods)
    # I3/I1 of the canonical moments (1 + rod rounds, and the flat edge moves it)
    np.testing.assert_allclose(budget, 10.0 * 1e-13 * (1.0 + rod) / rod * periods, rtol=1e-6)
    assert np.all(np.abs(got - expected) <= budget / 4), np.abs(got - expected) / budget


def test_catalog_verify_of_a_thin_rod_passes_with_a_note(tmp_path, capsys):
    from orbits.cli import main

    argv = ["catalog", "--moments", "1e-6", "1", "1.000001", "--n-max", "3", "--verify"]
    assert main([*argv, "--out", str(tmp_path / "rod.csv")]) == 0
    err = capsys.readouterr().err
    assert "within the check's own error" in err and "error:" not in err


# ------------------------------------------------ arguments of the helpers


def test_a_count_beyond_a_double_is_one_error(capsys):
    """--angles 1e400 (an int) was an OverflowError traceback in format_bytes."""
    huge = 10**400
    with pytest.raises(orbits.InputError, match="~1e400 angles = ~1e400 initial conditions"):
        checks.verify_body((1, 2, 3), huge)
    assert main(["verify", "--moments", "1", "2", "3", "--angles", str(huge)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "more bytes than a double can count" in err[0]


@pytest.mark.parametrize(
    "moments, omega0, times, dps, error",
    [
        ((1, 2, 3), [np.nan, 0, 1], [0.1], 40, orbits.AngleError),
        ((1, 2, 3), [0, 0, 0], [0.1], 40, orbits.AngleError),
        ((-1, 2, 3), [1, 0, 1], [0.1], 40, orbits.NonPhysicalBodyError),
        ((1, 1, 2), [1, 0, 1], [0.1], 40, orbits.SymmetricTopError),
        ((1, 2, 30), [1, 0, 1], [0.1], 40, orbits.NonPhysicalBodyError),
        ((1, 2, 3), [0, 1, 0], [0.1], 40, orbits.SeparatrixError),
        ((1, 2, 3), [1, 0], [0.1], 40, orbits.AngleError),
        ((1, 2, 3), [1, 0, 1], [], 40, orbits.InputError),
        ((1, 2, 3), [1, 0, 1], [np.nan], 40, orbits.InputError),
        ((1, 2, 3), [1, 0, 1], [0.1], 0, orbits.InputError),
    ],
)
def test_the_mpmath_reference_refuses_what_motion_refuses(moments, omega0, times, dps, error):
    """exact_motion_mpmath gave NaN, plausible values for a symmetric or
    non-physical body, or ZeroDivision/Index/AttributeErrors."""
    with pytest.raises(error):
        checks.exact_motion_mpmath(moments, omega0, times, dps=dps)


def test_the_error_budgets_refuse_what_their_checks_refuse():
    """closure_error_budget(rtol=-1) was -30 rad, periods=-5 negative,
    dtheta=nan 0; ode_error_budget(rtol=-1) -600; negative slopes negative."""
    calls = [
        lambda: checks.closure_error_budget((1, 2, 3), 1e-4, 1, rtol=-1),
        lambda: checks.closure_error_budget((1, 2, 3), 1e-4, -5),
        lambda: checks.closure_error_budget((1, 2, 3), 1e-4, 2.5),
        lambda: checks.closure_error_budget((1, 2, 3), np.nan, 1),
        lambda: checks.closure_error_budget((1, 2, 3), 0.0, 1),
        lambda: checks.closure_error_budget((1, 2, 3), [1e-4, 1e-4], [1, 2, 3]),
        lambda: checks.ode_error_budget(100, rtol=-1),
        lambda: checks.ode_error_budget(-1.0),
        lambda: checks.gap_rounding_allowance(1e-3, -5),
    ]
    for call in calls:
        with pytest.raises(orbits.OrbitsError):
            call()
    for call in (lambda: checks.ode_error_budget(None), lambda: checks.circular_distance("a", 1)):
        with pytest.raises(orbits.ArgumentTypeError):
            call()
    # the values themselves, where the arguments are right
    rod = checks.closure_error_budget((1e-6, 1, 1.000001), [1e-4, 0.1], 3)
    assert rod[0] == pytest.approx(checks.QUARTER_ERROR_FACTOR * 1e-13 * 1.000001e6 * 3, rel=1e-12)
    assert rod[1] == 0.0
    assert np.isnan(checks.ode_error_budget(np.array([1.0, np.nan]))[1])
    assert np.isnan(checks.circular_distance(np.inf, 1.0))


def test_a_spin_along_an_axis_is_refused_at_once():
    """theta = 0 (along I3) used up 10**7 steps, then blamed a nearly
    symmetric body or the separatrix."""
    with pytest.raises(orbits.InputError, match="along the principal axis I3: a steady rotation"):
        checks.rotation_by_integration((1, 2, 3), 0.0)


@pytest.mark.parametrize("engine", ["compiled", "scipy"])
def test_rotation_by_integration_near_an_axis(engine):
    """A subnormal theta gave a false failure (5e-324: period 0.0123 found for
    6.589, error 0.29; 1e-310 compiled: 1.5e-8, above verify's 1e-9): refused
    now.  The smallest normal components still integrate, to verify's bound."""
    with pytest.raises(orbits.InputError, match="below the smallest normal double"):
        checks.rotation_by_integration(FIG6, 5e-324, engine=engine)
    with pytest.raises(orbits.InputError, match="below the smallest normal double"):
        checks.rotation_by_integration(FIG6, 1e-310, engine=engine)
    for theta in (1e-300, 3e-308):
        result = checks.rotation_by_integration(FIG6, theta, engine=engine)
        assert result.error <= 1e-9
        assert result.period == pytest.approx(
            orbits.Motion.from_spin(FIG6, theta).period, rel=1e-9
        )
