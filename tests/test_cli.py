"""The command line: results, and one-line errors with exit code 2."""

import io
import json
import math
import re
import shutil
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from verify_faults import wrong_closed_form

import orbits
from orbits.atomic import csv_float_options
from orbits.cli import main


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def assert_usage_error(code, err, *fragments):
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("orbits: error:")
    assert "Traceback" not in err
    for fragment in fragments:
        assert fragment in lines[0]


class TestPhase:
    def test_t_handle_csv(self, capsys):
        code, out, _ = run(
            capsys,
            "phase",
            "--preset",
            "t-handle",
            "--theta",
            "1.4207963267948966",
            "--phi",
            "1.3707963267948966",
            "--csv",
        )
        assert code == 0
        row = pd.read_csv(io.StringIO(out), comment="#", **csv_float_options()).iloc[0]
        assert row.total_phase == pytest.approx(21.5303, abs=5e-5)
        assert row.branch == "SAM"

    def test_negative_exponent_offsets(self, capsys):
        code, out, _ = run(
            capsys, "phase", "--preset", "fig6", "--dtheta", "-1e-300", "1e-300", "--csv"
        )
        assert code == 0
        table = pd.read_csv(io.StringIO(out), comment="#", **csv_float_options())
        assert table.branch.tolist() == ["SAM", "LAM"]
        assert table.dtheta.tolist() == [-1e-300, 1e-300]

    def test_table_output(self, capsys):
        code, out, _ = run(capsys, "phase", "--moments", "3", "1", "2", "--theta", "0.4")
        assert code == 0 and "total_phase" in out

    @pytest.mark.parametrize(
        "argv, fragments",
        [
            (["phase", "--moments", "1", "1", "2", "--theta", "0.3"], ["symmetric top"]),
            (["phase", "--moments", "1", "2", "4", "--theta", "0.3"], ["triangle"]),
            (["phase", "--moments", "1", "2", "nan", "--theta", "0.3"], ["not a finite number"]),
            (["phase", "--preset", "fig6", "--dtheta", "2"], ["outside [0, pi/2]", "not folded"]),
            (
                ["animate", "--preset", "fig6", "--dtheta", "5", "--out", "never.gif"],
                ["theta_c + dtheta", "outside [0, pi/2]", "not folded"],
            ),
            (["phase", "--preset", "nope", "--theta", "1"], ["invalid choice"]),
            (["phase", "--preset", "fig6"], ["--theta", "required"]),
            (
                ["phase", "--preset", "fig6", "--moments", "1", "2", "2.5", "--theta", "1"],
                ["not allowed with"],
            ),
            (["phase", "--preset", "fig6", "--dtheta", "0"], ["separatrix"]),
            (
                ["phase", "--t-handle", "8", "-4", "1", "--theta", "1"],
                ["T-handle l2 must be a finite positive number"],
            ),
            (["bench", "--only", "nope"], ["unknown benchmark"]),
            (["nonsense"], ["invalid choice"]),
            # a subnormal offset keeps a few digits of what was typed (-1e-320
            # was computed as -9.99989e-321 with exit 0)
            (
                ["phase", "--preset", "fig6", "--dtheta", "-1e-320"],
                [
                    "--dtheta -1e-320 is a subnormal double with about 3 significant",
                    "-9.99989e-321",
                ],
            ),
            (
                ["phase", "--preset", "fig6", "--dtheta", "1e-310", "--degrees"],
                ["is a subnormal double", "offsets from 4.941e-312 up keep at least 12"],
            ),
        ],
    )
    def test_bad_input(self, capsys, argv, fragments):
        code, _, err = run(capsys, *argv)
        assert_usage_error(code, err, *fragments)

    def test_the_smallest_offset_stated_is_accepted(self, capsys):
        """The help and the refusal named 4.9e-312, itself refused (the bound
        is 2**-1074 * 1e12 = 4.9407e-312); they state 4.941e-312 now."""
        code, out, _ = run(capsys, "phase", "--preset", "fig6", "--dtheta", "4.941e-312")
        assert code == 0 and "4.941e-312" in out
        code, _, err = run(capsys, "phase", "--preset", "fig6", "--dtheta", "4.94e-312")
        assert_usage_error(code, err, "offsets from 4.941e-312 up keep at least 12")

    def test_name_is_printed_not_ignored(self, capsys):
        """--name was accepted and shown nowhere (exit 0)."""
        base = ["phase", "--preset", "fig6", "--theta", "0.5", "0.7", "--name", "my top"]
        code, out, _ = run(capsys, *base)
        assert code == 0
        first = out.splitlines()[0].split()
        assert first[:2] == ["name", "[-]"] and " ".join(first[2:]) == "my top my top"
        code, out, _ = run(capsys, *base, "--csv")
        table = pd.read_csv(io.StringIO(out), comment="#", **csv_float_options())
        assert table.columns[0] == "name" and table.name.tolist() == ["my top", "my top"]
        # without --name the table is as before
        code, out, _ = run(capsys, *base[:-2])
        assert not out.startswith("name")
        code, out, _ = run(
            capsys,
            "phase",
            "--moments",
            "1",
            "2",
            "2.5",
            "--omega",
            "1",
            "0",
            "0.1",
            "--name",
            "Y",
        )
        assert code == 0 and out.splitlines()[0].split() == ["name", "[-]", "Y"]

    @pytest.mark.parametrize("omega, axis", [(("0", "0", "1"), "I3"), (("2", "0", "0"), "I1")])
    def test_steady_spin_about_an_axis(self, capsys, omega, axis):
        """omega along I3 was told that its I2 component reverses every T/2 (it is
        zero throughout), and Omega printed as -0.0."""
        code, out, _ = run(capsys, "phase", "--moments", "1", "2", "2.5", "--omega", *omega)
        assert code == 0
        lines = out.splitlines()
        assert (
            lines[-1]
            == f"steady spin about {axis}: omega stays along {axis} (no polhode, no flip)"
        )
        geometric = next(line for line in lines if line.startswith("geometric_phase"))
        assert geometric.split()[-1] == "0.0"


def test_bench_json_quick(capsys):
    # --no-load-check: the under-load check is a timing (exit 1 when this
    # shared machine slows the row down more than 2x), never a test's verdict
    code, out, _ = run(capsys, "bench", "--quick", "--json", "--only", "phase", "--no-load-check")
    assert code == 0
    report = json.loads(out)
    row = report["results"][0]
    assert row["name"] == "phase"
    assert row["ours_s"] > 0 and row["baseline_s"] > 0
    assert row["speedup"] == pytest.approx(row["baseline_s"] / row["ours_s"])


def test_console_script_has_no_traceback():
    exe = shutil.which("orbits")
    argv = [exe] if exe else [sys.executable, "-m", "orbits.cli"]
    proc = subprocess.run(
        argv + ["phase", "--moments", "1", "1", "2", "--theta", "1"],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1
    assert "Traceback" not in proc.stderr
    version = subprocess.run(argv + ["--version"], capture_output=True, text=True)
    assert version.returncode == 0 and version.stdout.startswith("orbits ")


def test_phase_folds_theta_and_phi(capsys):
    """--theta 2 is folded to pi - 2 (the same phase), not rejected."""
    import math

    import orbits

    code, out, _ = run(capsys, "phase", "--preset", "fig6", "--theta", "2", "--phi", "-3", "--csv")
    assert code == 0
    row = pd.read_csv(io.StringIO(out), comment="#", **csv_float_options()).iloc[0]
    assert row.theta == pytest.approx(math.pi - 2, abs=1e-15)
    want = orbits.phases(orbits.Body.preset("fig6"), math.pi - 2, math.pi - 3).iloc[0]
    assert row.phi == pytest.approx(math.pi - 3, abs=1e-15)
    assert row.total_phase == pytest.approx(want.total_phase, rel=1e-15)
    assert row.D == pytest.approx(want.D, rel=1e-15)


@pytest.mark.parametrize("stop", ["interrupt", "terminated"])
def test_a_stop_raised_inside_a_callback_is_not_lost(monkeypatch, capsys, stop):
    """A stop signal's exception raised in a weakref callback is raised again.

    Python drops exceptions raised in weakref callbacks (and ``__del__``,
    ctypes callbacks) after printing "Exception ignored"; an adversarial
    probe saw Ctrl-C during ``orbits figures`` land there: the run went on
    to exit 0, ignoring later signals.  Here the handler's exception is
    raised in such a callback on purpose; the run must still end as stopped,
    with one line.
    """
    import gc
    import signal
    import time
    import weakref

    import orbits.cli as cli

    def raise_stop(_reference):
        if stop == "interrupt":
            cli._raise_interrupt(signal.SIGINT, None)
        cli._raise_terminated(signal.SIGTERM, None)

    def run(args):
        class Thing:
            pass

        thing = Thing()
        holder = weakref.ref(thing, raise_stop)
        del thing  # the callback runs here; its exception is dropped by Python
        gc.collect()
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline:  # our own code: the stop comes back here
            sum(range(100))
        assert holder() is None
        return 0

    monkeypatch.setattr(cli, "check_arguments", lambda args: setattr(args, "run", run))
    start = time.monotonic()
    code = main(["phase", "--preset", "fig6", "--theta", "0.5"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == (130 if stop == "interrupt" else 128 + signal.SIGTERM)
    assert time.monotonic() - start < 2.0  # raised again within the retry interval
    assert len(err) == 1 and ("interrupted" in err[0] or "stopped by SIGTERM" in err[0]), err
    assert "Exception ignored" not in "".join(err)


# ------------------------------------------------------------------------
# Each test below kills a mutant of the output paths of orbits/cli (phase,
# catalog, survey, verify, shared) that passed the suite (a mutation audit,
# 2026-11-29: 56 mutants, 35 survivors that printed a wrong number, label
# or verdict, or the wrong exit code).  Every expected value is derived by
# hand (E = 1/2 w.I.w, |L| = |I w|, D = M^2/(2E), I = h/(8 pi^2 c B), ...)
# or read back from the written file, not from the printer.


def table_rows(out):
    """The text table of `orbits phase`: {name: (unit label, [cells])}."""
    rows = {}
    for line in out.splitlines():
        m = re.match(r"^(\S+)\s+\[([^\]]*)\]\s+(.*)$", line)
        if m:
            rows[m.group(1)] = (m.group(2), m.group(3).split())
    return rows


# ------------------------------------------------------------------ phase --omega
H, C_CM = 6.62607015e-34, 2.99792458e10  # J s, cm/s (exact SI)


def test_rotational_constants_print_si_units_and_si_values(capsys):
    """P02 (REAL_BODIES without rotational_constants: labels I, I rad^2/s^2)
    and P05 (D_normalised labelled with the moments' unit)."""
    code, out, err = run(
        capsys, "phase", "--rotational-constants", 10, 5, 4, "--omega", 1e12, 2e12, 1e11
    )
    assert code == 0 and err == ""
    rows = table_rows(out)
    moments = [H / (8 * math.pi**2 * C_CM * b) for b in (10.0, 5.0, 4.0)]  # kg m^2
    w = np.array([1e12, 2e12, 1e11])
    energy = 0.5 * float(np.dot(w * moments, w))  # J
    momentum = float(np.linalg.norm(np.multiply(moments, w)))  # J s
    for name, value in zip(("I1", "I2", "I3"), moments):
        assert rows[name][0] == "kg m^2"
        assert float(rows[name][1][0]) == pytest.approx(value, rel=1e-9)
    assert rows["energy"][0] == "J" and float(rows["energy"][1][0]) == pytest.approx(
        energy, rel=1e-12
    )
    assert rows["momentum"][0] == "J s"
    assert float(rows["momentum"][1][0]) == pytest.approx(momentum, rel=1e-12)
    assert rows["D"][0] == "kg m^2"
    assert float(rows["D"][1][0]) == pytest.approx(momentum**2 / (2 * energy), rel=1e-12)
    assert rows["D_normalised"][0] == "|I|=1"
    assert float(rows["D_normalised"][1][0]) == pytest.approx(
        momentum**2 / (2 * energy) / np.linalg.norm(moments), rel=1e-12
    )


def test_steady_spin_periods_are_in_their_own_columns(capsys):
    """P07 (precession and rotation periods swapped): about I1 of (1, 2, 3)
    the rotation period is the small-oscillation period 2 pi / sqrt((I2 - I1)
    (I3 - I1) / (I2 I3)) = 2 pi sqrt(3), and period_ratio = P_psi / P_phi."""
    code, out, _ = run(capsys, "phase", "--moments", 1, 2, 3, "--omega", 1, 0, 0, "--csv")
    assert code == 0
    row = pd.read_csv(io.StringIO(out), comment="#").iloc[0]
    assert row["rotation_period"] == pytest.approx(2 * math.pi * math.sqrt(3), rel=1e-12)
    assert row["period"] == pytest.approx(2 * math.pi * math.sqrt(3), rel=1e-12)
    assert row["rotation_period"] / row["precession_period"] == pytest.approx(
        row["period_ratio"], rel=1e-12
    )
    assert row["precession_period"] > row["rotation_period"]
    # energy and |L| by hand
    assert row["energy"] == 0.5 and row["momentum"] == 1.0


def test_spin_about_the_intermediate_axis_is_called_a_flip(capsys):
    """P12 (components[1] <= max: the flip note never printed)."""
    code, out, _ = run(capsys, "phase", "--moments", 1, 2, 3, "--omega", 0.1, 1, 0.1)
    assert code == 0
    period = float(table_rows(out)["period"][1][0])
    last = out.strip().splitlines()[-1]
    assert last.startswith("spin about the intermediate axis I2: the body flips")
    assert last.endswith(f"every T/2 = {period / 2:.6g} s")


def test_periods_note_repeats_both_periods_in_their_unit(capsys):
    """P15 (the note gave P_psi for P_phi)."""
    code, out, _ = run(capsys, "phase", "--box", 1, 2, 3, "--periods", 30, 10, "--time-unit", "h")
    assert code == 0
    assert "2 spins with P_psi = 30 h and P_phi = 10 h (Pravec" in out
    assert len([line for line in out.splitlines() if line.startswith("branch ")]) == 1


def test_periods_csv_units_and_values_in_hours(capsys):
    """P14/P16/P22 (units of --periods' table): periods in h, w in rad/h,
    E in kg m^2 rad^2/h^2; values checked by hand from the box's moments
    (1 x 2 x 3 m, 1 kg: I = (5, 10, 13)/12 kg m^2)."""
    code, out, _ = run(
        capsys, "phase", "--box", 1, 2, 3, "--periods", 30, 10, "--time-unit", "h", "--csv"
    )
    assert code == 0
    first = out.splitlines()[0]
    for piece in (
        "P_psi [h]",
        "P_phi [h]",
        "P_about_L [h]",
        "E_over_E0 [1]",
        "w1 [rad/h, principal axes I1<I2<I3]",
        "energy [kg m^2 rad^2/h^2]",
        "momentum [kg m^2 rad/h]",
        "D [kg m^2]",
        "total_phase [rad]",
    ):
        assert piece in first
    table = pd.read_csv(io.StringIO(out), comment="#")
    assert len(table) == 2
    moments = np.array([5.0, 10.0, 13.0]) / 12.0
    for _, row in table.iterrows():
        w = row[["w1", "w2", "w3"]].to_numpy(dtype=float)
        energy = 0.5 * float(np.sum(moments * w * w))
        momentum = float(np.linalg.norm(moments * w))
        assert row["energy"] == pytest.approx(energy, rel=1e-12)
        assert row["momentum"] == pytest.approx(momentum, rel=1e-12)
        assert row["D"] == pytest.approx(momentum**2 / (2 * energy), rel=1e-12)
        assert row["E_over_E0"] == pytest.approx(2 * energy * moments[2] / momentum**2, rel=1e-12)
        assert row["P_psi"] == pytest.approx(30, rel=1e-12)
        assert row["P_phi"] == pytest.approx(10, rel=1e-12)


# ------------------------------------------------------------------ catalog
def test_catalog_verify_reports_the_largest_closure_error(tmp_path, capsys):
    """C01 (min instead of max) and C02 (.2f: '0.00 rad')."""
    out = tmp_path / "c.csv"
    code, _, err = run(
        capsys, "catalog", "--preset", "fig6", "--n-max", 3, "--verify", "--out", out
    )
    assert code == 0
    errors = orbits.read_catalog(out)["closure_error"]
    assert len(errors) > 1 and f"{errors.max():.2e}" != f"{errors.min():.2e}"
    m = re.search(r"; largest closure error (\S+) rad$", err.strip().splitlines()[-1])
    assert m and m.group(1) == f"{errors.max():.2e}"


def test_catalog_verify_thin_rod_note_gives_the_largest_allowance(tmp_path, capsys):
    """C04 (allowed.min(): 'up to 1e-08 rad').  The allowance of the quarter
    path is 10 x rtol x I3/I1 x q = 10 x 1e-13 x 1e6 = 1e-6 rad."""
    out = tmp_path / "rod.csv"
    code, _, err = run(
        capsys,
        "catalog",
        "--moments",
        "1e-6",
        1,
        "1.000001",
        "--n-max",
        3,
        "--verify",
        "--out",
        out,
    )
    assert code == 0
    errors = orbits.read_catalog(out)["closure_error"].to_numpy()
    above = int(np.count_nonzero(errors > 1e-8))
    assert above > 0
    note = [line for line in err.splitlines() if line.startswith("orbits: note:")]
    assert len(note) == 1
    assert note[0].startswith(
        f"orbits: note: {above} closure error{'s' if above != 1 else ''} above 1e-08 rad"
    )
    assert "(up to 1e-06 rad:" in note[0]


def test_catalog_nearest_header_names_the_spin_unit(capsys):
    """C07 (the header said rad/s for a spin given in rpm)."""
    code, out, _ = run(
        capsys,
        "catalog",
        "--box",
        0.071,
        0.147,
        0.0078,
        "--mass",
        0.17,
        "--omega",
        60,
        0,
        600,
        "--units",
        "rpm",
        "--nearest",
        2,
        "--out",
        "-",
    )
    assert code == 0
    assert (
        "nearest closed orbits of the spin omega = (60, 0, 600) rpm in the body's own axes" in out
    )
    assert (
        "omega_x, omega_y, omega_z: the orbit's starting spin at that |L|, body's own axes, rpm"
        in out
    )


# ------------------------------------------------------------------ verify
LABELS = {
    "montgomery": "(b) Montgomery",
    "ode_rotation": "(a) ODE rotation",
    "exact_motion": "(c) exact motion",
    "theta_orbit": "theta -> orbit",
    "closed_form_routes": "public routes",
}


def _summary_lines(text):
    return {
        key: line
        for key, label in LABELS.items()
        for line in text.splitlines()
        if line.startswith(label)
    }


def test_verify_text_of_a_failing_run_agrees_with_its_json(capsys, monkeypatch):
    """V02 ('result: ok' always), V03 (.3f discrepancies: 0.000), V04 ('ok' for
    a failed check): the text summary's numbers and verdicts are the JSON's."""
    wrong_closed_form(monkeypatch, 1.0 + 1e-9)
    argv = ["verify", "--bodies", 3, "--angles", 2, "--no-progress"]
    code, out, _ = run(capsys, *argv, "--json")
    assert code == 1
    summary = json.loads(out)
    assert summary["passed"] is False
    code, text, _ = run(capsys, *argv)
    assert code == 1
    assert text.strip().splitlines()[-1] == "result: FAIL"
    lines = _summary_lines(text)
    failed = 0
    for name, line in lines.items():
        check = summary["checks"][name]
        cells = line[len(LABELS[name]) :].split()
        assert float(cells[0]) == pytest.approx(check["max_abs_error"], rel=5e-3)
        assert cells[0] == f"{check['max_abs_error']:.3e}"
        assert cells[-1] == ("ok" if check["passed"] else "FAIL")
        failed += not check["passed"]
    assert failed >= 2  # (b) and (c) at least see a closed form 1e-9 off
    assert "(b) Montgomery" in lines["montgomery"] and lines["montgomery"].endswith("FAIL")


def test_verify_of_one_real_body_reports_its_si_moments(capsys):
    """V06 (the JSON's moments at the unit scale, not the body's kg m^2).
    Box 0.1 x 0.2 x 0.3 m of 2 kg: I = m (b^2 + c^2) / 12, ..."""
    code, out, _ = run(
        capsys,
        "verify",
        "--box",
        0.1,
        0.2,
        0.3,
        "--mass",
        2,
        "--angles",
        2,
        "--json",
        "--no-progress",
    )
    assert code == 0
    summary = json.loads(out)
    a, b, c = 0.1, 0.2, 0.3
    expected = sorted(
        [2 * (b * b + c * c) / 12, 2 * (a * a + c * c) / 12, 2 * (a * a + b * b) / 12]
    )
    assert summary["moments"] == pytest.approx(expected, rel=1e-14)
    assert summary["initial_conditions"] == 2


def test_verify_explains_an_allowance_above_the_tolerance(capsys):
    """V08 (allowance < tolerance: the note never printed).  At --tolerance
    1e-18 the phases' own spacing is the allowance (it passes)."""
    argv = ["verify", "--bodies", 3, "--angles", 2, "--tolerance", "1e-18", "--no-progress"]
    code, out, _ = run(capsys, *argv, "--json")
    summary = json.loads(out)
    assert code == 0 and summary["largest_allowance"] > 1e-18
    code, text, _ = run(capsys, *argv)
    assert code == 0
    assert (
        f"note: the phases reach {summary['max_abs_phase']:.3g} rad, where doubles are "
        f"{summary['phase_resolution']:.3g} rad apart" in text
    )
    assert text.strip().splitlines()[-1] == "result: ok"
    # V05 (bodies for angles in the header), V07 (.3f: max |dT| = 0.000)
    assert text.startswith(
        "orbits verify: 6 initial conditions (3 bodies x 2 angles), tolerance 1e-18 rad"
    )
    period = summary["ode_period_max_abs_error"]
    assert period is not None and period > 0
    assert f"ODE period vs eqn:TK: max |dT| = {period:.3e}\n" in text


# ------------------------------------------------------------------ survey
SURVEY_LINE = re.compile(
    r"^orbits survey: (\d+) bodies \((\d+) computed now in ([\d.]+) s(?:, (\d+) bodies/s)?\), "
    r"(\d+) closed orbits with (n|p/q) <= (\d+), in (.+)$"
)


def _survey(capsys, out):
    code, text, _ = run(
        capsys,
        "survey",
        "--resolution",
        6,
        "--n-max",
        3,
        "--q-max",
        2,
        "--chunk",
        3,
        "--out",
        out,
    )
    assert code == 0
    return text.splitlines()


def _check_rate(m):
    pending, elapsed = int(m.group(2)), float(m.group(3))
    if pending == 0:
        assert m.group(4) is None
        return
    rate = int(m.group(4))
    assert rate >= pending / (elapsed + 0.05) - 0.5
    if elapsed >= 0.1:
        assert rate <= pending / (elapsed - 0.05) + 0.5


def test_survey_summary_counts_phases_and_check(tmp_path, capsys):
    """S01 (bodies computed counted as chunks), S02 (phase over pi, not 2 pi),
    S03 (low and high swapped), S04 (n for p/q), S09 (s/body as bodies/s),
    S05/S07 (--check: verified count and exit 1)."""
    out = tmp_path / "s"
    lines = _survey(capsys, out)
    report = json.loads((out / "report.json").read_text())
    m = SURVEY_LINE.match(lines[0])
    assert m, lines[0]
    assert int(m.group(1)) == report["bodies"] == int(m.group(2))  # a fresh run computes all
    assert int(m.group(5)) == report["orbits"] and m.group(6) == "p/q" and m.group(7) == "3"
    _check_rate(m)
    low, high = report["min_total_phase_range"]
    assert low < high
    assert lines[1].startswith(
        f"minimum total phase: {low / (2 * math.pi):.6f} to {high / (2 * math.pi):.6f} x 2 pi; "
    )
    # one orbits part of a chunk of 3 bodies lost: --check says so, exit 1
    chunks = sorted((out / "orbits").iterdir())
    chunks[0].unlink()
    code, text, _ = run(capsys, "survey", "--check", out)
    assert code == 1
    assert f": {len(chunks) - 1} of {len(chunks)} chunk(s) verified; DAMAGED" in text
    # the rerun computes those 3 bodies only
    m = SURVEY_LINE.match(_survey(capsys, out)[0])
    assert m and int(m.group(2)) == 3 and int(m.group(1)) == report["bodies"]
    _check_rate(m)
    code, text, _ = run(capsys, "survey", "--check", out)
    assert code == 0 and f": {len(chunks)} of {len(chunks)} chunk(s) verified; complete" in text


def test_survey_summary_says_n_for_integer_orbits(tmp_path, capsys):
    """S04, the other way: with --q-max 1 the orbits are n <= N."""
    code, text, _ = run(capsys, "survey", "--resolution", 3, "--n-max", 2, "--out", tmp_path / "s")
    assert code == 0
    m = SURVEY_LINE.match(text.splitlines()[0])
    assert m and m.group(6) == "n" and m.group(7) == "2"


# ------------------------------------------------------------------ shared
def test_skipped_rows_beyond_twenty_are_counted(tmp_path, capsys):
    """H02 (the count of the rows beyond the 20 listed was the total)."""
    path = tmp_path / "bodies.csv"
    path.write_text("I1,I2,I3\n" + "1,x,3\n" * 23 + "1,2,3\n")
    code, _, err = run(
        capsys,
        "catalog",
        "--bodies",
        path,
        "--skip-invalid",
        "--n-max",
        1,
        "--out",
        tmp_path / "c.csv",
    )
    assert code == 0
    lines = err.splitlines()
    assert sum(line.startswith("orbits: warning: skipped ") for line in lines) == 21
    assert "orbits: warning: skipped 3 more invalid rows" in lines
    assert "orbits catalog: 0 closed orbits of 1 body written to" in err


def test_provenance_line_quotes_the_words_typed(capsys):
    """H05 (the command line joined unquoted: 'my top' read back as two words)."""
    import shlex

    argv = [
        "catalog",
        "--moments",
        "1",
        "2",
        "3",
        "--name",
        "my top",
        "--n-max",
        "1",
        "--out",
        "-",
    ]
    code, out, _ = run(capsys, *argv)
    assert code == 0
    line = next(row for row in out.splitlines() if row.startswith("# command: "))
    assert shlex.split(line[len("# command: ") :]) == ["orbits", *argv]


def test_point_masses_print_si_units_and_hand_computed_values(tmp_path, capsys):
    """P03 (REAL_BODIES without point_masses: labels I, I rad^2/s^2, I rad/s).
    Masses 1 kg at x = +-1 m, 2 kg at y = +-0.5 m, 1 kg at z = +-0.3 m:
    Ixx = 2 x 2 x 0.25 + 2 x 0.09 = 1.18, Iyy = 2 + 0.18 = 2.18, Izz = 2 + 1 = 3."""
    path = tmp_path / "pm.csv"
    path.write_text(
        "mass,x,y,z\n1,1,0,0\n1,-1,0,0\n2,0,0.5,0\n2,0,-0.5,0\n1,0,0,0.3\n1,0,0,-0.3\n"
    )
    code, out, _ = run(capsys, "phase", "--point-masses", path, "--omega", 1, 2, 3)
    assert code == 0
    rows = table_rows(out)
    moments, w = np.array([1.18, 2.18, 3.0]), np.array([1.0, 2.0, 3.0])
    energy, momentum = 0.5 * float(np.sum(moments * w * w)), float(np.linalg.norm(moments * w))
    for name, value in zip(("I1", "I2", "I3"), moments):
        assert rows[name][0] == "kg m^2" and float(rows[name][1][0]) == pytest.approx(
            value, rel=1e-12
        )
    assert rows["energy"][0] == "J" and float(rows["energy"][1][0]) == pytest.approx(
        energy, rel=1e-12
    )
    assert rows["momentum"][0] == "J s"
    assert float(rows["momentum"][1][0]) == pytest.approx(momentum, rel=1e-12)
    assert rows["D"][0] == "kg m^2" and rows["D_normalised"][0] == "|I|=1"


def test_defect_flatten_reports_the_excess_removed(capsys):
    """H06 (the --defect flatten warning dropped).  Delta = I_C - I_A - I_B
    with I = 16.857629 u A^2 cm^-1 / B: 16.857629 (1/3 - 1/10 - 1/5) = 0.561921."""
    code, out, err = run(
        capsys,
        "phase",
        "--rotational-constants",
        10,
        5,
        3,
        "--defect",
        "flatten",
        "--omega",
        1e12,
        2e12,
        1e11,
    )
    assert code == 0 and out
    assert err.splitlines() == [
        "orbits: warning: inertial defect Delta = I_C - I_A - I_B = "
        f"{16.857629 / 30:.6f} u A^2 (10.000% of I_C) removed: I_C set to I_A + I_B (flat body)"
    ]
    rows = table_rows(out)
    i1, i2, i3 = (float(rows[n][1][0]) for n in ("I1", "I2", "I3"))
    assert i3 == pytest.approx(i1 + i2, rel=1e-12)


def test_catalog_summary_time_is_seconds(tmp_path, capsys):
    """C06 (the time printed in ms under 's')."""
    import time

    start = time.perf_counter()
    code, _, err = run(
        capsys, "catalog", "--preset", "fig6", "--n-max", 3, "--out", tmp_path / "c.csv"
    )
    wall = time.perf_counter() - start
    assert code == 0
    m = re.search(
        r"^orbits catalog: (\d+) closed orbits of 1 body written to .* in ([\d.]+) s$", err.strip()
    )
    assert m and int(m.group(1)) == len(orbits.read_catalog(tmp_path / "c.csv"))
    assert 0.0 <= float(m.group(2)) <= wall + 0.005


def test_survey_check_of_an_interrupted_survey_fails(tmp_path, capsys):
    """S05 (exit 0 for an incomplete survey that has no damaged part),
    S06 ('DAMAGED' without 'and incomplete'), S07 (verified count)."""
    from orbits.survey import Survey
    from orbits.threads import using_threads

    out = tmp_path / "s"
    survey = Survey.grid(out, 6, 3, q_max=2, chunk=3)

    def stop(_):
        raise KeyboardInterrupt

    # one thread: one chunk in flight at a time, so the stop leaves chunks
    # unwritten whatever the machine (with 6 or more threads all 6 were in
    # flight before the first progress call, and the survey was whole)
    with using_threads(1), pytest.raises(KeyboardInterrupt):
        survey.run(progress=stop)
    code, text, _ = run(capsys, "survey", "--check", out)
    assert code == 1
    first, *rest = text.splitlines()
    m = re.match(r".*: (\d+) of (\d+) chunk\(s\) verified; NOT complete$", first)
    assert m, first
    missing = rest[0].removeprefix("  missing: ").split(", ")
    assert int(m.group(2)) == 6 and int(m.group(1)) == 6 - len(missing) > 0
    # one written part lost as well: damaged and incomplete
    parts = json.loads((out / "manifest.json").read_text())["parts"]
    (out / next(iter(parts.values()))["bodies"]["file"]).unlink()
    code, text, _ = run(capsys, "survey", "--check", out)
    assert code == 1
    assert f": {5 - len(missing)} of 6 chunk(s) verified; DAMAGED and incomplete\n" in text


def test_stopped_survey_says_how_many_chunks_are_written(tmp_path, capsys, monkeypatch):
    """S08 (done = chunks left: '4 of 6 written' for 2 written).  The count
    is the manifest's ledger, read back here."""
    from orbits.survey import Survey

    original = Survey.run

    def interrupted(self, *args, progress=None, **kwargs):
        def stop(_):
            raise KeyboardInterrupt

        return original(self, *args, progress=stop, **kwargs)

    monkeypatch.setattr(Survey, "run", interrupted)
    out = tmp_path / "s"
    code, _, err = run(
        capsys, "survey", "--resolution", 6, "--n-max", 3, "--q-max", 2, "--chunk", 3, "--out", out
    )
    assert code == 130
    written = len(json.loads((out / "manifest.json").read_text())["parts"])
    assert written > 0  # the stop comes from the progress of a recorded chunk
    if written < 6:
        assert f"orbits: interrupted; {written} of 6 chunks are written whole in {out} " in err
    else:  # the chunks in flight all finished
        assert f"orbits: interrupted; every chunk is written in {out}" in err


def test_verify_on_the_separatrix_fails_every_check(capsys):
    """V09 (a check with no value printed 'n/a', not FAIL).  For (1, 2.5, 3)
    the separatrix M^2 = 2 E I2 at phi = 0 is tan^2 theta = I3 (I3 - I2) /
    (I1 (I2 - I1)) = 1: theta_c = pi/4, the one angle of --angles 1."""
    code, out, _ = run(capsys, "verify", "--moments", 1, 2.5, 3, "--angles", 1, "--no-progress")
    assert code == 1
    lines = _summary_lines(out)
    assert len(lines) == 5
    for line in lines.values():
        assert line.split()[-2:] == ["n/a", "FAIL"]
    assert "note: 1 initial condition(s) on the separatrix" in out
    assert out.strip().splitlines()[-1] == "result: FAIL"


def test_survey_lists_the_counterexamples_of_the_conjecture(tmp_path, capsys, monkeypatch):
    """S10 (the count of counterexamples off by one).  No body is known to
    break the conjecture, so the report is given two here."""
    from orbits.survey import Survey

    original = Survey.run
    rows = [
        {"body": k, "I1": 0.3, "I2": 0.5, "I3": 0.8, "min_total_phase": 7.0, "min_theta": 0.4}
        for k in (4, 9)
    ]

    def broken(self, *args, **kwargs):
        report = dict(original(self, *args, **kwargs))
        report["conjecture_minimum_at_the_ends"] = {
            "held_on_every_body": False,
            "counterexamples": rows,
        }
        return report

    monkeypatch.setattr(Survey, "run", broken)
    code, out, _ = run(capsys, "survey", "--resolution", 3, "--n-max", 2, "--out", tmp_path / "s")
    assert code == 0
    lines = out.splitlines()
    assert lines[2] == "conjecture (the minimum lies at theta -> 0 or pi/2): FAILED on 2 bodies:"
    assert lines[3] == (
        "  body 4: I = (0.300000, 0.500000, 0.800000), minimum 7.000000000 at theta = 0.400000000"
    )
    assert len(lines) == 5


def test_verify_announces_an_estimate_above_two_seconds(capsys, monkeypatch):
    """H04 (announce only above 20 s).  10,000 bodies x 10 angles at 3e-5 s a
    condition: 3 s, announced; 100 x 10 (0.03 s) is not.  The work itself is
    stopped at once (a KeyboardInterrupt where verify would start)."""
    from orbits import checks
    from orbits.limits import check_verify_size, format_bytes

    def stop(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(checks, "verify", stop)
    code, _, err = run(capsys, "verify", "--bodies", 10000, "--angles", 10, "--no-progress")
    assert code == 130
    _, memory = check_verify_size(10000, 10)
    assert err.splitlines()[0] == (
        f"orbits verify: estimated 3 s, up to {format_bytes(memory)} of memory; working..."
    )
    code, _, err = run(capsys, "verify", "--bodies", 100, "--angles", 10, "--no-progress")
    assert code == 130 and "estimated" not in err
