"""The command line: results, and one-line errors with exit code 2."""

import io
import json
import shutil
import subprocess
import sys

import pandas as pd
import pytest

from orbits.atomic import csv_float_options
from orbits.cli import main


def run(capsys, *argv):
    code = main(list(argv))
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
