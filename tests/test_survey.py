"""Survey: tables, the conjecture report, resume after a kill, Dask, Fig. 2."""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import orbits
from orbits import InputError
from orbits.atomic import FLOAT_FORMAT, csv_float_options
from orbits.cli import main
from orbits.survey import (
    BODY_COLUMNS,
    Survey,
    chunk_columns,
    chunk_tables,
    compute,
    compute_chunk,
    derive_orbit_rows,
    load_manifest,
    read_survey,
    search_chunk,
    sha256_file,
    survey_grid,
    write_part,
)
from orbits.survey.tables import arrow_table, read_table


def read_bytes(directory):
    return {
        p.relative_to(directory).as_posix(): p.read_bytes()
        for p in sorted(directory.rglob("part-*"))
    }


def test_chunk_matches_closed_orbits():
    moments = orbits.region_sample(40)
    bodies, orbits_table = compute_chunk(moments, 8, q_max=2, first_id=100)
    assert list(bodies.columns) == list(BODY_COLUMNS)
    assert list(orbits_table.columns) == list(orbits.CATALOG_COLUMNS)
    assert bodies["body"].tolist() == list(range(100, 140))
    for k in (0, 7, 23, 39):
        one = orbits.closed_orbits(moments[k], n_max=8, q_max=2)
        mine = orbits_table[orbits_table.body == 100 + k].reset_index(drop=True)
        np.testing.assert_array_equal(mine["dtheta"], one["dtheta"])
        np.testing.assert_array_equal(mine[["n", "q"]], one[["n", "q"]])
        assert bodies.loc[k, "orbits"] == len(one)
        assert bodies.loc[k, "n_smallest"] == one.loc[one.q == 1, "n"].min()
        value, where = orbits.minimum_phase(moments[k])
        assert bodies.loc[k, "min_total_phase"] == value
    lim = orbits.phase_limits(moments)
    np.testing.assert_array_equal(bodies["limit_theta_zero"], lim.theta_zero)
    # the conjecture on these bodies: the minimum is the smaller end value
    np.testing.assert_allclose(
        bodies["min_total_phase"], np.minimum(lim.theta_zero, lim.theta_half_pi), rtol=1e-13
    )
    assert bodies["min_at_end"].all()


def test_grid_survey_report(tmp_path):
    survey = Survey.grid(tmp_path / "s", 40, 6, chunk=300)
    report = survey.run()
    bodies, table = read_survey(tmp_path / "s")
    assert len(bodies) == len(orbits.region_grid(40)) == report["bodies"]
    assert bodies["body"].is_unique and len(table) == report["orbits"]
    conjecture = report["conjecture_minimum_at_the_ends"]
    assert conjecture["held_on_every_body"] and conjecture["counterexamples"] == []
    assert report["bodies_with_a_two_pi_orbit"] == 0
    assert report["min_total_phase_range"][0] > 2 * np.pi
    assert json.loads((tmp_path / "s" / "report.json").read_text()) == report


def test_report_lists_counterexamples(tmp_path):
    survey = Survey.grid(tmp_path / "s", 12, 3, chunk=50, fmt="csv")
    survey.run()
    part = tmp_path / "s" / "bodies" / "part-00000.csv"
    frame = pd.read_csv(part, **csv_float_options())
    frame.loc[3, "min_at_end"] = False  # pretend one body's minimum is inside
    write_part(frame, part, "csv")
    with pytest.raises(InputError, match="damaged.*part-00000.csv does not match"):
        survey.report()  # the ledger notices the change
    # record the change in the ledger, as a run would have
    survey.ledger.parts["0"]["bodies"]["sha256"] = sha256_file(part)
    survey.ledger.write_manifest()
    report = survey.report()
    assert not report["conjecture_minimum_at_the_ends"]["held_on_every_body"]
    assert [
        row["body"] for row in report["conjecture_minimum_at_the_ends"]["counterexamples"]
    ] == [3]


def test_parquet_and_csv_engines_agree(tmp_path):
    bodies, table = compute_chunk(orbits.region_sample(30), 5)
    for engine in ("arrow", "pandas"):
        write_part(table, tmp_path / f"{engine}.csv", "csv", engine=engine)
        again = pd.read_csv(tmp_path / f"{engine}.csv", **csv_float_options())
        pd.testing.assert_frame_equal(again, table, check_exact=True, check_dtype=False)
    write_part(table, tmp_path / "t.parquet", "parquet")
    pd.testing.assert_frame_equal(pd.read_parquet(tmp_path / "t.parquet"), table, check_exact=True)


def test_write_part_returns_the_hash_of_the_bytes_it_wrote(tmp_path):
    """write_part hashes the part in memory: the digest it returns is the
    file's.  A table gives the same bytes as arrays (what a survey run
    writes, chunk_columns) and as a DataFrame (chunk_tables), compact and
    full layouts alike; pandas reads the part back to the DataFrame, types
    and all (the branch a categorical); CSV through both engines."""
    for columns in ("compact", "all"):
        found = search_chunk(orbits.region_sample(40), 8)
        arrays = chunk_columns(found, 7, columns)
        frames = chunk_tables(found, 7, columns)
        for name, plain, frame in zip(("bodies", "orbits"), arrays, frames, strict=True):
            path = tmp_path / f"{columns}-{name}.parquet"
            digest = write_part(plain, path, "parquet")
            assert digest == sha256_file(path)
            assert write_part(frame, tmp_path / "frame.parquet", "parquet") == digest
            assert path.read_bytes() == (tmp_path / "frame.parquet").read_bytes()
            pd.testing.assert_frame_equal(pd.read_parquet(path), frame, check_exact=True)
            assert pq.read_schema(path).metadata is None  # no pandas metadata
    bodies, table = compute_chunk(orbits.region_sample(20), 5)
    for engine in ("arrow", "pandas"):
        path = tmp_path / f"{engine}.csv"
        assert write_part(table, path, "csv", engine=engine) == sha256_file(path)
    table.to_csv(tmp_path / "plain.csv", index=False, float_format=FLOAT_FORMAT)
    assert (tmp_path / "pandas.csv").read_bytes() == (tmp_path / "plain.csv").read_bytes()


def test_parts_keep_nan_and_types_without_pandas_metadata(tmp_path):
    """Parts are plain Arrow: NaN stays a NaN (never a null), booleans,
    int8 codes and names keep their types, and an empty table is a table."""
    columns = {
        "body": np.array([3, 4, 5], dtype=np.int64),
        "name": ["a", "=b", "é"],
        "x": np.array([np.nan, -0.0, 1.5]),
        "flag": np.array([True, False, True]),
        "branch": np.array([1, 0, 1], dtype=np.int8),
    }
    write_part(columns, tmp_path / "t.parquet", "parquet")
    for table in (columns, {**columns, "x": columns["x"][::-1]}, {"x": columns["x"][::2]}):
        arrow_table(table).validate(full=True)  # buffers Arrow accepts, strided input too
    assert arrow_table({"x": columns["x"][::-1]}).column("x").to_pylist()[0] == 1.5
    arrow = pq.read_table(tmp_path / "t.parquet")
    assert arrow.column("x").null_count == 0
    branch = arrow.schema.field("branch").type
    assert pa.types.is_dictionary(branch) and branch.index_type == pa.int8()
    assert arrow.schema.field("flag").type == pa.bool_()
    assert arrow.column("branch").to_pylist() == ["LAM", "SAM", "LAM"]
    back = pd.read_parquet(tmp_path / "t.parquet")
    assert np.isnan(back["x"][0]) and np.signbit(back["x"][1]) and back["x"][2] == 1.5
    assert back["flag"].tolist() == [True, False, True]
    assert back["branch"].astype(str).tolist() == ["LAM", "SAM", "LAM"]
    assert back["name"].tolist() == ["a", "=b", "é"]
    empty = {name: values[:0] for name, values in columns.items()}
    write_part(empty, tmp_path / "e.parquet", "parquet")
    assert pq.read_table(tmp_path / "e.parquet").schema.equals(arrow.schema)
    bad = {
        "codes outside": {"branch": np.array([2], dtype=np.int8)},
        "integer codes": {"branch": np.array([0.5])},
        "a column is 1-d": {"x": np.zeros((2, 3))},
        "different lengths": {"x": np.zeros(2), "y": np.zeros(3)},
    }
    for message, table in bad.items():
        with pytest.raises(InputError, match=message):
            write_part(table, tmp_path / "b.parquet", "parquet")
    with pytest.raises(InputError, match="not text"):  # not stringified silently
        write_part(pd.DataFrame({"flag": [True, None]}), tmp_path / "o.parquet", "parquet")
    nullable = pd.DataFrame({"n": pd.array([1, None], dtype="Int64")})
    with pytest.raises(InputError, match="missing values"):
        write_part(nullable, tmp_path / "n.parquet", "parquet")
    assert not any((tmp_path / f"{k}.parquet").exists() for k in "bno")


def test_a_survey_run_never_loads_pandas(tmp_path):
    """The survey command makes and writes its default (compact) tables
    without pandas (its import is serial start-up): with pandas made
    unimportable it still runs, Parquet and CSV, and so does a survey of
    named bodies.  (A ``--bodies`` CSV is read, and ``--columns all`` rows
    are made, through pandas.)"""
    guard = (
        "import sys\n"
        "class NoPandas:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name == 'pandas' or name.startswith('pandas.'):\n"
        "            raise ImportError('pandas is not to be loaded by a survey run')\n"
        "sys.meta_path.insert(0, NoPandas())\n"
    )
    command = guard + "from orbits.cli import main\nmain(sys.argv[1:])\n"
    for k, extra in enumerate(([], ["--format", "csv"])):
        out = tmp_path / f"s{k}"
        arguments = ["survey", "--resolution", "12", "--n-max", "5", *extra, "--out", str(out)]
        done = subprocess.run(
            [sys.executable, "-c", command, *arguments],
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert done.returncode == 0, done.stderr[-2000:]
        assert (out / "report.json").is_file()
    named = guard + (
        "from orbits import Body\n"
        "from orbits.survey import Survey\n"
        "bodies = [Body([1, 2, 3], name='phone'), Body([0.1, 1, 1.05], name='rod')]\n"
        "Survey.from_bodies(sys.argv[1], bodies, 6).run()\n"
        "assert 'pandas' not in sys.modules\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", named, str(tmp_path / "named")],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    bodies, _ = read_survey(tmp_path / "named")
    assert bodies["name"].tolist() == ["phone", "rod"]


def test_table_workers_before_any_parallel_kernel():
    # a survey on the GPU asks before any CPU parallel kernel has run: the
    # answer must still be the layer's, not "one chunk at a time"
    code = (
        "import numba\n"
        "from orbits.survey.runner import table_workers\n"
        "workers = table_workers(10, 1, 100)\n"
        "print(numba.threading_layer(), workers)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr[-2000:]
    layer, workers = done.stdout.split()
    if layer in ("omp", "tbb"):
        assert int(workers) >= 1
    else:
        assert int(workers) == 0


def test_other_parameters_are_refused(tmp_path):
    Survey.grid(tmp_path / "s", 20, 4, chunk=100).run()
    with pytest.raises(InputError, match="different parameters.*n_max"):
        Survey.grid(tmp_path / "s", 20, 5, chunk=100).run()
    with pytest.raises(InputError, match="different parameters"):
        Survey.grid(tmp_path / "s", 21, 4, chunk=100).run()
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "notes.txt").write_text("mine")
    with pytest.raises(InputError, match="not a survey directory"):
        Survey.grid(tmp_path / "other", 20, 4).run()


def _ledger_size(directory):
    # finished chunks are those in the manifest's ledger (written atomically
    # after each part); a part file alone may be a chunk killed mid-way
    try:
        return len(load_manifest(directory)["parts"])
    except Exception:
        return 0


def test_resume_after_a_kill(tmp_path):
    # resolution 300: about 90 chunks, so the kill lands mid-run on any machine
    reference = tmp_path / "reference"
    Survey.grid(reference, 300, 6, chunk=400).run()
    target = tmp_path / "killed"
    argv = [
        sys.executable,
        "-m",
        "orbits.cli",
        "survey",
        "--resolution",
        "300",
        "--n-max",
        "6",
        "--chunk",
        "400",
        "--out",
        str(target),
    ]
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 120
    while time.time() < deadline and _ledger_size(target) < 3 and proc.poll() is None:
        time.sleep(0.005)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    finished = _ledger_size(target)
    total = Survey.grid(target, 300, 6, chunk=400).chunks
    assert 3 <= finished < total, "the kill came too late to test a resume"
    # a second run computes only the chunks missing from the ledger
    calls = []
    import orbits.survey.compute as module

    original = module.search_chunk

    def counting(moments, *args, **kwargs):
        calls.append(len(moments))
        return original(moments, *args, **kwargs)

    module.search_chunk = counting
    try:
        Survey.grid(target, 300, 6, chunk=400).run()
    finally:
        module.search_chunk = original
    assert len(calls) == total - finished
    assert read_bytes(target) == read_bytes(reference)  # nothing lost or doubled
    assert not list(target.rglob("*.part"))


def _cluster_survey(cluster, out):
    """The command line of the grid-60 survey (n <= 8, chunks of 500) on ``cluster``."""
    return ["survey", "--resolution", "60", "--n-max", "8", "--chunk", "500"] + [
        "--scheduler",
        cluster.scheduler_address,
        "--out",
        str(out),
    ]


def test_distributed_equals_local(tmp_path):
    distributed = pytest.importorskip("distributed")
    local = tmp_path / "local"
    Survey.grid(local, 60, 8, chunk=500).run()
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        with distributed.Client(cluster) as client:
            Survey.grid(tmp_path / "client", 60, 8, chunk=500).run(scheduler=client)
        # and by address, as --scheduler tcp://host:port does
        code = main(_cluster_survey(cluster, tmp_path / "address"))
        assert code == 0
        # workers whose orbits differ from this process's (another version or
        # edited sources) are refused, not mixed in under this version
        with distributed.Client(cluster) as client:
            client.run(_set_worker_fingerprint, "f" * 64)
            try:
                with pytest.raises(orbits.InputError, match="a dask worker runs orbits"):
                    Survey.grid(tmp_path / "other", 60, 8, chunk=500).run(scheduler=client)
            finally:
                client.run(_set_worker_fingerprint, None)
    assert read_bytes(tmp_path / "client") == read_bytes(local)
    assert read_bytes(tmp_path / "address") == read_bytes(local)
    # the refused run resumes locally to the same files
    Survey.grid(tmp_path / "other", 60, 8, chunk=500).run()
    assert read_bytes(tmp_path / "other") == read_bytes(local)


def test_distributed_fresh_worker_with_threads(tmp_path):
    """A fresh worker process with several threads: its first chunks took
    their lazy imports side by side and met numpy.ma partially initialised
    ("chunk 0 was lost ... has no attribute 'MaskedArray'"; an audit, 2 of 3
    fresh starts with --nthreads 2; 1 of 3 here with 4 threads).  The first
    chunk on a worker now runs alone."""
    distributed = pytest.importorskip("distributed")
    local = tmp_path / "local"
    Survey.grid(local, 60, 8, chunk=50).run()
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=4, processes=True, dashboard_address=None
    ) as cluster:
        with distributed.Client(cluster) as client:
            Survey.grid(tmp_path / "cluster", 60, 8, chunk=50).run(scheduler=client)
    assert read_bytes(tmp_path / "cluster") == read_bytes(local)


def _set_worker_fingerprint(value):
    import orbits._version

    orbits._version._FINGERPRINT = value


def _die_in_chunk(*arguments):
    import os

    os._exit(3)


def test_distributed_lost_chunk_is_one_error_and_resumes(tmp_path, capsys):
    """A worker that dies on a chunk (out of memory, killed): dask gives up
    after its allowed failures (KilledWorker); the run ends with one
    InputError line, exit 2, not a traceback, and a rerun resumes."""
    distributed = pytest.importorskip("distributed")
    import dask

    local = tmp_path / "local"
    Survey.grid(local, 60, 8, chunk=500).run()
    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
        with distributed.LocalCluster(
            n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster:
            with distributed.Client(cluster) as client:
                client.run(_patch_worker_chunk)
            code = main(_cluster_survey(cluster, tmp_path / "lost"))
    err = capsys.readouterr().err
    assert code == 2
    lines = [line for line in err.splitlines() if line.startswith("orbits: error:")]
    assert len(lines) == 1 and "lost on the dask cluster (KilledWorker" in lines[0], err
    assert "rerun the same command to resume" in lines[0]
    assert "Traceback" not in err
    Survey.grid(tmp_path / "lost", 60, 8, chunk=500).run()
    assert read_bytes(tmp_path / "lost") == read_bytes(local)


def _patch_worker_chunk():
    import orbits.survey.runner as runner

    runner._chunk_on_worker = _die_in_chunk


def test_fig2_from_a_survey(tmp_path, capsys):
    survey_dir = tmp_path / "s"
    Survey.grid(survey_dir, 50, 3, chunk=5000).run()
    i1, i2, minimum = survey_grid(survey_dir)
    inside = np.isfinite(minimum)
    assert inside.sum() == len(orbits.region_grid(50))
    from orbits.plotting import limits_field

    np.testing.assert_allclose(minimum[inside], limits_field(i1, i2)[inside], rtol=1e-12)
    assert (
        main(
            [
                "figures",
                "--survey",
                str(survey_dir),
                "--formats",
                "png",
                "--out",
                str(tmp_path / "fig"),
            ]
        )
        == 0
    )
    assert (tmp_path / "fig" / "fig2.png").exists()


def test_cli_survey_and_errors(tmp_path, capsys, monkeypatch):
    import orbits.survey.runner as module

    monkeypatch.setattr(module, "CONNECT_TIMEOUT", 2)
    bodies = tmp_path / "bodies.csv"
    bodies.write_text("name,I1,I2,I3\na,0.26,0.55,0.793662\nb,1,1.7,2.2\n")
    assert (
        main(
            [
                "survey",
                "--bodies",
                str(bodies),
                "--n-max",
                "6",
                "--json",
                "--out",
                str(tmp_path / "s"),
            ]
        )
        == 0
    )
    report = json.loads(capsys.readouterr().out)
    assert report["bodies"] == 2
    for argv, fragment in [
        (["survey", "--n-max", "3", "--out", "x"], "exactly one"),
        (
            ["survey", "--resolution", "10", "--n-max", "0", "--out", "x"],
            "must be an integer >= 1",
        ),
        (
            ["survey", "--resolution", "10", "--n-max", "3", "--format", "xml", "--out", "x"],
            "invalid choice",
        ),
        (
            ["survey", "--resolution", "10", "--n-max", "3", "--out", "/proc/orbits-survey"],
            "cannot create",
        ),
        (
            [
                "survey",
                "--resolution",
                "10",
                "--n-max",
                "3",
                "--scheduler",
                "tcp://127.0.0.1:9",
                "--out",
                str(tmp_path / "dask"),
            ],
            "scheduler",
        ),
        (
            ["figures", "--survey", str(tmp_path / "s"), "--out", str(tmp_path / "f")],
            "grid survey",
        ),
    ]:
        code = main(argv)
        err = capsys.readouterr().err.strip().splitlines()
        assert code == 2 and len(err) == 1 and fragment in err[0], (argv, err)


@pytest.mark.parametrize("failure", ["write", "interrupt"])
def test_a_failure_mid_run_leaves_whole_chunks(tmp_path, monkeypatch, failure):
    """Chunks are made and written by a pool of threads while the next is searched.

    A failing write (the third chunk) or an interrupt while the fourth is
    searched stops the run; every chunk handed to the pool before is still
    written, every chunk in the ledger has both parts with their SHA-256,
    no temporary is left, and a second run completes the survey to the same
    bytes as an uninterrupted one.
    """
    import orbits.survey.compute as module

    reference = tmp_path / "reference"
    Survey.grid(reference, 40, 4, chunk=60).run()
    target = tmp_path / "target"
    original_write = Survey.write_chunk
    original_compute = module.search_chunk
    computed = []

    def failing_write(self, index, bodies, orbits):
        if index == 2:
            raise InputError("cannot write: disk full (simulated)")
        return original_write(self, index, bodies, orbits)

    def interrupted_compute(moments, *args, **kwargs):
        computed.append(1)
        if len(computed) == 4:
            raise KeyboardInterrupt
        return original_compute(moments, *args, **kwargs)

    if failure == "write":
        monkeypatch.setattr(Survey, "write_chunk", failing_write)
        expected = pytest.raises(InputError, match="simulated")
    else:
        monkeypatch.setattr(module, "search_chunk", interrupted_compute)
        expected = pytest.raises(KeyboardInterrupt)
    with expected:
        Survey.grid(target, 40, 4, chunk=60).run()
    ledger = load_manifest(target)["parts"]
    if failure == "write":
        # chunk 3 may have been in the pool beside the failing chunk 2
        assert {"0", "1"} <= set(ledger) <= {"0", "1", "3"}
    else:
        assert sorted(ledger, key=int) == ["0", "1", "2"]
    for entry in ledger.values():
        for table in ("orbits", "bodies"):
            assert sha256_file(target / entry[table]["file"]) == entry[table]["sha256"]
    assert not list(target.rglob("*.part"))
    monkeypatch.undo()
    Survey.grid(target, 40, 4, chunk=60).run()
    assert read_bytes(target) == read_bytes(reference)


def _interrupt_second_chunk(monkeypatch):
    """Ctrl-C while the second chunk is searched (the first is written)."""
    import orbits.survey.compute as module

    original = module.search_chunk
    calls = []

    def interrupted(moments, *args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return original(moments, *args, **kwargs)

    monkeypatch.setattr(module, "search_chunk", interrupted)


@pytest.mark.parametrize("verify", [True, False])
def test_an_interrupted_survey_is_not_read_as_one(tmp_path, monkeypatch, verify):
    """read_survey and read_table refuse a directory with chunks never written.

    ``verify=False`` skips the hashing of the parts, not the check that the
    ledger has every chunk: the bodies and orbits of the chunks written
    would otherwise pass for the survey (their row sums agree).
    """
    _interrupt_second_chunk(monkeypatch)
    target = tmp_path / "interrupted"
    survey = Survey.grid(target, 20, 4, chunk=50)
    with pytest.raises(KeyboardInterrupt):
        survey.run()
    written = load_manifest(target)["parts"]
    assert 1 <= len(written) < survey.chunks
    with pytest.raises(InputError, match="incomplete .*chunk 1 missing"):
        read_survey(target, verify=verify)
    for table in ("bodies", "orbits"):
        with pytest.raises(InputError, match="incomplete"):
            read_table(target, table, verify=verify)
    monkeypatch.undo()
    survey.run()
    bodies, orbits_ = read_survey(target, verify=verify)
    assert len(bodies) == survey.moments.shape[0]
    assert len(orbits_) == int(bodies["orbits"].sum())


def test_a_stopped_survey_command_says_what_it_kept(tmp_path, monkeypatch, capsys):
    # the chunks finished stay (whole, in the ledger) for a rerun to resume:
    # the stop's line says so instead of "no partial output was written"
    _interrupt_second_chunk(monkeypatch)
    out = tmp_path / "stopped"
    argv = ["survey", "--resolution", "20", "--n-max", "4", "--chunk", "50", "--out", str(out)]
    assert main(argv) == 130
    done = len(load_manifest(out)["parts"])
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert last == (
        f"orbits: interrupted; {done} of 4 chunks are written whole in {out} (the survey "
        "is incomplete, and read_survey refuses it): rerun the same command to compute the rest"
    )
    assert 1 <= done < 4
    monkeypatch.undo()
    assert main(argv) == 0
    assert len(read_survey(out)[0]) == 157


def test_survey_warns_of_orbits_left_out_next_to_the_separatrix(tmp_path, capsys):
    # (0.001, 1, 1.001) at n <= 300: 147 levels are reached only closer than
    # |dtheta| = 2.2e-308 to theta_c; orbits catalog warns of them, and so
    # does the survey (it used to say only "1048 closed orbits")
    bodies = tmp_path / "b.csv"
    bodies.write_text("I1,I2,I3\n0.001,1,1.001\n0.3,0.5,0.7\n")
    out = tmp_path / "s"
    argv = ["survey", "--bodies", str(bodies), "--n-max", "300", "--out", str(out)]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert (
        "orbits: warning: 1 of 2 bodies has closed orbits with 2 pi p/q <= 2 pi 300 "
        "closer than |dtheta| = 2.2e-308 to the separatrix"
    ) in err
    table, orbit_rows = read_survey(out)
    assert table["unresolved"].tolist() == [147, 0]
    with pytest.warns(orbits.UnresolvedOrbitsWarning, match="147 closed orbits"):
        expected = orbits.catalog([[0.001, 1, 1.001], [0.3, 0.5, 0.7]], n_max=300)
    assert len(orbit_rows) == len(expected)
    argv = ["survey", "--bodies", str(bodies), "--n-max", "20", "--out", str(tmp_path / "t")]
    assert main(argv) == 0
    assert "warning" not in capsys.readouterr().err


def test_a_stopped_survey_counts_the_chunks_its_manifest_holds(tmp_path, monkeypatch, capsys):
    """A chunk is entered in the ledger in memory, then the manifest is
    written; a stop between the two must not count it (the line said 2 of 4
    chunks were kept, the manifest on disk held 1)."""
    import orbits.survey.runner as runner
    from orbits.survey.ledger import Ledger

    monkeypatch.setattr(runner, "table_workers", lambda *args: 0)  # in the main thread
    original = Ledger.write_manifest

    def stopped_writing(self):
        if len(self.parts) == 2:
            raise KeyboardInterrupt
        return original(self)

    monkeypatch.setattr(Ledger, "write_manifest", stopped_writing)
    out = tmp_path / "stopped"
    argv = ["survey", "--resolution", "20", "--n-max", "4", "--chunk", "50", "--out", str(out)]
    assert main(argv) == 130
    assert list(load_manifest(out)["parts"]) == ["0"]
    assert "interrupted; 1 of 4 chunks are written whole" in capsys.readouterr().err


def test_a_survey_stopped_after_its_report_says_it_is_whole(tmp_path, monkeypatch, capsys):
    # a stop while the summary is printed: the survey and report.json are
    # complete, and the line says so (it said "no partial output was written")
    import orbits.cli.survey as command

    def stopped(*args):
        raise KeyboardInterrupt

    monkeypatch.setattr(command, "_print_report", stopped)
    out = tmp_path / "whole"
    argv = ["survey", "--resolution", "20", "--n-max", "4", "--out", str(out)]
    assert main(argv) == 130
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert last == "orbits: interrupted as the run ended; its output was written whole"
    assert len(read_survey(out)[0]) == 157


@pytest.mark.parametrize("fmt", ["parquet", "csv"])
@pytest.mark.parametrize("columns", ["compact", "all"])
def test_run_report_equals_the_report_read_back(tmp_path, fmt, columns, monkeypatch):
    # a run reports from the summaries of the chunks it wrote (it reads no
    # part back); read back from the verified parts, the report is the same
    from orbits.survey import report as report_module

    def no_reading(*args, **kwargs):
        raise AssertionError("the run read its parts back")

    survey = Survey.grid(tmp_path / "s", 30, 5, chunk=70, fmt=fmt, columns=columns)
    with monkeypatch.context() as patch:
        patch.setattr(report_module, "read_table", no_reading)
        report = survey.run()
    assert survey.chunks > 3
    written = (tmp_path / "s" / "report.json").read_bytes()
    again = survey.report()  # reads every bodies part, checks the SHA-256s
    assert again == report
    assert (tmp_path / "s" / "report.json").read_bytes() == written
    assert report["bodies"] == len(orbits.region_grid(30))


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
def test_a_full_stdout_after_a_whole_survey_is_a_warning(tmp_path):
    """`orbits survey ... >/dev/full` wrote the whole survey, then ended with
    exit 2 ("no file created or changed"): its summary is report.json."""
    out = tmp_path / "s"
    argv = [sys.executable, "-m", "orbits", "survey", "--resolution", "12", "--n-max", "3"]
    with open("/dev/full", "w") as full:
        done = subprocess.run([*argv, "--out", str(out)], stdout=full, stderr=subprocess.PIPE)
    err = done.stderr.decode().strip().splitlines()
    assert done.returncode == 0, err
    assert err[-1] == (
        "orbits: warning: the summary could not be printed (No space left on device); "
        f"the survey in {out} is complete and its report.json holds the summary"
    )
    assert main(["survey", "--check", str(out)]) == 0


def test_a_refused_rerun_is_one_line_without_the_skipped_rows(tmp_path, capsys):
    """--skip-invalid into a directory of another survey's parameters: the
    skipped row's warning came before the refusal (two lines)."""
    bodies = tmp_path / "b.csv"
    bodies.write_text("I1,I2,I3\n0.26,0.55,0.793662\n1,2,9\n")
    argv = ["survey", "--bodies", str(bodies), "--skip-invalid", "--n-max", "3"]
    assert main([*argv, "--out", str(tmp_path / "s")]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert sum("orbits: warning: skipped" in line for line in err) == 1  # reported on a run
    assert main([*argv, "--format", "csv", "--out", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        f"orbits: error: {tmp_path / 's'} holds a survey with different parameters "
        "(format); use a new directory"
    ]


def test_chunk_summaries_combine_as_the_whole_table():
    from orbits.survey.report import bodies_summary, combined_summary

    bodies, _ = compute_chunk(orbits.region_sample(60), 6, first_id=7)
    # counterexamples in two chunks, a 2 pi orbit and unresolved bodies,
    # so that every figure of the summary is exercised
    bodies.loc[[3, 40, 41], "min_at_end"] = False
    # a minimum below 2 pi (inside a branch): a spin with Delta alpha = 2 pi
    bodies.loc[[5, 50], "min_total_phase"] = [6.0, 2 * np.pi * (1 - 1e-15)]
    bodies.loc[[2, 33, 59], "unresolved"] = [1, 2, 1]
    bodies.loc[12, "min_total_phase"] = np.nan  # skipped, as on the whole column
    whole = bodies_summary(bodies)
    parts = [bodies.iloc[:25], bodies.iloc[25:26], bodies.iloc[26:]]
    combined = combined_summary([bodies_summary(part) for part in parts])
    assert combined == whole
    assert [row["body"] for row in whole["counterexamples"]] == [10, 47, 48]
    assert (whole["two_pi"], whole["unresolved"], whole["bodies"]) == (2, 3, 60)
    finite = bodies["min_total_phase"].dropna()
    assert (whole["min"], whole["max"]) == (finite.min(), finite.max())


def test_a_resumed_run_reports_on_every_chunk(tmp_path):
    # chunks written by an earlier run have no summary in this one: the
    # report reads the bodies table and still counts every body
    survey = Survey.grid(tmp_path / "s", 30, 5, chunk=70)
    first = survey.run()
    (tmp_path / "s" / "bodies" / "part-00002.parquet").unlink()
    again = Survey.grid(tmp_path / "s", 30, 5, chunk=70)
    assert again.run() == first


@pytest.mark.parametrize("kind", ["directory", "fifo"])
def test_a_part_no_file_can_replace_is_refused_before_the_ledger_changes(tmp_path, capsys, kind):
    """A part's name held by a directory: the rerun dropped the chunk from
    the manifest, computed, and only then failed at the chunk (exit 2)."""
    survey = Survey.grid(tmp_path / "s", 30, 5, chunk=70)
    survey.run()
    manifest = (tmp_path / "s" / "manifest.json").read_bytes()
    part = tmp_path / "s" / "orbits" / "part-00002.parquet"
    part.unlink()
    if kind == "directory":
        part.mkdir()
    else:
        os.mkfifo(part)
    argv = ["survey", "--resolution", "30", "--n-max", "5", "--chunk", "70"]
    assert main(argv + ["--out", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    what = "a directory" if kind == "directory" else "not a file"
    assert err == [
        f"orbits: error: {part} is {what}; a survey part is only ever replaced by a "
        "regular file: remove it and run the survey again"
    ]
    assert (tmp_path / "s" / "manifest.json").read_bytes() == manifest
    part.rmdir() if kind == "directory" else part.unlink()
    assert main(argv + ["--out", str(tmp_path / "s")]) == 0
    assert Survey.grid(tmp_path / "s", 30, 5, chunk=70).run() == survey.run()


_SMALL = ["survey", "--resolution", "6", "--n-max", "3", "--format", "csv", "--chunk", "3"]


def _small_survey(target, capsys):
    assert main(_SMALL + ["--out", str(target)]) == 0
    capsys.readouterr()
    return json.loads((target / "report.json").read_text())


@pytest.mark.parametrize("damage", ["edited", "deleted", "not-json", "directory"])
def test_check_verifies_the_report(tmp_path, capsys, damage):
    """--check recomputes report.json from the verified parts; a rerun rewrites it."""
    from orbits.survey import check_survey

    target = tmp_path / "s"
    report = _small_survey(target, capsys)
    assert check_survey(target)["report"] == "ok"
    path = target / "report.json"
    if damage == "edited":
        edited = dict(report, bodies_with_a_two_pi_orbit=7)
        path.write_text(json.dumps(edited, indent=2))
        problem = "report.json differs from the report of the verified parts (bodies_with_a_two_pi_orbit)"
    elif damage == "deleted":
        path.unlink()
        problem = "report.json is missing"
    elif damage == "directory":  # was exit 2, "Is a directory" (unreadable, not damage)
        path.unlink()
        path.mkdir()
        problem = "report.json is a directory, not the report; remove it"
    else:
        path.write_text("{")
        problem = "report.json is not valid JSON"
    status = check_survey(target)
    assert not status["complete"] and status["verified"] == status["chunks"] == 6
    assert status["report"].startswith(problem)
    assert status["damaged"] == [status["report"]]
    assert "rerun the survey command to rewrite it" in status["report"]
    assert main(["survey", "--check", str(target)]) == 1
    out = capsys.readouterr().out
    assert "DAMAGED" in out and problem in out and "every part" not in out
    if damage == "directory":
        path.rmdir()  # as the message says
    # the rerun recomputes nothing and rewrites the report
    assert main(_SMALL + ["--out", str(target)]) == 0
    assert "(0 computed now" in capsys.readouterr().out
    assert json.loads(path.read_text()) == report
    assert main(["survey", "--check", str(target), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["report"] == "ok"


def test_a_reindented_report_still_verifies(tmp_path, capsys):
    from orbits.survey import check_survey

    target = tmp_path / "s"
    report = _small_survey(target, capsys)
    (target / "report.json").write_text(json.dumps(report, indent=7, sort_keys=True))
    assert check_survey(target)["complete"]


def test_check_exit_codes_damage_and_unreadable(tmp_path, capsys):
    """docs/cli.md: 1 damaged parts or report; 2 a directory that cannot be checked."""
    target = tmp_path / "s"
    _small_survey(target, capsys)
    manifest = target / "manifest.json"
    original = manifest.read_text()
    # a damaged part: 1, listed
    part = target / "bodies" / "part-00001.csv"
    part.write_text(part.read_text() + "\n")
    assert main(["survey", "--check", str(target)]) == 1
    assert "damaged chunk 1: bodies/part-00001.csv does not match" in capsys.readouterr().out
    # a manifest edited by hand cannot be trusted: nothing can be checked, 2, one line
    document = json.loads(original)
    document["parts"]["0"]["orbits"]["rows"] = 0
    manifest.write_text(json.dumps(document))
    assert main(["survey", "--check", str(target)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and "does not match its own SHA-256" in err[0]
    # the documentation says the same
    from pathlib import Path

    docs = (Path(__file__).resolve().parents[1] / "docs" / "cli.md").read_text()
    assert "Exit 0 complete; 1 damaged or incomplete (parts or\nreport)" in docs
    assert "does not match its own SHA-256 (its ledger cannot be\ntrusted" in docs


@pytest.mark.parametrize("trailing", ["", "/"])
def test_an_out_that_is_a_link_is_refused(tmp_path, capsys, trailing):
    """--out (and Survey(out_dir)) naming a symbolic link: exit 2 before anything is written."""
    import os

    real = tmp_path / "real"
    _small_survey(real, capsys)
    link = tmp_path / "link"
    os.symlink(real, link)
    before = read_bytes(real)
    manifest = (real / "manifest.json").read_bytes()
    report = (real / "report.json").read_bytes()
    # the same survey (it would resume there) and another one (it would be refused there)
    for argv in (_SMALL, _SMALL[:4] + ["4"] + _SMALL[5:]):
        assert main(argv + ["--out", str(link) + trailing]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "is a symbolic link; orbits never writes through a link" in err[0]
    with pytest.raises(InputError, match="is a symbolic link"):
        Survey.grid(link, 6, 3, fmt="csv", chunk=3)
    # a link to a missing directory would create it: refused too
    dangling = tmp_path / "dangling"
    os.symlink(tmp_path / "nowhere", dangling)
    assert main(_SMALL + ["--out", str(dangling)]) == 2
    assert not (tmp_path / "nowhere").exists()
    assert read_bytes(real) == before
    assert (real / "manifest.json").read_bytes() == manifest
    assert (real / "report.json").read_bytes() == report
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dangling", "link", "real"]


def test_a_scheduler_of_the_wrong_type_is_said_so_at_once(tmp_path):
    """Not 'cannot reach the dask scheduler at 123 within 10 s'."""
    survey = Survey.grid(tmp_path / "s", 5, 3)
    with pytest.raises(orbits.ArgumentTypeError, match="got int"):
        survey.run(scheduler=123)
    assert not (tmp_path / "s").exists()


def test_a_rerun_whose_file_skipped_other_rows_is_refused(tmp_path, capsys):
    """The same bodies from a file that skipped other rows: the rerun was
    accepted and rewrote report.json but not the manifest (--check: damaged)."""
    first, second = tmp_path / "a.csv", tmp_path / "c.csv"
    first.write_text("I1,I2,I3\n1,2,2.5\n1,1,2\n2,3,4\n")  # row 2 symmetric: skipped
    second.write_text("I1,I2,I3\n1,2,2.5\n2,3,4\n")
    out = str(tmp_path / "s")
    assert (
        main(["survey", "--bodies", str(first), "--skip-invalid", "--n-max", "4", "--out", out])
        == 0
    )
    before = {p.name: p.read_bytes() for p in (tmp_path / "s").iterdir() if p.is_file()}
    capsys.readouterr()
    assert main(["survey", "--bodies", str(second), "--n-max", "4", "--out", out]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"orbits: error: {out} holds a survey whose bodies file skipped other rows "
        "(1 there, 0 now); use a new directory"
    ]
    assert before == {p.name: p.read_bytes() for p in (tmp_path / "s").iterdir() if p.is_file()}
    assert main(["survey", "--check", out]) == 0


def test_a_manifest_edited_down_to_format_2_is_refused(tmp_path):
    """Format 2 has no checksum: "orbits_survey": 2 switched the manifest's
    own SHA-256 off, and any further edit (n_max) passed --check."""
    Survey.grid(tmp_path / "s", 20, 4, chunk=100).run()
    manifest = tmp_path / "s" / "manifest.json"
    text = manifest.read_text()
    manifest.write_text(text.replace('"orbits_survey": 3', '"orbits_survey": 2'))
    with pytest.raises(InputError, match="says format 2 but carries a later format's keys"):
        read_survey(tmp_path / "s")


def test_names_utf8_cannot_hold_are_refused_before_anything_is_written(tmp_path):
    with pytest.raises(InputError, match="lone surrogate"):
        Survey.from_bodies(tmp_path / "s", [[1.0, 2.0, 2.5]], 3, names=["a\ud800"]).run()
    assert not (tmp_path / "s").exists()


def test_names_of_some_bodies_are_kept(tmp_path):
    """One named Body among moments kept no name column at all, silently."""
    named = orbits.Body((0.26, 0.55, 0.793662), name="x")
    Survey.from_bodies(tmp_path / "s", [named, [2.0, 3.0, 4.0]], 3).run()
    bodies, _ = read_survey(tmp_path / "s")
    assert bodies["name"].tolist() == ["x", ""]
    Survey.from_bodies(tmp_path / "t", [[2.0, 3.0, 4.0], orbits.Body((1.0, 2.0, 2.5))], 3).run()
    assert "name" not in read_survey(tmp_path / "t")[0].columns  # no name given: no column
    # a name that is falsy but given (rows of DataFrame.iterrows() are named by
    # their index labels, the first 0) is kept
    rows = pd.DataFrame({"I1": [0.3, 0.31], "I2": [0.5, 0.5], "I3": [0.7, 0.7]}).iterrows()
    assert Survey.from_bodies(tmp_path / "u", [row for _, row in rows], 2).names == ["0", "1"]


def test_min_theta_stays_in_the_quadrant(tmp_path):
    """theta_c + (pi/2 - theta_c) rounded 1 ulp above pi/2 for some bodies."""
    Survey.grid(tmp_path / "s", 40, 3).run()
    bodies, _ = read_survey(tmp_path / "s")
    assert bodies["min_theta"].between(0.0, 0.5 * np.pi).all()
    assert (bodies["min_theta"] == 0.5 * np.pi).any()


def test_a_grid_into_a_directory_it_cannot_use_is_one_line(tmp_path, capsys):
    """The grid's estimate ("estimated 10 s ...; working...") came first and
    the grid was built, then the directory was refused: two lines."""
    (tmp_path / "file").write_text("x")
    argv = ["survey", "--resolution", "150", "--n-max", "10", "--chunk", "10"]
    assert main([*argv, "--out", str(tmp_path / "file")]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"orbits: error: {tmp_path / 'file'} exists and is not a directory"
    ]
    Survey.grid(tmp_path / "s", 150, 3, chunk=20_000).run()
    assert main([*argv, "--out", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "different parameters (chunk, n_max)" in err[0], err


def test_table_workers_where_no_threading_layer_loads(monkeypatch):
    """NUMBA_THREADING_LAYER=tbb without tbb: a ValueError traceback, where
    one chunk at a time (0) is the answer."""
    import numba

    from orbits.core import tasks
    from orbits.survey import runner

    def no_layer(*args):
        raise ValueError("No threading layer could be loaded.")

    monkeypatch.setattr(numba, "threading_layer", no_layer)
    monkeypatch.setattr(tasks, "start_threads", no_layer)
    assert runner.table_workers(10, 1, 100) == 0


# ------------------------------------------------------------------------
# Each test below kills a mutant of orbits/survey or core/rows that passed
# the suite (a mutation audit, 2026-11-29: 53 mutants, 18 survivors that
# changed an output or a report).


def _overflow_rows(moments, levels, capacity):
    from orbits.core import search as K

    n = len(moments)
    info = np.empty((n, K.INFO_SIZE))
    br = np.empty((n, capacity), np.int8)
    le = np.empty((n, capacity), np.int64)
    off = np.empty((n, capacity))
    found = np.empty(n, np.int64)
    K.search_many(moments, levels, br, le, off, found, info)
    return found, compute._flatten(moments, levels, br, le, off, found, info)


def test_overflowed_bodies_are_searched_again_to_the_same_rows():  # C4 C5 C6
    """Bodies whose roots overflow their row are searched again (compute._flatten):
    the same rows, in dtheta order, with their branch (no test reached it)."""
    from orbits.bodies import unit_moments
    from orbits.search import phase_levels, searched

    moments = np.ascontiguousarray(unit_moments(orbits.region_sample(6))[0]).reshape(-1, 3)
    p, q, lv = phase_levels(6, 1)
    levels = np.ascontiguousarray(lv[np.flatnonzero(searched(p, q))])
    _, good = _overflow_rows(moments, levels, 2 * levels.size + 8)
    found, small = _overflow_rows(moments, levels, 3)
    assert (found < 0).sum() == 4 and len(small[0]) == 32
    for a, b in zip(good, small):
        np.testing.assert_array_equal(a, b)


def test_min_at_end_tolerances_of_the_survey():  # C8 C9
    """min_at_end is True only within the survey's own end tolerances."""
    from orbits.core import search as K

    found = compute.search_chunk(np.array([[0.3, 0.6, 0.9]] * 2), 6)
    i1, i2, i3 = found.moments[0]
    end = min(
        2 * np.pi * np.sqrt(i1 * i2 / ((i3 - i2) * (i3 - i1))),
        2 * np.pi * np.sqrt(i2 * i3 / ((i2 - i1) * (i3 - i1))),
    )
    info = found.info.copy()
    w = info[:, K.INFO_WIDTH_SAM]
    info[:, K.INFO_MIN_SAM] = [end, end * (1 - 1e-9)]  # at the end value / 1e-9 below it
    info[:, K.INFO_MIN_AT_SAM] = [-(w[0] - 1e-7), -w[1]]  # 1e-7 rad inside / at the end
    info[:, K.INFO_MIN_LAM] = np.inf
    found.info = info
    bodies, _ = compute.chunk_columns(found, 0, "compact")
    assert bodies["min_at_end"].tolist() == [False, False]


def test_estimate_counts_a_partial_last_chunk():  # C10
    """The estimate counts the last, partial chunk: 15 bodies in chunks of 10
    are two chunks, as 20 are (the per-body terms cancel in each difference,
    leaving the cost of a second chunk)."""

    def seconds(bodies, chunk):
        return compute.survey_estimate(bodies, 3, 1, chunk)[1]

    partial = seconds(15, 10) - seconds(15, 15)
    whole = seconds(20, 10) - seconds(20, 20)
    assert whole > 0.0 and partial == pytest.approx(whole, rel=1e-12)


def test_the_advised_chunk_fits(monkeypatch):  # C11
    """The --chunk a refusal advises fits the memory budget; one more does not."""
    budget = compute.survey_estimate(1000, 30, 1, 1000)[0] * 0.5
    monkeypatch.setattr(compute, "memory_budget", lambda: budget)
    with pytest.raises(InputError, match=r"use --chunk 499 or less"):
        compute.check_survey_bounds(1000, 30, 1, 1000)
    assert (
        compute.survey_estimate(499, 30, 1, 499)[0]
        <= budget
        < compute.survey_estimate(500, 30, 1, 500)[0]
    )


def test_a_forged_branch_label_is_damage(tmp_path):  # C12
    """A branch label that is not the branch of its dtheta is refused on read."""
    s = Survey.grid(tmp_path / "s", 10, 4, chunk=1000, fmt="csv")
    s.run()
    part = tmp_path / "s" / "orbits" / "part-00000.csv"
    f = pd.read_csv(part)
    f.loc[0, "branch"] = "LAM" if f.loc[0, "branch"] == "SAM" else "SAM"
    write_part(f, part, "csv")
    s.ledger.parts["0"]["orbits"]["sha256"] = sha256_file(part)
    s.ledger.write_manifest()
    with pytest.raises(InputError, match="branch is not the branch of its dtheta"):
        read_survey(tmp_path / "s")


def test_a_row_of_the_next_chunks_body_is_an_input_error():  # C13
    """An orbit row of a body outside the chunk is an InputError, not an IndexError."""
    unit = np.array([[0.3, 0.6, 0.9]]) / np.linalg.norm([0.3, 0.6, 0.9])
    row = pd.DataFrame(
        {
            "body": [1],
            "branch": pd.Categorical(["SAM"], ["SAM", "LAM"]),
            "n": [4],
            "q": [1],
            "dtheta": [0.0],
        }
    )
    with pytest.raises(InputError, match="not orbits of the survey"):
        derive_orbit_rows(row, unit, 0, 4, 1)


def test_names_follow_their_bodies_across_chunks(tmp_path):  # U1
    """Each chunk's names are its own bodies' names."""
    bs = [orbits.Body((x, 0.6, 0.8), name=n) for x, n in ((0.3, "a"), (0.4, "b"), (0.5, "c"))]
    Survey.from_bodies(tmp_path / "s", bs, 3, chunk=1).run()
    assert read_survey(tmp_path / "s")[0]["name"].tolist() == ["a", "b", "c"]


def test_local_progress_counts_bodies(tmp_path):  # U4
    """Local progress counts bodies, not orbits."""
    seen = []
    Survey.grid(tmp_path / "s", 12, 3, chunk=20).run(progress=seen.append)
    assert seen and sum(seen) == 56


def test_distributed_keeps_columns_all_and_counts_bodies(tmp_path):  # U3 U5
    """The dask path writes columns="all" as the local one, byte for byte, and
    its progress counts bodies (it wrote compact parts under an "all" manifest)."""
    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(
            n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
        ) as cl,
        distributed.Client(cl) as c,
    ):
        seen = []
        Survey.grid(tmp_path / "d", 12, 3, chunk=20, columns="all").run(
            scheduler=c, progress=seen.append
        )
    Survey.grid(tmp_path / "l", 12, 3, chunk=20, columns="all").run()
    assert sum(seen) == 56
    for t in ("bodies", "orbits"):
        assert (tmp_path / "d" / t / "part-00000.parquet").read_bytes() == (
            tmp_path / "l" / t / "part-00000.parquet"
        ).read_bytes()
    assert len(read_survey(tmp_path / "d")[1].columns) == 20


def test_table_workers_leave_room_for_the_chunk_being_searched(monkeypatch):  # U8
    """The table workers leave memory for the chunk being searched."""
    import orbits.limits
    from orbits.survey.runner import table_workers

    per_chunk = compute.survey_estimate(50, 6, 1, 50)[0] / 2
    compute.search_chunk(np.array([[0.3, 0.6, 0.8]]), 3)  # a parallel kernel has run
    monkeypatch.setattr(orbits.limits, "memory_budget", lambda: 2.5 * per_chunk)
    assert table_workers(6, 1, 50) in (0, 1)


def test_more_than_ten_chunks_read_in_order(tmp_path):  # T1
    """Chunks 10 and 11 are read after chunk 2 (numeric, not text, order)."""
    Survey.grid(tmp_path / "s", 12, 3, chunk=5).run()
    bodies, table = read_survey(tmp_path / "s")
    assert bodies["body"].tolist() == list(range(56))
    assert table["body"].is_monotonic_increasing


def test_csv_bodies_keep_integer_columns(tmp_path):  # T3
    """A CSV survey's integer body columns read back as int64."""
    Survey.grid(tmp_path / "s", 8, 3, fmt="csv").run()
    bodies, _ = read_survey(tmp_path / "s")
    for name in ("body", "orbits", "n_smallest", "n_largest", "unresolved"):
        assert bodies[name].dtype == np.int64, name


def _one_csv_chunk(tmp_path):
    s = Survey.grid(tmp_path / "s", 10, 3, chunk=1000, fmt="csv")
    s.run()
    return s, tmp_path / "s" / "orbits" / "part-00000.csv"


def test_unverified_read_refuses_orbits_out_of_body_order(tmp_path):  # T6
    """verify=False still refuses orbit rows out of their bodies' order."""
    s, part = _one_csv_chunk(tmp_path)
    lines = part.read_bytes().splitlines(keepends=True)
    body = [line.split(b",")[0] for line in lines]
    k = next(i for i in range(2, len(lines)) if body[i] != body[i - 1])
    lines[k - 1], lines[k] = lines[k], lines[k - 1]
    part.write_bytes(b"".join(lines))
    with pytest.raises(InputError, match="not of the chunk's bodies"):
        read_survey(tmp_path / "s", verify=False)


def test_unverified_read_refuses_a_missing_orbit_row(tmp_path):  # T7
    """verify=False still refuses a chunk whose orbit rows miss one."""
    s, part = _one_csv_chunk(tmp_path)
    part.write_bytes(b"".join(part.read_bytes().splitlines(keepends=True)[:-1]))
    s.ledger.parts["0"]["orbits"]["rows"] -= 1
    s.ledger.write_manifest()
    with pytest.raises(InputError, match="93 orbit rows, but the bodies table counts 94"):
        read_survey(tmp_path / "s", verify=False)


def test_a_forged_row_count_is_repaired_by_a_rerun(tmp_path):  # L3
    """A ledger row count that is not the part's is damage, and a rerun repairs it."""
    from orbits.survey.ledger import check_parts

    s = Survey.grid(tmp_path / "s", 10, 3, chunk=1000)
    s.run()
    s.ledger.parts["0"]["orbits"]["rows"] += 1
    s.ledger.write_manifest()
    assert check_parts(tmp_path / "s")["damaged"] == [
        "chunk 0: orbits/part-00000.parquet has 94 rows, the ledger says 95"
    ]
    Survey.grid(tmp_path / "s", 10, 3, chunk=1000).run()
    assert len(read_survey(tmp_path / "s")[1]) == 94


def test_a_bodies_part_short_of_its_chunk_is_damage(tmp_path):  # L8
    """A bodies part with fewer rows than its chunk's bodies is damage."""
    from orbits.survey.ledger import check_parts

    s, _ = _one_csv_chunk(tmp_path)
    bp = tmp_path / "s" / "bodies" / "part-00000.csv"
    bp.write_bytes(b"".join(bp.read_bytes().splitlines(keepends=True)[:-1]))
    e = s.ledger.parts["0"]["bodies"]
    e["rows"] -= 1
    e["sha256"] = sha256_file(bp)
    s.ledger.write_manifest()
    assert check_parts(tmp_path / "s")["damaged"] == [
        "chunk 0: bodies/part-00000.csv: 38 rows for 39 bodies"
    ]


def test_a_flat_body_at_exactly_two_pi_is_no_two_pi_orbit(tmp_path):  # P1
    """A minimum of exactly 2 pi (a flat body) is no 2 pi orbit in the report."""
    s = Survey.from_bodies(tmp_path / "s", [[0.3, 0.6, 0.9], [1.0, 1.7, 2.3]], 4)
    report = s.run()
    # 2 pi exactly here (the raw minimum rounds 4 ulps below and is clamped)
    assert abs(read_survey(tmp_path / "s")[0]["min_total_phase"][0] - 2 * np.pi) <= 8 * np.spacing(
        2 * np.pi
    )
    assert report["bodies_with_a_two_pi_orbit"] == 0


def test_report_combines_chunk_summaries_in_chunk_order(tmp_path):  # P3
    """The report's counterexamples come in chunk order, not in arrival order."""
    from orbits.survey.report import bodies_summary, build_report

    Survey.grid(tmp_path / "s", 12, 3, chunk=30).run()

    def one(body):
        return bodies_summary(
            {
                "min_at_end": np.array([False]),
                "min_total_phase": np.array([7.0]),
                "orbits": np.array([1]),
                "unresolved": np.array([0]),
                "body": np.array([body]),
                "I1": np.array([0.3]),
                "I2": np.array([0.6]),
                "I3": np.array([0.7]),
                "min_theta": np.array([1.0]),
            }
        )

    report = build_report(tmp_path / "s", 3, 1, 0, verify=False, summaries={1: one(40), 0: one(3)})
    assert [r["body"] for r in report["conjecture_minimum_at_the_ends"]["counterexamples"]] == [
        3,
        40,
    ]
