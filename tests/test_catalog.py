"""Catalogs: schema, exact CSV round trip, provenance, atomic output, the CLI."""

import errno
import hashlib
import os
import shlex
import signal
import sys
from pathlib import Path

import mpmath
import numpy as np
import pandas as pd
import pytest
from long_run import interrupted_catalog

import orbits
from orbits import (
    ArgumentTypeError,
    Body,
    InputError,
    catalog,
    closed_orbits,
    read_catalog,
    write_catalog,
)
from orbits.atomic import write_csv_atomic
from orbits.catalog import CHECKSUM_KEY, ROWS_KEY, bodies_from_csv, csv_text
from orbits.cli import main

ROOT = Path(__file__).resolve().parents[1]
CATALOGS = ROOT / "catalogs"
FIG6 = Body.preset("fig6")


def assert_one_line_error(code, err, fragment):
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("orbits: error:"), err
    assert fragment in lines[0]


def test_schema_and_order():
    frame = orbits.closed_orbits(FIG6, n_max=4)
    assert list(frame.columns) == list(orbits.CATALOG_COLUMNS)
    assert list(orbits.CATALOG_COLUMNS) == [
        "body",
        "I1",
        "I2",
        "I3",
        "theta_crit",
        "branch",
        "n",
        "q",
        "theta",
        "dtheta",
        "total_phase",
        "dynamic_phase",
        "geometric_phase",
        "period",
        "energy",
        "momentum",
        "D",
        "m",
        "residual",
        "closes_after",
    ]
    assert frame["body"].unique().tolist() == ["fig6"]
    assert frame["n"].dtype.kind == "i" and frame["q"].dtype.kind == "i"
    np.testing.assert_allclose(frame[["I1", "I2", "I3"]].pow(2).sum(axis=1), 1.0, rtol=1e-15)
    np.testing.assert_allclose(frame["theta"], frame["theta_crit"] + frame["dtheta"], rtol=1e-15)
    np.testing.assert_allclose(
        frame["geometric_phase"], frame["dynamic_phase"] - frame["total_phase"], atol=1e-12
    )


@pytest.mark.parametrize("name", ["fig6", "t-handle"])
def test_elliptic_parameter_near_the_separatrix(name):
    """``m = k^2`` stays below 1 and within 8 ulps of mpmath up to n = 30.

    The quotient of gaps put ``m`` at 1 + 4 ulp (outside the domain of
    ``K(m)``) on 67 rows of the committed t-handle catalog, up to 10.3 ulps
    off (7.7 on fig6); with ``1 - kc^2`` the worst is 6.3 ulps.  Reference: eqn:TK at 40 digits for
    the spin ``theta_crit + dtheta`` of each row (the body's own moments).
    """
    body = Body.preset(name)
    frame = orbits.closed_orbits(body, n_max=30, q_max=5)
    assert (frame["m"] <= 1.0).all() and (frame["m"] > 0.0).all()
    worst = 0.0
    with mpmath.workdps(40):
        i1, i2, i3 = (mpmath.mpf(float(x)) for x in body.unit_moments)
        theta_c = mpmath.atan(mpmath.sqrt(i3 * (i3 - i2) / (i1 * (i2 - i1))))
        for m, dtheta in zip(frame["m"], frame["dtheta"]):
            s, c = mpmath.sin(theta_c + dtheta), mpmath.cos(theta_c + dtheta)
            d = (i1**2 * s**2 + i3**2 * c**2) / (i1 * s**2 + i3 * c**2)
            if d > i2:
                exact = (i2 - i1) * (i3 - d) / ((i3 - i2) * (d - i1))
            else:
                exact = (i3 - i2) * (d - i1) / ((i2 - i1) * (i3 - d))
            worst = max(worst, float(abs(m - exact)) / np.spacing(float(exact)))
    assert worst <= 8.0, worst


def test_csv_round_trip_is_bit_exact(tmp_path):
    frame = catalog(FIG6, n_max=30, q_max=3, verify=True)
    path = tmp_path / "fig6.csv"
    write_catalog(frame, path, command="orbits catalog --preset fig6")
    again = read_catalog(path)
    pd.testing.assert_frame_equal(again, frame, check_exact=True)
    # plain pandas with the documented option (none needed on pandas >= 3)
    from orbits.atomic import csv_float_options

    plain = pd.read_csv(path, comment="#", **csv_float_options())
    for column in frame.select_dtypes("float").columns:
        assert np.array_equal(
            plain[column].to_numpy().view(np.int64), frame[column].to_numpy().view(np.int64)
        ), column
    header = again.attrs["header"]
    assert header[0] == f"orbits {orbits.__version__} closed-orbit catalog"
    assert header[1] == "command: orbits catalog --preset fig6"


@pytest.mark.parametrize(
    "mutate, message",
    [
        (lambda f: f.drop(columns="theta"), "schema"),
        (lambda f: f[list(f.columns[::-1])], "schema"),
        (lambda f: f.assign(extra=1.0), "unexpected"),
        (lambda f: f.assign(branch="XAM"), "SAM or LAM"),
        (lambda f: f.assign(n=0), "integers >= 1"),
        (lambda f: f.assign(period=np.inf), "non-finite"),
        # hand edits that keep the schema (the checksum rewritten with them)
        (lambda f: f.assign(dtheta=np.abs(f["dtheta"])), "a SAM orbit must have dtheta < 0"),
        (lambda f: f.assign(dtheta=-np.abs(f["dtheta"])), "a LAM orbit must have dtheta > 0"),
        (lambda f: f.assign(total_phase=99.0), "total_phase is not 2 pi n/q"),
        (lambda f: f.assign(residual=1e-3), "residual is too large"),
        (lambda f: f.assign(n=2 * f["n"], q=2), "not in lowest terms"),
        (lambda f: f.assign(n=1), "not above 1"),
        # a dtheta moved by 1e-3 of itself still has the right sign, phase and
        # residual columns: the theta it no longer matches shows it
        (lambda f: f.assign(dtheta=f["dtheta"] * 1.001), "theta is not theta_crit \\+ dtheta"),
        (lambda f: f.assign(theta=f["theta"] + 1e-9), "theta is not theta_crit \\+ dtheta"),
        # the identities between columns (an edited moment, period, energy,
        # D or phase was written and read back before)
        (lambda f: f.assign(I1=f["I1"] + 0.01), "not of unit norm"),
        (lambda f: f.assign(I1=f["I2"], I2=f["I1"]), "not I1 < I2 < I3"),
        (lambda f: f.assign(period=f["period"] * (1 + 1e-12)), "not 2 E T / M"),
        (lambda f: f.assign(energy=f["energy"] * 1.5), "not 2 E T / M"),
        (lambda f: f.assign(D=f["D"] * (1 + 1e-12)), "D is not M\\^2 / \\(2E\\)"),
        (lambda f: f.assign(geometric_phase=5.0), "not dynamic_phase - geometric_phase"),
        (lambda f: f.assign(closes_after="2"), "closes_after is not that of n/q"),
        (lambda f: f.assign(m=f["m"] * (1 + 1e-9)), "its m is not k\\^2"),
        (lambda f: f.assign(m=1.0 + 2.0**-52), "its m is not k\\^2"),
        (lambda f: f.assign(m=1.0 + 2.0**-40), "its m is not k\\^2"),
        # the largest double: refused, not an overflow warning from its ulp
        (lambda f: f.assign(m=np.finfo(float).max), "its m is not k\\^2"),
    ],
)
def test_read_catalog_checks_schema(tmp_path, mutate, message):
    path = tmp_path / "bad.csv"
    # write_catalog refuses to write it ...
    with pytest.raises(InputError, match=message):
        write_catalog(mutate(orbits.closed_orbits(FIG6, n_max=3)), path)
    assert not path.exists()
    # ... and read_catalog to read it, written by hand with its checksum rewritten
    data = csv_text(mutate(orbits.closed_orbits(FIG6, n_max=3)))
    rows = data.count("\n") - 1
    digest = hashlib.sha256(data.encode()).hexdigest()
    path.write_text(f"# {ROWS_KEY}{rows}\n# {CHECKSUM_KEY}{digest}\n{data}")
    with pytest.raises(InputError, match=message):
        read_catalog(path)
    # without the header lines too (check=False reads hand-made catalogs)
    write_csv_atomic(mutate(orbits.closed_orbits(FIG6, n_max=3)), path)
    with pytest.raises(InputError, match="no row count and checksum"):
        read_catalog(path)
    with pytest.raises(InputError, match=message):
        read_catalog(path, check=False)


def test_read_catalog_names_m_above_1_from_before_the_fix(tmp_path):
    """Catalogs written before m was kept <= 1 hold m = 1 + 4 ulp near the
    separatrix (7 rows of the t-handle's at n <= 30): refused with the
    remedy (regenerate), not as a hand edit; m above 1 that is no rounding
    of k^2 is an edit."""
    frame = orbits.closed_orbits(Body.preset("t-handle"), n_max=30)
    near = frame["m"] == 1.0
    assert near.sum() >= 7
    old = frame.assign(m=np.where(near, 1.0 + 4 * np.spacing(1.0), frame["m"]))
    data = csv_text(old)
    path = tmp_path / "old.csv"
    rows, digest = data.count("\n") - 1, hashlib.sha256(data.encode()).hexdigest()
    path.write_text(f"# {ROWS_KEY}{rows}\n# {CHECKSUM_KEY}{digest}\n{data}")
    first = int(np.flatnonzero(near)[0]) + 1
    with pytest.raises(InputError) as error:
        read_catalog(path)
    message = str(error.value)
    assert f"data row {first} (and {near.sum() - 1} more): its m is above 1 by rounding" in message
    assert message.endswith("regenerate the catalog with the command in its header")
    assert "edited by hand" not in message


def test_read_catalog_missing_file(tmp_path):
    with pytest.raises(InputError, match="no catalog"):
        read_catalog(tmp_path / "none.csv")


def test_many_bodies_and_bodies_file(tmp_path):
    path = tmp_path / "bodies.csv"
    path.write_text("name,I1,I2,I3\nfig6,0.26,0.55,0.793662\nhandle,5.4722,1.9722,3.6667\n")
    bodies = bodies_from_csv(path)
    assert [b.name for b in bodies] == ["fig6", "handle"]
    frame = catalog(bodies, n_max=5)
    assert frame["body"].unique().tolist() == ["fig6", "handle"]
    single = orbits.closed_orbits(FIG6, n_max=5)
    pd.testing.assert_frame_equal(frame[frame.body == "fig6"].reset_index(drop=True), single)


@pytest.mark.parametrize(
    "text, message",
    [
        ("I1,I2\n1,2\n", "missing column"),
        ("I1,I2,I3\n1,2,2.5\n1,1,2\n", "row 2"),
        ("I1,I2,I3\n", "no bodies"),
    ],
)
def test_bad_bodies_file(tmp_path, text, message):
    path = tmp_path / "bodies.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=message):
        bodies_from_csv(path)


def test_failed_write_keeps_the_old_file(tmp_path, monkeypatch):
    path = tmp_path / "keep.csv"
    path.write_text("good old content\n")
    frame = orbits.closed_orbits(FIG6, n_max=3)

    class Full:
        """A file on a full disk: every write fails with ENOSPC."""

        def __init__(self, name, *args, **kwargs):
            self.name = name

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def write(self, text):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), self.name)

    module = sys.modules["orbits.catalog"]  # orbits.catalog is also the function
    monkeypatch.setattr(module, "open", Full, raising=False)
    with pytest.raises(InputError, match=f"cannot write {path}: No space left on device"):
        write_catalog(frame, path)
    assert path.read_text() == "good old content\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.csv"]


def test_new_files_get_normal_permissions(tmp_path):
    path = tmp_path / "new.csv"
    write_catalog(orbits.closed_orbits(FIG6, n_max=3), path)
    umask = os.umask(0)
    os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask


def test_interrupt_leaves_no_partial_file(tmp_path):
    code, err, out = interrupted_catalog(tmp_path, signal.SIGINT, module="orbits.cli")
    assert code == 130
    assert err == ["orbits: interrupted; no partial output was written"]
    assert out.read_text() == "previous good catalog\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bodies.csv", "out.csv"]


def committed_commands():
    for line in (CATALOGS / "regenerate.sh").read_text().splitlines():
        if line.startswith("orbits catalog"):
            yield shlex.split(line)[1:]


@pytest.mark.parametrize(
    "argv", list(committed_commands()), ids=lambda argv: argv[argv.index("--out") + 1]
)
def test_committed_catalogs_regenerate(tmp_path, capsys, argv):
    committed = CATALOGS / Path(argv[argv.index("--out") + 1]).name
    fresh = tmp_path / committed.name
    argv = list(argv)
    argv[argv.index("--out") + 1] = str(fresh)
    assert main(argv) == 0
    old, new = read_catalog(committed), read_catalog(fresh)
    assert old.attrs["header"][1] == "command: orbits " + " ".join(
        shlex.quote(w) for w in argv[:-1] + [f"catalogs/{committed.name}"]
    )
    assert (old[["body", "branch", "n", "q"]] == new[["body", "branch", "n", "q"]]).all().all()
    floats = [c for c in orbits.CATALOG_COLUMNS if old[c].dtype.kind == "f" and c != "residual"]
    np.testing.assert_allclose(new[floats], old[floats], rtol=1e-12, atol=0)
    np.testing.assert_allclose(new["residual"], old["residual"], atol=1e-12)
    # the independent integration closes every committed orbit
    assert old["closure_error"].max() <= 1e-8
    assert new["closure_error"].max() <= 1e-8


def test_committed_fig6_matches_the_paper():
    table = read_catalog(CATALOGS / "fig6_n30.csv")
    small = table[table.n <= 5]
    assert small["n"].tolist() == [2, 3, 4, 5, 5, 4, 3, 2]
    assert np.round(small["theta"], 4).tolist() == [
        0.9562,
        1.0043,
        1.0113,
        1.0124,
        1.0139,
        1.0207,
        1.0611,
        1.2742,
    ]


class TestCli:
    def test_writes_a_catalog(self, tmp_path, capsys):
        out = tmp_path / "c.csv"
        assert (
            main(
                [
                    "catalog",
                    "--ellipsoid",
                    "0.4",
                    "0.2",
                    "--n-max",
                    "6",
                    "--q-max",
                    "2",
                    "--verify",
                    "--out",
                    str(out),
                ]
            )
            == 0
        )
        table = read_catalog(out)
        assert set(table["q"]) == {1, 2} and table["closure_error"].max() <= 1e-8
        assert "closed orbits" in capsys.readouterr().err

    @pytest.mark.parametrize(
        "argv, fragment",
        [
            (
                ["catalog", "--preset", "fig6", "--n-max", "0", "--out", "x.csv"],
                "must be an integer >= 1",
            ),
            (["catalog", "--preset", "nope", "--n-max", "3", "--out", "x.csv"], "invalid choice"),
            (
                ["catalog", "--moments", "1", "1", "2", "--n-max", "3", "--out", "x.csv"],
                "symmetric top",
            ),
            (
                ["catalog", "--moments", "1", "2", "nan", "--n-max", "3", "--out", "x.csv"],
                "finite",
            ),
            (
                ["catalog", "--moments", "1", "2", "9", "--n-max", "3", "--out", "x.csv"],
                "triangle",
            ),
            (
                ["catalog", "--preset", "fig6", "--n-max", "3", "--out", "/no/such/dir/x.csv"],
                "does not exist",
            ),
            (["catalog", "--preset", "fig6", "--n-max", "3"], "--out"),
            (
                ["catalog", "--bodies", "/no/such/bodies.csv", "--n-max", "3", "--out", "x.csv"],
                "no bodies file",
            ),
            (
                ["catalog", "--ellipsoid", "0.9", "0.8", "--n-max", "3", "--out", "x.csv"],
                "too large",
            ),
        ],
    )
    def test_bad_input(self, tmp_path, capsys, monkeypatch, argv, fragment):
        monkeypatch.chdir(tmp_path)
        code = main(argv)
        assert_one_line_error(code, capsys.readouterr().err, fragment)
        assert not (tmp_path / "x.csv").exists()

    @pytest.mark.parametrize("target", ["/proc/orbits-test.csv", "/sys/orbits-test.csv"])
    def test_unwritable_filesystem(self, capsys, target):
        """Not writable even for root: a clear one-line error, nothing left over."""
        code = main(["catalog", "--preset", "fig6", "--n-max", "3", "--out", target])
        assert_one_line_error(code, capsys.readouterr().err, f"cannot write {target}")

    def test_unwritable_directory(self, tmp_path, capsys):
        locked = tmp_path / "locked"
        locked.mkdir()
        locked.chmod(0o500)
        try:
            if os.access(locked, os.W_OK):
                pytest.skip("running as a user who can write anywhere")
            code = main(
                ["catalog", "--preset", "fig6", "--n-max", "3", "--out", str(locked / "x.csv")]
            )
            assert_one_line_error(code, capsys.readouterr().err, "not writable")
        finally:
            locked.chmod(0o700)


def test_a_catalog_of_a_body_listed_twice_reads_back(tmp_path, capsys):
    """One body twice under one name: its rows repeat, and the catalog the
    package wrote must read back."""
    bodies = tmp_path / "dup.csv"
    bodies.write_text("I1,I2,I3,name\n1,2,3,a\n1,2,3,a\n")
    out = tmp_path / "dupcat.csv"
    assert main(["catalog", "--bodies", str(bodies), "--n-max", "3", "--out", str(out)]) == 0
    table = read_catalog(out)
    assert len(table) == 2 * len(catalog(Body((1.0, 2.0, 3.0)), n_max=3))


def test_flags_are_bools(tmp_path):
    """read_catalog(check="no") skipped the check ("no" is true only by
    accident here: any string was taken for its truth value)."""
    out = tmp_path / "c.csv"
    write_catalog(closed_orbits(Body.preset("fig6"), n_max=2), out)
    for value in ("no", np.array([True, False]), 1, None):
        with pytest.raises(ArgumentTypeError, match="check must be True or False"):
            read_catalog(out, check=value)
    assert read_catalog(out, check=np.False_).equals(read_catalog(out))


def test_write_catalog_writes_only_what_read_catalog_reads(tmp_path):
    """A frame read_catalog refuses (another schema, NaN, extra or reordered
    columns, an edited row) was written with a valid checksum; notes="text"
    wrote a header line per letter."""
    frame = closed_orbits(FIG6, n_max=3)
    out = tmp_path / "c.csv"
    bad = {
        "columns ['a'] do not start with the catalog schema": pd.DataFrame({"a": [1.0]}),
        "column total_phase has non-finite numbers": frame.assign(total_phase=np.nan),
        "do not start with the catalog schema": frame[frame.columns[::-1]],
        "unexpected columns ['extra']": frame.assign(extra=1.0),
        "columns given twice: ['n']": pd.concat([frame, frame[["n"]]], axis=1),
        "its total_phase is not 2 pi n/q": frame.assign(n=frame["n"] + 1),
    }
    for message, wrong in bad.items():
        with pytest.raises(InputError, match=message.replace("[", r"\[").replace("]", r"\]")):
            write_catalog(wrong, out)
        assert not out.exists() and list(tmp_path.iterdir()) == []
    write_catalog(frame, out, notes="one note")
    back = read_catalog(out)
    assert back.equals(frame) and back.attrs["header"][3] == "one note"


@pytest.mark.parametrize(
    "keywords, error",
    [
        ({"notes": None}, orbits.ArgumentTypeError),
        ({"notes": 0.5}, orbits.ArgumentTypeError),
        ({"notes": b"ab"}, orbits.ArgumentTypeError),  # wrote lines "# 97", "# 98"
        ({"notes": [1]}, orbits.ArgumentTypeError),
        ({"command": 0}, orbits.ArgumentTypeError),  # recorded "(Python API)"
        ({"command": ["orbits", "catalog"]}, orbits.ArgumentTypeError),  # the list's repr
        ({"command": np.array([1, 2])}, orbits.ArgumentTypeError),
        ({"command": "a\ud800"}, InputError),  # a raw UnicodeEncodeError
        ({"notes": ["\ud800"]}, InputError),
    ],
)
def test_write_catalog_checks_its_header_text(tmp_path, keywords, error):
    path = tmp_path / "c.csv"
    with pytest.raises(error):
        write_catalog(orbits.closed_orbits(FIG6, n_max=3), path, **keywords)
    assert list(tmp_path.iterdir()) == []
    write_catalog(orbits.closed_orbits(FIG6, n_max=3), path, command="x", notes=("a", "b"))
    assert path.read_text().splitlines()[1:5:3] == ["# command: x", "# b"]


def test_unresolved_orbit_warnings_name_the_body_at_the_callers_line():
    """catalog's warning pointed at orbits/catalog.py and did not say which
    body (two unnamed bodies: two identical lines)."""
    fig6 = orbits.Body.preset("fig6")
    with pytest.warns(orbits.UnresolvedOrbitsWarning) as caught:
        orbits.catalog([fig6, orbits.Body(fig6.moments)], n_max=400)
    assert [w.filename for w in caught] == [__file__, __file__]
    texts = [str(w.message) for w in caught]
    assert texts[0].startswith("body 1 of 2: fig6: 29 closed orbits (15 on SAM and 14 on LAM)")
    assert texts[1].startswith("body 2 of 2: 29 closed orbits")
    with pytest.warns(orbits.UnresolvedOrbitsWarning) as caught:
        orbits.closed_orbits(fig6, n_max=400)
    assert caught[0].filename == __file__ and str(caught[0].message).startswith("fig6: 29")
    # nearest_orbits does not pass the warning on: the orbits it names are
    # either farther than every row or among the nearest, and then the call
    # is refused (here the spin lies beyond what an orbit's double reaches;
    # it used to return 20 rows ranked without the nearest ones, and warn)
    with pytest.raises(orbits.InputError, match="total phase 4727.7 rad, SAM.*above 2423.57 rad"):
        orbits.nearest_orbits(fig6, [1e-300, 1.0, 1e-300], 20)


def test_catalogs_from_threads_leave_the_warning_machinery_alone():
    """catalog relabelled the search's warnings inside warnings.catch_warnings,
    which swaps the process's filters and showwarning: from four threads at
    once it left a filter list that sent every later warning to a dead list
    (and lost some of the UnresolvedOrbitsWarnings).  Each call's warning is
    delivered once, and the machinery is as it was."""
    import warnings
    from concurrent.futures import ThreadPoolExecutor

    orbits.catalog(FIG6, n_max=3)  # the modules it imports on first use, imported here
    filters, show = list(warnings.filters), warnings.showwarning
    calls = [420 if k % 25 == 0 else 3 for k in range(200)]  # 8 calls leave orbits out
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        inside = list(warnings.filters)
        with ThreadPoolExecutor(4) as pool:
            frames = list(pool.map(lambda n_max: orbits.catalog(FIG6, n_max=n_max), calls))
        assert warnings.filters == inside
    assert warnings.filters == filters and warnings.showwarning is show
    unresolved = [w for w in caught if issubclass(w.category, orbits.UnresolvedOrbitsWarning)]
    assert len(unresolved) == calls.count(420)
    assert all(str(w.message).startswith("fig6: 69 closed orbits") for w in unresolved)
    assert all(w.filename == __file__ for w in unresolved)  # the user's line
    assert [len(f) for f in frames] == [
        len(frames[0]) if n == 420 else len(frames[1]) for n in calls
    ]


@pytest.mark.parametrize("added, code", [(5e-7, 1), (5e-9, 0)])
def test_catalog_verify_fails_on_a_closure_error(tmp_path, monkeypatch, capsys, added, code):
    """`orbits catalog --verify` exits 1 when an orbit does not close to 1e-8
    rad (here the independent integration is made to miss by 5e-7), and 0
    within it; nothing tested the failing branch (an exit 0 there, or an
    allowance 100 times too wide, passed the suite)."""
    from orbits import checks

    original = checks.closure_errors
    monkeypatch.setattr(
        checks, "closure_errors", lambda *args, **kwargs: original(*args, **kwargs) + added
    )
    out = tmp_path / "c.csv"
    argv = ["catalog", "--preset", "fig6", "--n-max", "3", "--verify", "--out", str(out)]
    assert main(argv) == code
    err = capsys.readouterr().err
    failed = "orbits: error: 4 closure errors above 1e-08 rad (and the check's own error)"
    assert (failed in err) == (code == 1)
    assert read_catalog(out)["closure_error"].min() >= added


def test_catalog_verify_of_no_orbit_says_so(tmp_path, capsys):
    """An empty catalog printed "largest closure error 0.00e+00 rad", a
    check that never ran (an audit)."""
    out = tmp_path / "none.csv"
    command = ["catalog", "--preset", "fig6", "--n-max", "1", "--q-max", "5", "--verify"]
    assert main([*command, "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "0 closed orbits of 1 body written" in err and err.rstrip().endswith(
        "; no orbit to verify"
    )
    assert "closure error" not in err
    assert len(read_catalog(out)) == 0
