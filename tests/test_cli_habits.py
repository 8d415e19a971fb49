"""Command-line habits: real units, degrees, real bodies, verify BODY, tables."""

import io
import math
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

import orbits
from orbits import Body, Motion
from orbits.cli import announce_compilation, format_value, main


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def csv_rows(out):
    from orbits.atomic import csv_float_options

    return pd.read_csv(io.StringIO(out), comment="#", **csv_float_options())


PHONE = ("--box", "0.146", "0.071", "0.008", "--mass", "0.17")


def test_csv_states_units_and_frame_on_its_first_line(capsys):
    """`phase --omega ... --csv` printed w1..w3, energy and periods with no
    unit or frame (the table labels them): a '# units:' line comes first."""
    code, out, _ = run(
        capsys, "phase", *PHONE, "--omega", "0.3", "0.1", "3", "--units", "Hz", "--csv"
    )
    first = out.splitlines()[0]
    assert code == 0 and first.startswith("# units: ")
    stated = dict(item.rsplit(" [", 1) for item in first[len("# units: ") :].split("; "))
    assert stated["w1"] == "rad/s, principal axes I1<I2<I3]"
    assert stated["energy"] == "J]"  # a box in m and kg: SI
    assert stated["period"] == "s]"
    # every column but the text ones is stated
    header = out.splitlines()[1].split(",")
    assert set(stated) == set(header) - {"branch"}


class TestOmega:
    def test_omega_in_hz_gives_physical_outputs_and_d(self, capsys):
        code, out, _ = run(
            capsys, "phase", *PHONE, "--omega", "0.3", "0.1", "3", "--units", "Hz", "--csv"
        )
        assert code == 0
        row = csv_rows(out).iloc[0]
        body = Body.box(0.146, 0.071, 0.008, 0.17)
        omega = 2 * math.pi * np.array([0.3, 0.1, 3.0])
        principal = body.frame @ omega
        # independent: E, L and D straight from the vector
        inertia_omega = body.moments * principal
        energy = 0.5 * principal @ inertia_omega
        momentum = np.linalg.norm(inertia_omega)
        assert row.energy == pytest.approx(energy, rel=1e-14)  # J
        assert row.momentum == pytest.approx(momentum, rel=1e-14)  # J s
        assert row.D == pytest.approx(momentum**2 / (2 * energy), rel=1e-14)
        assert body.moments[0] <= row.D <= body.moments[2]
        # and it finds its catalog row: phases() at the same direction, |I| = 1
        theta = math.atan2(math.hypot(principal[0], principal[1]), abs(principal[2]))
        unit_row = orbits.phases(body, theta, math.atan2(principal[1], principal[0]))
        assert row.D_normalised == pytest.approx(unit_row.D.iloc[0], rel=1e-13)
        # the period in seconds: the unit-spin period over |omega| in rad/s
        unit = Motion.from_omega(body, principal / np.linalg.norm(principal), axes="principal")
        assert row.period == pytest.approx(unit.period / np.linalg.norm(omega), rel=1e-12)

    @pytest.mark.parametrize(
        "unit, factor",
        [("rad/s", 1.0), ("deg/s", math.pi / 180), ("rpm", math.pi / 30), ("Hz", 2 * math.pi)],
    )
    def test_units(self, capsys, unit, factor):
        code, out, _ = run(
            capsys,
            "phase",
            "--moments",
            "1",
            "2",
            "2.5",
            "--omega",
            "1",
            "0.5",
            "2",
            "--units",
            unit,
            "--csv",
        )
        assert code == 0
        row = csv_rows(out).iloc[0]
        np.testing.assert_allclose(
            [row.w1, row.w2, row.w3], factor * np.array([1.0, 0.5, 2.0]), rtol=1e-15
        )

    def test_omega_is_taken_along_the_callers_axes(self, capsys):
        # moments given out of order: omega along the given 2nd axis (I = 3)
        code, out, _ = run(
            capsys, "phase", "--moments", "1", "3", "2", "--omega", "0.01", "1", "0.01", "--csv"
        )
        assert code == 0
        row = csv_rows(out).iloc[0]
        assert abs(row.w3) == pytest.approx(1.0)  # I3 = 3 is the largest
        assert row.branch == "SAM"

    def test_zero_omega_is_a_usage_error(self, capsys):
        code, _, err = run(capsys, "phase", *PHONE, "--omega", "0", "0", "0")
        assert code == 2 and "nonzero" in err


class TestDegrees:
    def test_degrees_equal_radians(self, capsys):
        _, out_deg, _ = run(
            capsys,
            "phase",
            "--preset",
            "fig6",
            "--theta",
            "30",
            "50",
            "--phi",
            "20",
            "--degrees",
            "--csv",
        )
        _, out_rad, _ = run(
            capsys,
            "phase",
            "--preset",
            "fig6",
            "--theta",
            repr(math.radians(30)),
            repr(math.radians(50)),
            "--phi",
            repr(math.radians(20)),
            "--csv",
        )
        pd.testing.assert_frame_equal(csv_rows(out_deg), csv_rows(out_rad))


class TestTables:
    def test_tiny_offsets_print_in_full(self, capsys):
        code, out, _ = run(capsys, "phase", "--preset", "fig6", "--dtheta", "1e-300", "-2.5e-310")
        assert code == 0
        line = next(line for line in out.splitlines() if line.startswith("dtheta"))
        assert line.split()[2:] == ["1e-300", "-2.5e-310"]  # name, [unit], values

    def test_format_value_round_trips(self):
        for value in (1e-300, -2.5e-310, 0.1, 2363.3445496407253, 1.0 / 3.0):
            assert float(format_value(np.float64(value))) == value
        assert format_value("SAM") == "SAM"


class TestTotalPhase:
    def test_total_phase_finds_every_spin(self, capsys):
        code, out, _ = run(capsys, "phase", "--preset", "fig6", "--total-phase", "20", "--csv")
        assert code == 0
        table = csv_rows(out)
        assert set(table.branch) == {"SAM", "LAM"}
        np.testing.assert_allclose(
            orbits.total_phase(Body.preset("fig6"), dtheta=table.dtheta.to_numpy()),
            20.0,
            rtol=1e-12,
        )

    def test_total_phase_in_degrees(self, capsys):
        _, out, _ = run(
            capsys, "phase", "--preset", "fig6", "--total-phase", "1440", "--degrees", "--csv"
        )
        np.testing.assert_allclose(csv_rows(out).total_phase, 8 * math.pi, rtol=1e-12)

    def test_unreachable_total_phase_is_a_usage_error(self, capsys):
        code, _, err = run(capsys, "phase", "--preset", "fig6", "--total-phase", "1")
        assert code == 2 and "at least" in err


class TestRealBodies:
    def test_box_and_cylinder(self, capsys):
        code, out, _ = run(capsys, "phase", *PHONE, "--theta", "0.3", "--csv")
        assert code == 0
        code, _, err = run(capsys, "phase", "--cylinder", "0.1", "1", "--theta", "0.3")
        assert code == 2 and "symmetric top" in err
        code, _, _ = run(
            capsys, "phase", "--cylinder", "0.1", "1", "0.05", "--mass", "2", "--theta", "0.3"
        )
        assert code == 0

    def test_point_masses_file(self, capsys, tmp_path):
        path = tmp_path / "masses.csv"
        path.write_text("mass,x,y,z\n1,0,0,0\n2,1,0,0\n3,0,2,0\n4,0,0,3\n")
        code, _, _ = run(capsys, "phase", "--point-masses", str(path), "--theta", "0.3")
        assert code == 0
        path.write_text("mass,x,y\n1,0,0\n")
        code, _, err = run(capsys, "phase", "--point-masses", str(path), "--theta", "0.3")
        assert code == 2 and "z" in err

    def test_point_masses_file_reads_exactly_what_it_says(self, capsys, tmp_path):
        """Columns in any order, # comments, blank lines: the moments are those
        of Body.from_point_masses of the same numbers, bit for bit."""
        from orbits.atomic import csv_float_options
        from orbits.cli.shared import _point_masses_from_csv

        path = tmp_path / "masses.csv"
        path.write_text(
            "# a made-up molecule\nz, x ,y,mass\n0,0,0,1.5 # at the origin\n\n"
            "0,1e-10,0,2\n3.25,0,2,3\n-1,0,0.125,4\n"
        )
        masses, positions = _point_masses_from_csv(str(path))
        assert masses.tolist() == [1.5, 2.0, 3.0, 4.0]
        assert positions.tolist() == [[0, 0, 0], [1e-10, 0, 0], [0, 2, 3.25], [0, 0.125, -1]]
        code, out, _ = run(capsys, "phase", "--point-masses", str(path), "--theta", "0.3", "--csv")
        assert code == 0
        body = orbits.Body.from_point_masses(masses, positions)
        want = orbits.phases(body, 0.3)
        got = pd.read_csv(io.StringIO(out), comment="#", **csv_float_options())
        assert got["total_phase"].iloc[0] == want["total_phase"].iloc[0]

    def test_rotational_constants_defect(self, capsys):
        water = ("--rotational-constants", "835840.3", "435351.7", "278138.7", "--unit", "MHz")
        code, _, err = run(capsys, "phase", *water, "--theta", "0.3")
        assert code == 2 and "--defect flatten" in err and "inertial defect" in err
        code, _, err = run(capsys, "phase", *water, "--defect", "flatten", "--theta", "0.3")
        assert code == 0 and "warning: inertial defect" in err

    def test_mesh(self, capsys, tmp_path):
        trimesh = pytest.importorskip("trimesh")
        path = tmp_path / "box.stl"
        trimesh.creation.box(extents=(3.0, 2.0, 1.0)).export(path)
        code, out, _ = run(
            capsys, "phase", "--mesh", str(path), "--density", "2", "--theta", "0.3", "--csv"
        )
        assert code == 0
        row = csv_rows(out).iloc[0]
        expected = Body.box(3.0, 2.0, 1.0).normalized_moments
        np.testing.assert_allclose([row.I1, row.I2, row.I3], expected, rtol=1e-6)

    def test_name(self, capsys, tmp_path):
        out_file = tmp_path / "c.csv"
        code, _, _ = run(
            capsys, "catalog", *PHONE, "--name", "phone", "--n-max", "3", "--out", str(out_file)
        )
        assert code == 0
        assert set(orbits.read_catalog(out_file)["body"]) == {"phone"}


class TestVerifyBody:
    def test_verify_my_body(self, capsys):
        code, out, _ = run(capsys, "verify", *PHONE, "--angles", "4", "--json")
        assert code == 0
        import json

        summary = json.loads(out)
        assert summary["initial_conditions"] == 4
        assert summary["passed"]
        assert all(check["max_abs_error"] < 1e-9 for check in summary["checks"].values())


def test_python_dash_m_orbits():
    result = subprocess.run(
        [sys.executable, "-m", "orbits", "--version"], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0
    assert result.stdout.startswith("orbits ")


def test_threads_option(capsys):
    code, _, err = run(capsys, "--threads", "1", "phase", "--preset", "fig6", "--theta", "0.3")
    assert code == 0
    import numba

    code, _, err = run(
        capsys,
        "--threads",
        str(numba.config.NUMBA_NUM_THREADS + 1),
        "phase",
        "--preset",
        "fig6",
        "--theta",
        "0.3",
    )
    assert code == 2 and "threads" in err
    orbits.set_num_threads(numba.config.NUMBA_NUM_THREADS)


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_compile_note_only_on_a_terminal_with_an_empty_cache(tmp_path, monkeypatch):
    import orbits.cli as cli

    assert announce_compilation(io.StringIO()) is False  # not a terminal
    # a copy of the package layout with no cache: the note is printed
    core = tmp_path / "orbits" / "core"
    core.mkdir(parents=True)
    monkeypatch.setattr(cli, "__file__", str(tmp_path / "orbits" / "cli" / "__init__.py"))
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    stream = _Terminal()
    assert announce_compilation(stream) is True
    assert stream.getvalue().count("\n") == 1 and "compiling" in stream.getvalue()
    # once an index file exists, nothing is printed
    (core / "__pycache__").mkdir()
    (core / "__pycache__" / "phase.cel-1.py311.nbi").write_bytes(b"")
    assert announce_compilation(_Terminal()) is False


def test_compile_note_follows_numba_cache_dir(tmp_path, monkeypatch):
    """With NUMBA_CACHE_DIR set numba caches only there: an index file next
    to the sources does not mean the kernels are compiled."""
    import orbits.cli as cli

    core = tmp_path / "orbits" / "core"
    (core / "__pycache__").mkdir(parents=True)
    (core / "__pycache__" / "phase.cel-1.py311.nbi").write_bytes(b"")
    monkeypatch.setattr(cli, "__file__", str(tmp_path / "orbits" / "cli" / "__init__.py"))
    cache = tmp_path / "cache"
    cache.mkdir()
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(cache))
    assert announce_compilation(_Terminal()) is True
    (cache / "sub").mkdir()
    (cache / "sub" / "search.search_body-331.py311.nbi").write_bytes(b"")
    assert announce_compilation(_Terminal()) is False


def test_first_run_on_a_terminal_says_it_compiles(tmp_path):
    """End to end: stderr a pseudo-terminal, an empty numba cache."""
    import os
    import pty
    import subprocess
    import sys

    main_fd, child_fd = pty.openpty()
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    result = subprocess.run(
        [sys.executable, "-m", "orbits", "phase", "--preset", "fig6", "--theta", "0.3"],
        stderr=child_fd,
        stdout=subprocess.PIPE,
        env=env,
        timeout=600,
        check=False,
    )
    os.close(child_fd)
    err = b""
    while True:
        try:
            chunk = os.read(main_fd, 4096)
        except OSError:
            break
        if not chunk:
            break
        err += chunk
    os.close(main_fd)
    assert result.returncode == 0
    lines = err.decode().splitlines()
    assert len(lines) == 1 and "compiling" in lines[0], lines
    assert b"total_phase" in result.stdout


@pytest.mark.parametrize(
    "argv, message",
    [
        # argparse let the last one win silently
        (
            ["phase", "--preset", "fig6", "--theta", "0.5", "--theta", "0.7"],
            "--theta is given more",
        ),
        (["phase", "--preset", "fig6", "--preset", "t-handle", "--theta", "0.5"], "--preset is"),
        (
            ["phase", "--moments", "1", "2", "3", "--moments", "3", "4", "5", "--theta", "1"],
            "once",
        ),
        # two spellings of one option: MHz against GHz moved every moment 1000x
        (
            ["phase", "--rotational-constants", "3", "2", "1.5", "--unit", "MHz"]
            + ["--constants-unit", "GHz", "--theta", "0.5"],
            "--unit and --constants-unit set the same thing",
        ),
        # --units with no spin to apply to was ignored
        (["catalog", "--preset", "fig6", "--n-max", "3", "--units", "rpm", "--out", "-"], "only"),
    ],
)
def test_repeated_conflicting_or_idle_options_are_refused(argv, message, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err


def test_an_endless_input_file_is_refused_within_the_memory_budget(monkeypatch, capsys):
    """``--bodies /dev/zero`` read until the machine ran out of memory (killed, 137)."""
    import orbits.limits

    monkeypatch.setattr(orbits.limits, "memory_budget", lambda: 16 * 2**20)
    for argv in (
        ["catalog", "--bodies", "/dev/zero", "--n-max", "3", "--out", "-"],
        ["phase", "--point-masses", "/dev/zero", "--theta", "0.5"],
    ):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "holds more than 1 MiB" in err[0], err


def test_usage_errors_name_the_program_once(capsys):
    """The top-level parser's errors read "orbits: error: orbits: ..." before."""
    code, _, err = run(capsys, "--threads", "abc", "phase", "--preset", "fig6", "--theta", "0.3")
    assert code == 2 and err == "orbits: error: argument --threads: not an integer: 'abc'\n"
    code, _, err = run(capsys, "nope")
    assert code == 2 and err.startswith("orbits: error: argument command: invalid choice: 'nope'")
    # a subcommand's errors say which one
    code, _, err = run(capsys, "phase", "--preset", "fig6", "--theta", "x")
    assert (
        code == 2 and err == "orbits: error: orbits phase: argument --theta: not a number: 'x'\n"
    )


@pytest.mark.parametrize("exponent", [-1000, -530, 520, 1000])
def test_d_normalised_at_any_scale_of_the_moments(exponent, capsys):
    """|I| over- or underflowed beyond 1e+-154: D_normalised printed 0.0, a
    2.8 % error, or a ZeroDivisionError traceback.  Moments scaled by an
    exact power of two give the same bits as (1, 2, 3)."""

    def d_normalised(moments):
        argv = ["phase", "--moments", *map(repr, moments), "--omega", "1", "1", "1", "--csv"]
        assert main(argv) == 0
        table = pd.read_csv(io.StringIO(capsys.readouterr().out), comment="#")
        return float(table["D_normalised"].iloc[0])

    reference = d_normalised([1.0, 2.0, 3.0])
    assert reference == pytest.approx(0.62360956446232363, rel=1e-15)
    scaled = [math.ldexp(v, exponent) for v in (1.0, 2.0, 3.0)]
    assert d_normalised(scaled) == reference


def test_a_name_stays_one_table_line_and_a_safe_csv_cell(capsys):
    """--name with a newline split the text table; '=1+2' went into the CSV
    as a formula (catalogs neutralise such cells: orbits.cells.neutralize)."""
    assert main(["phase", "--preset", "fig6", "--name", "a\nb", "--theta", "0.3"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].split() == ["name", "[-]", "a\\nb"]
    assert out[1].startswith("I1 ")
    assert main(["phase", "--preset", "fig6", "--name", "=1+2", "--theta", "0.3", "--csv"]) == 0
    table = pd.read_csv(io.StringIO(capsys.readouterr().out), comment="#")
    assert table["name"].iloc[0] == "'=1+2"


def test_point_masses_file_with_a_byte_order_mark(capsys, tmp_path):
    """Excel's 'CSV UTF-8' starts with a byte-order mark (and CRLF lines)."""
    from orbits.cli.shared import _point_masses_from_csv

    path = tmp_path / "masses.csv"
    path.write_bytes(b"\xef\xbb\xbfmass,x,y,z\r\n1,1,0,0\r\n1,-1,0,0\r\n1,0,2,0\r\n1,0,-2,0.5\r\n")
    masses, positions = _point_masses_from_csv(str(path))
    assert masses.tolist() == [1.0, 1.0, 1.0, 1.0]
    assert positions[3].tolist() == [0.0, -2.0, 0.5]
    assert main(["phase", "--point-masses", str(path), "--theta", "0.3"]) == 0


def _orbits(tmp_path, env, *argv):
    """``python -m orbits ARGV`` in ``tmp_path`` with ``env`` added: (code, stdout, stderr)."""
    import os

    done = subprocess.run(
        [sys.executable, "-m", "orbits", *argv],
        cwd=tmp_path,
        env={**os.environ, **env},
        capture_output=True,
        timeout=300,
    )
    return done.returncode, done.stdout, done.stderr.decode("ascii", "backslashreplace")


@pytest.mark.parametrize(
    "argv",
    [
        ["figures", "--preset", "fig6", "--n-max", "2", "--out", "f"],
        ["animate", "--preset", "fig6", "--theta", "0.5", "--out", "a.gif"],
    ],
)
def test_a_bad_matplotlib_backend_is_one_line(tmp_path, argv):
    """MPLBACKEND=nonsense: import matplotlib raised a ValueError traceback, exit 1."""
    code, _, err = _orbits(tmp_path, {"MPLBACKEND": "nonsense"}, *argv)
    assert code == 2, err
    assert err.splitlines() == [
        "orbits: error: MPLBACKEND='nonsense' is not a matplotlib backend, and matplotlib "
        "cannot start; orbits draws off screen with Agg: unset MPLBACKEND or give a "
        "valid one (e.g. agg)"
    ]
    assert list(tmp_path.iterdir()) == []


def test_an_ascii_terminal_and_a_name_it_cannot_show(tmp_path):
    """PYTHONIOENCODING=ascii and --name é: a UnicodeEncodeError traceback, exit 1;
    a message holding the name is escaped on stderr, not lost."""
    ascii_io = {"PYTHONIOENCODING": "ascii"}
    code, out, err = _orbits(
        tmp_path, ascii_io, "phase", "--preset", "fig6", "--theta", "0.5", "--name", "é"
    )
    assert code == 2 and err.splitlines() == [
        r"orbits: error: cannot write '\xe9' in ascii (standard output's encoding is "
        "ascii); set PYTHONIOENCODING=utf-8 or a UTF-8 locale"
    ]
    code, _, err = _orbits(tmp_path, ascii_io, "phase", "--preset", "fégé", "--theta", "0.5")
    assert code == 2 and err.splitlines() == [
        r"orbits: error: orbits phase: argument --preset: invalid choice: 'f\xe9g\xe9' "
        "(choose from 'fig6', 't-handle')"
    ]
    code, out, _ = _orbits(
        tmp_path,
        {"PYTHONIOENCODING": "utf-8"},
        "phase",
        "--preset",
        "fig6",
        "--theta",
        "0.5",
        "--name",
        "é",
    )
    assert code == 0 and "é" in out.decode("utf-8")


def test_an_attached_value_ending_in_the_separator_is_kept(capsys):
    """--name=a=-- names "a=--" (argparse strips only a value of exactly
    "--"); the refusal of --OPT=-- took it for one."""
    code = main(["phase", "--preset", "fig6", "--theta", "0.5", "--name=a=--"])
    out = capsys.readouterr().out
    assert code == 0 and out.splitlines()[0].split()[-1] == "a=--"
