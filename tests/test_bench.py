"""``orbits bench``: the under-load check runs, reports, and cleans up.

No timing is asserted (the machine is shared); what is tested is that each
row is re-timed beside a CPU-bound child, that the child is stopped, and
that the table prints the check.
"""

import contextlib
import importlib.util
import inspect
import math
import os
import signal
import subprocess
import sys
import time
import types
from pathlib import Path

import numpy as np
import pytest

from orbits import bench


def test_load_check_times_each_row_and_stops_the_busy_process(monkeypatch):
    started = []
    real = bench._busy_process

    def spy():
        process = real()
        started.append(process)
        return process

    monkeypatch.setattr(bench, "_busy_process", spy)
    calls = []
    rows = [
        _row(task="a", _ours=(lambda: calls.append("a") or sum(range(20000)), 5)),
        _row(task="no task of its own", ours_s=1.0, baseline_s=math.nan, speedup=math.nan),
    ]
    bench.load_check(rows)
    assert len(started) == 1 and started[0].poll() is not None  # stopped
    load = rows[0]["load"]
    assert set(load) == {"idle_s", "loaded_s", "slowdown", "holds", "runs"}
    assert load["runs"] == 5
    assert load["slowdown"] == load["loaded_s"] / load["idle_s"]
    assert load["holds"] == (load["slowdown"] <= bench.LOAD_LIMIT)
    assert len(calls) == 2 * (1 + 5)  # warm-up + 5, idle and loaded
    assert "_ours" not in rows[0] and "load" not in rows[1]
    text = bench.format_table(
        {
            "machine": _machine(),
            "results": rows,
        }
    )
    assert "under-load check:" in text and "of 1 rows hold within 2x" in text


def test_load_check_stops_the_busy_process_on_error(monkeypatch):
    started = []
    real = bench._busy_process
    monkeypatch.setattr(bench, "_busy_process", lambda: started.append(real()) or started[-1])
    state = {"n": 0}

    def fails_when_loaded():
        state["n"] += 1
        if state["n"] > 2:
            raise KeyboardInterrupt

    rows = [{"task": "x", "_ours": (fails_when_loaded, 1)}]
    try:
        bench.load_check(rows)
    except KeyboardInterrupt:
        pass
    assert len(started) == 1 and started[0].poll() is not None


def _running(pid):
    """Whether process ``pid`` exists and is not a zombie (Linux /proc)."""
    try:
        with open(f"/proc/{pid}/stat") as stat:
            state = stat.read().rpartition(")")[2].split()[0]
    except (FileNotFoundError, ProcessLookupError, IndexError):
        return False
    return state not in ("Z", "X")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_the_busy_process_ends_when_the_bench_is_killed():
    """A bench killed with SIGKILL during the under-load check left its busy
    child spinning forever (parent pid 1, one core at 100%)."""
    bench_process = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import sys, time\n"
            "from orbits import bench\n"
            "print(bench._busy_process().pid, flush=True)\n"
            "time.sleep(600)\n",
        ],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        text=True,
    )
    busy = None
    try:
        busy = int(bench_process.stdout.readline())
        time.sleep(0.5)
        assert _running(busy), "the busy child ended while its parent lived"
        bench_process.send_signal(signal.SIGKILL)
        bench_process.wait(timeout=30)
        deadline = time.monotonic() + 10
        while _running(busy) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not _running(busy), "the busy child outlived its parent"
    finally:
        bench_process.kill()
        bench_process.wait(timeout=30)
        bench_process.stdout.close()
        if busy is not None and _running(busy):
            os.kill(busy, signal.SIGKILL)


def test_bench_device_cuda_without_a_gpu_is_one_line(capsys):
    """``orbits bench --device cuda`` with no usable GPU: exit 2, one line, no timing."""
    from orbits.cli import main
    from orbits.device import cuda_kernels
    from orbits.errors import DeviceError

    try:
        cuda_kernels()
    except DeviceError:
        pass
    else:
        pytest.skip("a GPU is usable here")
    assert main(["bench", "--device", "cuda", "--only", "cuda_phase"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("orbits: error: "), err
    # the CPU rows are not GPU rows: the names are checked against the device's table
    assert main(["bench", "--device", "cuda", "--only", "phase"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "known: cuda_phase, cuda_search" in err[0], err


def test_amdahl_bound():
    # 1 s serial of a 4 s run: two CPUs give at most 4 / (1 + 3/2) = 1.6x
    assert bench.amdahl_bound(4.0, 1.0, 2) == pytest.approx(1.6, rel=1e-15)
    assert bench.amdahl_bound(4.0, 1.0, 1) == pytest.approx(1.0, rel=1e-15)
    assert bench.amdahl_bound(4.0, 0.0, 16) == pytest.approx(16.0, rel=1e-15)
    # no parallel part (a noisy fixed cost above the run): no speed-up
    assert bench.amdahl_bound(1.0, 1.2, 2) == 1.0


def test_search_scaling_row_counts_the_grid():
    from orbits.bodies import region_grid

    row = bench.bench_search_scaling(resolution=12, n_max=5, repeats=1)
    bodies = len(region_grid(12))
    assert row["bodies_per_s"] == pytest.approx(bodies / row["ours_s"], rel=1e-12)
    assert row["ours_s"] > 0 and row["baseline_s"] > 0
    assert row["speedup"] == pytest.approx(row["baseline_s"] / row["ours_s"], rel=1e-12)
    assert f"{bodies} bodies" in row["note"]


# ------------------------------------------------------------------ probe10 fixes
def _strict_json(text):
    """json.loads that refuses NaN and Infinity (as JavaScript's JSON.parse does)."""
    import json

    def refuse(constant):
        raise ValueError(f"not JSON: {constant}")

    return json.loads(text, parse_constant=refuse)


def _row(**extra):
    """A report row with placeholder figures; ``extra`` sets or adds fields."""
    row = {
        "task": "a task",
        "timed": "t",
        "ours_s": 1e-3,
        "baseline": "b",
        "baseline_s": 2e-3,
        "speedup": 2.0,
        "note": "n",
    }
    row.update(extra)
    return row


def _machine():
    return {
        "cpus_usable": 2,
        "cpu_count": 2,
        "numba_threads": 2,
        "python": "3",
        "numpy": "2",
        "scipy": "1",
        "numba": "0",
    }


def _one_line_error(capsys, *fragments):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("orbits: error: "), err
    for fragment in fragments:
        assert fragment in err[0], err
    return err[0]


@pytest.fixture
def restore_threads(monkeypatch):
    """``orbits --threads N`` sets the count for the process: put it back after."""
    import numba

    from orbits import threads

    before = numba.get_num_threads()
    monkeypatch.setattr(threads, "_requested", threads._requested)
    yield
    numba.set_num_threads(before)


def test_json_is_strict_json_with_null_for_missing_figures(capsys):
    """F1: the throughput row has no baseline: null, not NaN (invalid JSON)."""
    from orbits.cli import main

    assert main(["bench", "--only", "motion_rate", "--quick", "--json", "--no-load-check"]) == 0
    report = _strict_json(capsys.readouterr().out)
    row = report["results"][0]
    assert row["name"] == "motion_rate"
    assert row["baseline_s"] is None and row["speedup"] is None
    assert row["ours_s"] > 0
    # any other non-finite number becomes null too, never NaN or Infinity
    text = bench.to_json({"a": [math.nan, math.inf, -math.inf, 1.5], "b": {"c": math.nan}})
    assert _strict_json(text) == {"a": [None, None, None, 1.5], "b": {"c": None}}


def _fake_subprocess_run(monkeypatch, calls, stdout='{"bodies": 7}'):
    """Replace subprocess.run: record each child's argv and environment."""
    import subprocess

    def fake(argv, **options):
        calls.append({"argv": list(argv), "env": options.get("env")})
        return subprocess.CompletedProcess(argv, 0, stdout=stdout, stderr="")

    monkeypatch.setattr(subprocess, "run", fake)


def test_threads_option_reaches_the_thread_rows_and_the_children(
    capsys, monkeypatch, restore_threads
):
    """F3: ``orbits --threads 1 bench`` compares 1 thread with 1 in the in-process
    rows, and the children (survey_scaling, cold_compile) get ``--threads 1`` and
    the user's PYTHONPATH after the package's own directory."""
    import os
    from pathlib import Path

    from orbits.cli import main

    monkeypatch.setitem(
        bench.BENCHMARKS,
        "survey_threads",
        lambda **kw: bench.bench_survey_threads(resolution=8, n_max=3),
    )
    monkeypatch.setitem(
        bench.BENCHMARKS,
        "search_scaling",
        lambda **kw: bench.bench_search_scaling(resolution=8, n_max=3, repeats=1),
    )
    monkeypatch.setitem(
        bench.BENCHMARKS,
        "survey_scaling",
        lambda **kw: bench.bench_survey_scaling(resolution=4, n_max=2, repeats=1),
    )
    # the children are not started (no timing); two CPUs whatever this machine has
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    monkeypatch.setattr(os, "sched_setaffinity", lambda pid, cpus: None, raising=False)
    calls = []
    _fake_subprocess_run(monkeypatch, calls)
    monkeypatch.setenv("PYTHONPATH", "/the/users/own/path")
    names = ["survey_threads", "search_scaling", "survey_scaling", "cold_compile"]
    assert main(["--threads", "1", "bench", "--only", *names, "--json", "--no-load-check"]) == 0
    report = _strict_json(capsys.readouterr().out)
    assert report["machine"]["numba_threads"] == 1
    rows = {row["name"]: row for row in report["results"]}
    assert set(rows) == set(names)
    assert rows["survey_threads"]["task"].endswith(": 1 thread vs 1")
    assert rows["search_scaling"]["task"].endswith(": 1 thread vs 1")
    for name in names:
        assert rows[name]["threads"] == 1, name
    assert "(1 thread) vs 1" in rows["survey_scaling"]["task"]
    assert "--threads 1 survey" in rows["survey_scaling"]["command"]
    # every orbits child was told the count; the one-CPU runs use one thread
    children = [call["argv"] for call in calls if "orbits" in call["argv"]]
    assert len(children) == 4 + 2  # survey: warm-up + 3 in turns; catalog: cold + warm
    for argv in children:
        assert argv[argv.index("--threads") + 1] == "1", argv
    root = str(Path(bench.__file__).resolve().parents[1])
    for call in calls:
        assert call["env"]["PYTHONPATH"] == root + os.pathsep + "/the/users/own/path"


def test_survey_scaling_without_cpu_affinity(capsys, monkeypatch):
    """F5: no os.sched_getaffinity (macOS, Windows): named, one line and exit 2;
    among all rows, a skipped row with the reason (and strict JSON)."""
    import os

    from orbits.cli import main

    monkeypatch.delattr(os, "sched_getaffinity", raising=False)
    monkeypatch.delattr(os, "sched_setaffinity", raising=False)
    assert main(["bench", "--only", "survey_scaling", "--quick", "--no-load-check"]) == 2
    _one_line_error(capsys, "survey_scaling cannot run here", "sched_getaffinity")
    with pytest.raises(bench.BenchError, match="cannot run here"):
        bench.bench_survey_scaling(resolution=4, n_max=2, repeats=1)

    def other(**kw):
        return _row(task="another row", ours_s=1.0, baseline_s=2.0)

    monkeypatch.setattr(
        bench, "BENCHMARKS", {"survey_scaling": bench.bench_survey_scaling, "other": other}
    )
    report = bench.run(quick=True, load=False)  # all rows
    skipped, ran = report["results"]
    assert skipped["name"] == "survey_scaling" and "sched_getaffinity" in skipped["skipped"]
    assert skipped["ours_s"] is None and skipped["speedup"] is None
    assert ran["name"] == "other" and "skipped" not in ran
    assert _strict_json(bench.to_json(report))["results"][0]["skipped"] == skipped["skipped"]
    text = bench.format_table(report)
    assert "survey_scaling: skipped" in text and "    skipped: needs os.sched_getaffinity" in text


@pytest.fixture
def failing_interpreter(tmp_path, monkeypatch):
    """sys.executable replaced by a program that fails with a message on stderr."""
    import sys

    script = tmp_path / "python"
    script.write_text(
        "#!/bin/sh\necho 'first line' >&2\necho 'boom: the child broke' >&2\nexit 3\n"
    )
    script.chmod(0o755)
    monkeypatch.setattr(sys, "executable", str(script))
    return script


def test_a_failing_child_process_is_one_line_and_exit_2(capsys, failing_interpreter):
    """F5: a child that fails (CalledProcessError before) is one line, exit 2."""
    import os

    from orbits.cli import main

    assert main(["bench", "--only", "startup", "--quick", "--no-load-check"]) == 2
    line = _one_line_error(capsys, "child process failed (exit 3)", "boom: the child broke")
    assert "-c 'import numpy'" in line
    if hasattr(os, "sched_getaffinity") and len(os.sched_getaffinity(0)) >= 2:
        assert main(["bench", "--only", "survey_scaling", "--quick", "--no-load-check"]) == 2
        _one_line_error(capsys, "child process failed (exit 3)", "survey --resolution 2")


def test_startup_warms_up_before_it_times(monkeypatch):
    """F2: one untimed run of each fresh-process command before the medians."""
    calls = []
    _fake_subprocess_run(monkeypatch, calls)
    row = bench.bench_startup(repeats=2)
    commands = [call["argv"][1:] for call in calls]
    assert len(commands) == 3 + 3 * 2
    assert commands[:3] == [
        ["-c", "import numpy"],
        ["-c", "import orbits"],
        ["-m", "orbits", "--help"],
    ]
    assert "median of 2 fresh processes" in row["timed"] and "untimed run" in row["timed"]


def test_survey_bytes_warms_up_before_it_times(monkeypatch):
    """F2: the compact survey was timed cold against a warm ``all``; now each
    layout has an untimed run first, and the timed runs are the last two."""
    from orbits.survey import Survey

    runs = []
    real = Survey.run

    def spy(self, *args, **kwargs):
        runs.append(self.columns)
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Survey, "run", spy)
    row = bench.bench_survey_bytes(resolution=8, n_max=3)
    assert runs == ["compact", "all", "compact", "all"]
    assert "after an untimed warm-up run of each" in row["timed"]


def test_survey_baseline_says_it_is_extrapolated(monkeypatch):
    """F2: the survey row's baseline loop runs on a sample and is scaled; the
    row says how many bodies and to how many."""
    from orbits.bodies import region_grid

    monkeypatch.setattr(bench, "SURVEY_SAMPLE", 5)
    row = bench.bench_survey(resolution=12, n_max=2)
    count = len(region_grid(12))
    sample = len(region_grid(12)[:: count // 5])
    assert 5 <= sample < count
    assert row["baseline_sample"] == sample
    assert f"extrapolated from {sample} of the {count} bodies" in row["baseline"]
    assert f"scaled by {count}/{sample}" in row["note"]
    assert f"over {sample} sampled bodies" in row["timed"]


def test_motion_accuracy_column_hides_only_a_missing_mpmath(monkeypatch):
    """F7: an error in the mpmath reference is raised, not shown as 'install mpmath'."""
    import sys

    pytest.importorskip("mpmath")
    from orbits import checks

    def broken(*args, **kwargs):
        raise RuntimeError("the reference broke")

    monkeypatch.setattr(checks, "exact_motion_mpmath", broken)
    with pytest.raises(RuntimeError, match="the reference broke"):
        bench.bench_motion(points=41, repeats=1)
    monkeypatch.setitem(sys.modules, "mpmath", None)  # import mpmath fails
    row = bench.bench_motion(points=41, repeats=1)
    assert "accuracy vs mpmath: n/a (install mpmath)" in row["note"]


def test_phase_note_makes_no_claim_about_the_baseline_losing_digits():
    """F7: both routes are at theta's conditioning limit next to theta_c; the
    note gives the largest difference and where it is, nothing more."""
    row = bench.bench_total_phase(points=2000, repeats=1)
    assert "loses digits" not in row["note"]
    assert "max relative difference ours vs baseline" in row["note"]
    assert "theta - theta_c = " in row["note"]


def test_failed_under_load_check_exits_1_after_the_table(capsys, monkeypatch):
    """F7: a row that slows down more than LOAD_LIMIT fails the command (exit 1,
    one line naming it, after the table or the JSON)."""
    from orbits.cli import main

    def report(*args, **kwargs):
        load = {"idle_s": 1e-3, "loaded_s": 4.46e-3, "slowdown": 4.46, "holds": False, "runs": 20}
        rows = [_row(name="search", task="closed orbits", load=load)]
        return {"machine": _machine(), "results": rows}

    monkeypatch.setattr(bench, "run", report)
    assert main(["bench", "--only", "search"]) == 1
    captured = capsys.readouterr()
    assert "under-load check: 0 of 1 rows hold within 2x" in captured.out
    err = captured.err.strip().splitlines()
    assert err == ["orbits: error: under-load check failed (limit 2x): closed orbits slowed 4.46x"]
    assert main(["bench", "--only", "search", "--json"]) == 1
    captured = capsys.readouterr()
    assert _strict_json(captured.out)["results"][0]["load"]["holds"] is False
    assert len(captured.err.strip().splitlines()) == 1


def test_run_reports_the_load_check(monkeypatch):
    """The report says how many rows held (JSON users need not recount)."""
    monkeypatch.setattr(
        bench,
        "BENCHMARKS",
        {
            "a": lambda **kw: _row(
                task="a", ours_s=1.0, baseline_s=1.0, speedup=1.0, _ours=(lambda: None, 1)
            )
        },
    )
    monkeypatch.setattr(bench, "_busy_process", lambda: _Stopped())
    report = bench.run(["a"])
    check = report["load_check"]
    assert check["limit"] == bench.LOAD_LIMIT and check["rows"] == 1
    assert check["held"] + (not check["passed"]) == 1
    assert "_ours" not in report["results"][0]


class _Stopped:
    def kill(self):
        pass

    def wait(self):
        pass


def test_device_cuda_refuses_no_load_check(capsys):
    """F7: the GPU rows have no under-load check, so --no-load-check is refused there."""
    from orbits.cli import main

    assert main(["bench", "--device", "cuda", "--no-load-check"]) == 2
    _one_line_error(capsys, "--no-load-check applies only with --device cpu")


def test_only_refuses_a_repeated_name(capsys):
    """F8: ``--only motion_rate motion_rate`` ran the row twice."""
    from orbits.cli import main

    code = main(["bench", "--only", "motion_rate", "motion_rate", "--quick", "--no-load-check"])
    assert code == 2
    _one_line_error(capsys, "named more than once: motion_rate")
    with pytest.raises(bench.InputError, match="named more than once"):
        bench.run(["phase", "phase"])


def test_long_task_names_keep_the_columns_aligned():
    """F8: a task longer than the column pushed its figures out of line."""
    long = "survey search on the GPU, 3855 bodies, n <= 30 (grid 100), a long name"
    load = {"idle_s": 1e-3, "loaded_s": 1e-3, "slowdown": 1.0, "holds": True, "runs": 3}
    rows = [_row(task=task, load=load) for task in ("short", long)]
    lines = bench.format_table({"machine": _machine(), "results": rows}).splitlines()
    main_table = [line for line in lines if line.startswith(("task", "short", long))]
    assert len(main_table) == 6  # header and two rows, twice (times, under load)
    first, second = main_table[:3], main_table[3:]
    assert len({len(line) for line in first}) == 1, first
    assert len({len(line.rstrip()) for line in second}) == 1, second


def _rows_under_the_simulator(code, count):
    """The last ``count`` JSON lines printed by ``code`` (dedented) in a fresh
    interpreter on the CUDA simulator, this tree first on the path."""
    import json
    import subprocess
    import textwrap

    if importlib.util.find_spec("numba_cuda") is None:
        pytest.skip("numba-cuda not installed")
    root = Path(__file__).resolve().parents[1]
    env = dict(os.environ, NUMBA_ENABLE_CUDASIM="1")
    env["PYTHONPATH"] = str(root) + os.pathsep + env.get("PYTHONPATH", "")
    done = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        env=env,
        cwd=root,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return [json.loads(line) for line in done.stdout.strip().splitlines()[-count:]]


def test_cuda_phase_labels_under_the_simulator():
    """F7/F8: the cuda_phase row says what is timed (the CPU on fewer points,
    scaled), where theta is folded, and the CPU's thread count (one thread
    under 20,000 points)."""
    code = """
        import json
        from orbits import bench
        print(json.dumps(bench.bench_cuda_total_phase(points=48, repeats=1)))
        print(json.dumps(bench.bench_cuda_search(resolution=4, n_max=3, repeats=1)))
    """
    row, search_row = _rows_under_the_simulator(code, 2)
    assert row["threads"] == 1 and "(1 thread)" in row["baseline"]
    assert "timed on all the angles" in row["timed"]
    assert "theta folded and checked in the kernel" in row["note"]
    assert "fold and checks on the host" not in row["note"]
    # the ratio compares the same work: the public call end to end on both
    # sides (it divided the CPU call by the GPU kernel alone: 138.6x printed,
    # 0.88x end to end); the kernel alone is in the note, labelled
    for each in (row, search_row):
        assert each["ours_s"] == each["end_to_end_s"]
        assert each["speedup"] == pytest.approx(each["baseline_s"] / each["end_to_end_s"])
        assert each["kernel_speedup"] == pytest.approx(each["baseline_s"] / each["kernel_s"])
        assert "end to end" in each["task"] and each["timed"].startswith("end to end")
        assert "kernel only" in each["note"] and "not the ratio column" in each["note"]
    assert "device='cpu'" in row["baseline"]
    assert search_row["agrees"] is True and "agree: " in search_row["note"]


def test_survey_tables_times_the_table_work_of_real_chunks(monkeypatch, tmp_path):
    """survey_tables: every pass makes and writes each chunk once (warm-up,
    then one thread and all in turns), its parts are the survey's own (the
    ledger verifies them), the bodies are counted right, and nothing is
    left in the temporary directory."""
    import tempfile

    from orbits.survey import Survey

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    written, verified = [], []
    real_write = Survey.write_chunk

    def write_chunk(self, index, bodies, orbits):
        real_write(self, index, bodies, orbits)
        written.append((self.out_dir.name, index, len(bodies["body"])))
        if index == 2:
            verified.append(self.verify())  # the parts just written check out

    monkeypatch.setattr(Survey, "write_chunk", write_chunk)
    row = bench.bench_survey_tables(resolution=40, n_max=3, chunks=3, chunk=100, repeats=2)
    passes = sorted({name for name, _, _ in written})
    assert passes == ["all-0", "all-1", "one-0", "one-1", "warm"]
    assert sorted(written) == sorted((p, i, 100) for p in passes for i in range(3))
    assert verified == [[]] * 5
    assert row["bodies_per_s"] == pytest.approx(300 / row["ours_s"])
    assert row["speedup"] == pytest.approx(row["baseline_s"] / row["ours_s"])
    assert "3 chunks of up to 100 bodies" in row["task"] and "ms a chunk" in row["note"]
    assert list(tmp_path.iterdir()) == []


def test_bytecode_current_reads_the_pyc_header_as_python_does(tmp_path):
    import importlib.util
    import os
    import py_compile
    import subprocess
    import sys

    source = tmp_path / "mod.py"
    source.write_text("x = 1\n")
    assert not bench._bytecode_current(str(source), importlib.util)  # no pyc yet
    py_compile.compile(str(source), doraise=True)
    assert bench._bytecode_current(str(source), importlib.util)
    # Python itself agrees: it imports the module without writing a new pyc
    cached = importlib.util.cache_from_source(str(source))
    before = os.stat(cached).st_mtime_ns
    subprocess.run(
        [sys.executable, "-c", "import mod"],
        cwd=tmp_path,
        check=True,
        env=dict(os.environ, PYTHONDONTWRITEBYTECODE=""),
    )
    assert os.stat(cached).st_mtime_ns == before
    # a source changed after its pyc (another size): the pyc is stale
    source.write_text("x = 12\n")
    assert not bench._bytecode_current(str(source), importlib.util)
    py_compile.compile(str(source), doraise=True)
    assert bench._bytecode_current(str(source), importlib.util)
    # another interpreter's magic number: not used by this one
    with open(cached, "r+b") as handle:
        handle.write(b"\0\0\0\0")
    assert not bench._bytecode_current(str(source), importlib.util)


def test_bytecode_note_only_when_fresh_processes_compile(monkeypatch):
    monkeypatch.delenv("PYTHONDONTWRITEBYTECODE", raising=False)
    assert bench.uncompiled_modules() == (0, 0.0)
    assert bench._bytecode_note() == ""
    monkeypatch.setenv("PYTHONDONTWRITEBYTECODE", "1")
    monkeypatch.setattr(bench, "_bytecode_current", lambda source, util: False)
    count, seconds = bench.uncompiled_modules()
    assert count >= 40 and seconds > 0.0  # every module of the package
    note = bench._bytecode_note()
    assert f"{count} modules of orbits have no cached bytecode" in note


def test_quick_changes_every_row_it_can():
    """--quick ran six rows (motion*, search, ...) at full size, silently."""
    from orbits import bench

    for name in bench.BENCHMARKS:
        kwargs = bench._quick_kwargs(name, None)
        if name == "cold_compile":  # one compile: nothing to make smaller
            assert kwargs == {}
            continue
        assert kwargs, name
        signature = inspect.signature(bench.BENCHMARKS[name])
        if not any(p.kind is p.VAR_KEYWORD for p in signature.parameters.values()):
            assert set(kwargs) <= set(signature.parameters), name


# ------------------------------------------------------------------ audit fixes
def test_header_counts_the_cpus_this_process_may_use(monkeypatch):
    """Under ``taskset -c 0`` the header said "2 cores" while one was usable."""
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0}, raising=False)
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    assert bench.usable_cpus() == (1, 2)
    monkeypatch.setattr(bench, "BENCHMARKS", {"r": lambda **kw: _row()})
    report = bench.run(["r"], load=False)
    assert report["machine"]["cpus_usable"] == 1 and report["machine"]["cpu_count"] == 2
    header = bench.format_table(report).splitlines()[0]
    assert header.startswith("orbits bench: 1 CPU usable of 2, ")
    assert "cores" not in header
    # no affinity API (macOS, Windows): the machine's count
    monkeypatch.delattr(os, "sched_getaffinity", raising=False)
    assert bench.usable_cpus() == (2, 2)
    # a report from before the field: the machine's count, not "usable"
    old = {k: v for k, v in _machine().items() if k != "cpus_usable"}
    assert bench.format_table({"machine": old, "results": []}).startswith("orbits bench: 2 CPUs, ")


def test_roots_agreement():
    def body(branches, levels, offsets):
        return (np.array(branches, np.int8), np.array(levels), np.array(offsets, float))

    a = [body([1, 1, -1], [0, 1, 0], [0.1, 0.2, 0.3]), None, body([], [], [])]
    same = [body([1, 1, -1], [0, 1, 0], [0.1, 0.2 * (1 + 1e-13), 0.3]), None, body([], [], [])]
    differ, worst = bench.roots_agreement(a, same)
    assert differ == 0 and 0 < worst < bench.SEARCH_RTOL
    off = [body([1, 1, -1], [0, 1, 0], [0.1, 0.2 * (1 + 1e-6), 0.3]), None, body([], [], [])]
    assert bench.roots_agreement(a, off)[0] == 1
    other_level = [body([1, 1, -1], [0, 2, 0], [0.1, 0.2, 0.3]), None, body([], [], [])]
    assert bench.roots_agreement(a, other_level)[0] == 1
    fewer = [body([1, 1], [0, 1], [0.1, 0.2]), body([], [], []), body([], [], [])]
    assert bench.roots_agreement(a, fewer)[0] == 2  # one root missing; refused by one side


def test_search_evaluations_checks_both_searches_agree(monkeypatch):
    """The row discarded the baseline's roots: a fast wrong search would win."""
    from orbits.core import search as kernels

    row = bench.bench_search_evaluations(resolution=8, n_max=3)
    assert row["agrees"] is True
    assert "agree: " in row["note"] and "DISAGREE" not in row["note"]
    assert f"offsets within {bench.SEARCH_RTOL:.0e} relative" in row["note"]
    real = kernels.search_body

    def wrong(i1, i2, i3, levels, branch, level, offset, info):
        found = real(i1, i2, i3, levels, branch, level, offset, info)
        offset[:found] *= 1.001
        return found

    monkeypatch.setattr(kernels, "search_body", wrong)
    row = bench.bench_search_evaluations(resolution=8, n_max=3)
    assert row["agrees"] is False and "DISAGREE: " in row["note"]


def test_search_row_compares_the_same_roots(monkeypatch):
    """The row printed a ratio (1.3-2x) of ours finding 98 roots at n <= 50
    against a theta grid finding 7 (an audit): now both arms find the 28 of
    n <= 15 and the row checks their theta."""
    row = bench.bench_search(repeats=1)
    assert row["agrees"] is True and "DISAGREE" not in row["note"]
    assert row["task"] == "closed orbits n <= 15, both branches (fig6)"
    assert row["note"].startswith("28 roots, the nearest 2.2e-12 rad from theta_c")
    assert "the baseline finds 28, theta within" in row["note"]
    real = bench._roots_by_scipy
    monkeypatch.setattr(bench, "_roots_by_scipy", lambda body, n_max: real(body, n_max)[1:])
    row = bench.bench_search(repeats=1)
    assert row["agrees"] is False and "DISAGREE: the baseline finds 27" in row["note"]
    monkeypatch.setattr(bench, "_roots_by_scipy", lambda body, n_max: real(body, n_max) + 1e-12)
    row = bench.bench_search(repeats=1)
    assert row["agrees"] is False and "DISAGREE: the baseline finds 28" in row["note"]


def test_survey_checks_the_loop_against_the_survey(monkeypatch):
    """The survey row never compared the loop's orbits with the survey's."""
    from orbits import search

    monkeypatch.setattr(bench, "SURVEY_SAMPLE", 5)
    row = bench.bench_survey(resolution=12, n_max=2)
    assert row["agrees"] is True and "agree: " in row["note"]
    sample = row["baseline_sample"]
    assert f"{sample} of the {sample} sampled bodies have as many orbits" in row["note"]
    real = search.closed_orbits

    def one_short(*args, **kwargs):
        frame = real(*args, **kwargs)
        shorter = frame.iloc[1:]
        shorter.attrs.update(frame.attrs)
        return shorter

    monkeypatch.setattr(search, "closed_orbits", one_short)
    row = bench.bench_survey(resolution=12, n_max=2)
    assert row["agrees"] is False and "DISAGREE: " in row["note"]


def test_a_row_that_disagrees_exits_1_after_the_table(capsys, monkeypatch):
    from orbits.cli import main

    rows = [
        _row(task="search kernel", agrees=False, note="DISAGREE: 3 of 4 bodies"),
        _row(task="survey", agrees=True, note="agree: all"),
    ]
    monkeypatch.setattr(
        bench, "BENCHMARKS", {"a": lambda **kw: rows[0], "b": lambda **kw: rows[1]}
    )
    report = bench.run(load=False)
    assert report["agreement"] == {"rows": 2, "agree": 1, "passed": False}
    assert [row["task"] for row in bench.disagreements(report)] == ["search kernel"]
    assert main(["bench", "--no-load-check"]) == 1
    captured = capsys.readouterr()
    assert "agreement check: both sides agree in 1 of 2 rows" in captured.out
    assert "NOT ALL: DISAGREE" in captured.out
    # no ratio for the row whose two sides disagree; the other keeps its own
    table = {line.split()[0]: line.split()[-1] for line in captured.out.splitlines() if line}
    assert table["search"] == "DISAGREE" and table["survey"].endswith("x")
    assert captured.err.strip().splitlines() == [
        "orbits: error: the two sides disagree: search kernel"
    ]
    rows[0] = _row(task="search kernel", agrees=True)
    assert main(["bench", "--no-load-check", "--json"]) == 0
    assert _strict_json(capsys.readouterr().out)["agreement"]["passed"] is True


def test_survey_scaling_gives_the_amdahl_figure_as_an_estimate(monkeypatch):
    """Recorded runs exceeded the "at most" bound (1.76x against 1.71x)."""
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    monkeypatch.setattr(os, "sched_setaffinity", lambda pid, cpus: None, raising=False)
    _fake_subprocess_run(monkeypatch, [])
    row = bench.bench_survey_scaling(resolution=4, n_max=2, repeats=1)
    assert "at most" not in row["note"]
    assert "CPUs give about" in row["note"] and "Amdahl estimate" in row["note"]


def test_help_and_docstring_say_how_each_row_is_timed(capsys):
    """``survey`` is one run of each format, not "best of several"."""
    from orbits.cli import main

    try:
        code = main(["bench", "--help"])
    except SystemExit as exit:
        code = exit.code
    assert code in (0, None)
    text = " ".join(capsys.readouterr().out.split())
    assert (
        "search_evaluations, survey_threads, survey_bytes and survey one run of each side" in text
    )
    assert "phase, motion*, motion_rate and search the best of several runs" in text
    assert "search_scaling and survey_tables the best of three" in text
    doc = " ".join(bench.__doc__.split())
    assert (
        "``search_evaluations``, ``survey_threads``, ``survey_bytes`` and ``survey``: one" in doc
    )
    assert "most rows" not in doc


def test_scale_script_refuses_cpus_outside_its_affinity():
    """benchmarks/scale.py: a CPU this process may not use is exit 2, one line."""
    from pathlib import Path

    if not hasattr(os, "sched_getaffinity"):
        pytest.skip("needs os.sched_getaffinity")
    script = Path(__file__).resolve().parents[1] / "benchmarks" / "scale.py"
    outside = max(os.sched_getaffinity(0)) + 1
    done = subprocess.run(
        [sys.executable, str(script), "40", "5", "1", "0", f"0-{outside}"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 2 and done.stdout == ""
    err = done.stderr.strip().splitlines()
    assert len(err) == 1 and f"CPU(s) {outside} not available" in err[0], err
    done = subprocess.run(
        [sys.executable, str(script), "40", "5"], capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 2 and done.stderr.startswith("scale.py: error: usage:")


def test_only_help_names_every_row():
    """--help lists the --only names (the table shows descriptions, not
    names); the list is the benchmarks' own keys."""
    from orbits.cli import bench as cli_bench

    assert cli_bench.ROW_NAMES == tuple(bench.BENCHMARKS)
    assert cli_bench.CUDA_ROW_NAMES == tuple(bench.CUDA_BENCHMARKS)


# ------------------------------------------------------------------------
# Each test below kills a mutant of orbits/bench.py, orbits/cli/bench.py or
# benchmarks/scale.py that passed the suite (a mutation audit, 2026-11-29:
# 47 mutants, 28 survivors that printed a misleading figure with exit 0).
# No test asserts on measured speed: the timing functions are replaced by
# fakes returning fixed figures; what is asserted is which work each arm
# did and how the row turns the figures into its fields.


ROOT = Path(bench.__file__).resolve().parents[1]


def _queue_best_time(monkeypatch, figures, call=True):
    """bench.best_time replaced: each call runs ``function`` once (so spies see
    the work) and returns the next of ``figures``."""
    figures = list(figures)
    seen = []

    def fake(function, repeats):
        if call:
            function()
        seen.append(repeats)
        return figures.pop(0)

    monkeypatch.setattr(bench, "best_time", fake)
    return seen


class _FakeClock:
    """A stand-in for the ``time`` module inside orbits.bench."""

    def __init__(self):
        self.now = 0.0

    def perf_counter(self):
        return self.now

    def sleep(self, seconds):
        pass


# ------------------------------------------------------------------ in-process rows
def test_phase_ratio_is_baseline_over_ours(monkeypatch):
    _queue_best_time(monkeypatch, [1.0, 2.0, 4.0], call=False)  # ours, scalar, scipy
    row = bench.bench_total_phase(points=200, repeats=1)
    assert (row["ours_s"], row["scalar_s"], row["baseline_s"]) == (1.0, 2.0, 4.0)
    assert row["speedup"] == 4.0


def test_motion_both_arms_time_the_same_grid(monkeypatch):
    import orbits.motion as motion_module

    monkeypatch.setitem(sys.modules, "mpmath", None)  # no accuracy reference
    sizes, points = [], []
    real_ivp, real_herp = bench._herpolhode_by_integration, motion_module.herpolhode

    def ivp(motion, times):
        sizes.append(times.size)
        return real_ivp(motion, times)

    def herp(body, theta, points=None, **kw):
        sizes_ours.append(points)
        return real_herp(body, theta, points=points, **kw)

    sizes_ours = points
    monkeypatch.setattr(bench, "_herpolhode_by_integration", ivp)
    monkeypatch.setattr(motion_module, "herpolhode", herp)
    _queue_best_time(monkeypatch, [1.0, 3.0, 0.5])  # ours, solve_ivp, direct
    row = bench.bench_motion(points=41, repeats=1)
    assert sizes == [41] and points == [41]
    assert row["ours_s"] == 1.0 and row["baseline_s"] == 3.0
    assert row["speedup"] == 3.0


def test_search_baseline_times_the_same_n_max(monkeypatch):
    seen = []
    real = bench._roots_by_scipy

    def spy(body, n_max, *args):
        seen.append(n_max)
        return real(body, n_max, *args)

    monkeypatch.setattr(bench, "_roots_by_scipy", spy)
    _queue_best_time(monkeypatch, [1.0, 0.1, 5.0])  # ours, kernel, baseline
    row = bench.bench_search(repeats=1)
    assert seen and set(seen) == {bench.SEARCH_N_MAX}
    assert row["agrees"] is True
    assert row["baseline_s"] == 5.0 and row["speedup"] == 5.0


def test_search_evaluations_arms_time_the_same_bodies(monkeypatch):
    from orbits.bodies import region_grid
    from orbits.core import search as kernels

    real = bench._search_counts
    timed = []

    def spy(function, bodies, levels, keep=None):
        _, evaluations, roots = real(function, bodies, levels, keep)
        if keep is None and len(bodies) > 2:
            timed.append((function is kernels.search_body, len(bodies)))
        return (1.0 if function is kernels.search_body else 3.0), evaluations, roots

    monkeypatch.setattr(bench, "_search_counts", spy)
    row = bench.bench_search_evaluations(resolution=8, n_max=3)
    count = len(region_grid(8))
    assert timed == [(True, count), (False, count)]
    assert row["speedup"] == 3.0 and row["agrees"] is True


def test_search_evaluations_nan_offsets_disagree(monkeypatch):
    """A kernel that returns NaN offsets must not pass the agreement check."""
    from orbits.core import search as kernels

    real = kernels.search_body

    def nan_offsets(i1, i2, i3, levels, branch, level, offset, info):
        found = real(i1, i2, i3, levels, branch, level, offset, info)
        offset[:found] = np.nan
        return found

    monkeypatch.setattr(kernels, "search_body", nan_offsets)
    row = bench.bench_search_evaluations(resolution=8, n_max=3)
    assert row["agrees"] is False and "DISAGREE: " in row["note"]
    body = (np.array([1], np.int8), np.array([0]), np.array([0.1]))
    nan = (np.array([1], np.int8), np.array([0]), np.array([np.nan]))
    assert bench.roots_agreement([nan], [body])[0] == 1


def test_survey_figures_scale_the_sample_to_the_grid(monkeypatch):
    from orbits.bodies import region_grid

    monkeypatch.setattr(bench, "SURVEY_SAMPLE", 5)
    _queue_best_time(monkeypatch, [2.0, 1.0, 0.5])  # csv, parquet, loop over the sample
    row = bench.bench_survey(resolution=12, n_max=2)
    count = len(region_grid(12))
    sample = row["baseline_sample"]
    assert sample < count
    assert row["ours_s"] == 1.0
    assert row["baseline_s"] == pytest.approx(0.5 / sample * count, rel=1e-12)
    assert row["speedup"] == pytest.approx(0.5 / sample * count / 1.0, rel=1e-12)
    assert row["bodies_per_s"] == pytest.approx(count / 1.0, rel=1e-12)
    assert row["agrees"] is True


# ------------------------------------------------------------------ under-load check
def test_load_check_counts_a_failing_row(monkeypatch):
    figures = iter([1.0, 5.0])  # idle, loaded: 5x
    monkeypatch.setattr(bench, "_median_time", lambda function, repeats: next(figures))
    monkeypatch.setattr(
        bench, "_busy_process", lambda: types.SimpleNamespace(kill=lambda: None, wait=lambda: None)
    )
    monkeypatch.setattr(bench, "time", _FakeClock())
    monkeypatch.setattr(
        bench,
        "BENCHMARKS",
        {
            "a": lambda **kw: {
                "task": "a",
                "timed": "t",
                "ours_s": 1.0,
                "baseline": "b",
                "baseline_s": 1.0,
                "speedup": 1.0,
                "note": "n",
                "_ours": (lambda: None, 5),
            }
        },
    )
    report = bench.run(["a"])
    load = report["results"][0]["load"]
    assert load["slowdown"] == 5.0 and load["holds"] is False
    assert report["load_check"] == {"limit": 2.0, "rows": 1, "held": 0, "passed": False}
    assert bench.load_failures(report) == report["results"]


def test_load_check_runs_at_least_three_for_a_two_run_row(monkeypatch):
    monkeypatch.setattr(
        bench, "_busy_process", lambda: types.SimpleNamespace(kill=lambda: None, wait=lambda: None)
    )
    calls = []
    rows = [{"task": "m", "_ours": (lambda: calls.append(1), 2)}]
    bench.load_check(rows)
    assert rows[0]["load"]["runs"] == 3
    assert len(calls) == 2 * (1 + 3)


# ------------------------------------------------------------------ fresh-process rows
def test_cold_compile_ratio_is_warm_over_cold(monkeypatch):
    figures = iter([(10.0, 12.0), (2.0, 2.5)])  # cold, warm
    monkeypatch.setattr(bench, "_fresh_interpreter", lambda args, env=None: next(figures))
    row = bench.bench_cold_compile()
    assert row["ours_s"] == 10.0 and row["baseline_s"] == 2.0
    assert row["speedup"] == pytest.approx(0.2, rel=1e-15)


def test_survey_scaling_arms_cpus_threads_and_figures(monkeypatch):
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1, 2, 3}, raising=False)
    monkeypatch.setattr(os, "sched_setaffinity", lambda pid, cpus: None, raising=False)
    monkeypatch.setattr(bench, "get_num_threads", lambda: 4)
    calls = []

    def wall(resolution, n_max, cpus, threads=1, extra=()):
        calls.append((resolution, n_max, frozenset(cpus), threads))
        if resolution == 2:
            return 0.5, 4, 400
        return (4.0 if len(cpus) == 1 else 2.5), 100, 12345

    monkeypatch.setattr(bench, "_survey_command_wall", wall)
    row = bench.bench_survey_scaling(resolution=9, n_max=5, repeats=2)
    timed = [c for c in calls if c[0] == 9]
    one, everything = frozenset({0}), frozenset({0, 1, 2, 3})
    assert timed == [(9, 5, one, 1), (9, 5, everything, 4)] * 2
    assert all(c == (2, 1, one, 1) for c in calls if c[0] == 2)
    assert row["ours_s"] == 2.5 and row["baseline_s"] == 4.0
    assert row["speedup"] == pytest.approx(1.6, rel=1e-15)
    assert row["fixed_s"] == 0.5
    assert row["bound"] == pytest.approx(4.0 / (0.5 + 3.5 / 4), rel=1e-15)
    assert row["bytes_per_body"] == pytest.approx(123.45, rel=1e-15)
    assert row["bodies_per_s"] == pytest.approx(40.0, rel=1e-15)


def test_survey_command_is_pinned_to_its_cpus(monkeypatch):
    import subprocess

    pinned, options_seen = [], []
    monkeypatch.setattr(
        os, "sched_setaffinity", lambda pid, cpus: pinned.append((pid, set(cpus))), raising=False
    )

    def fake(argv, **options):
        options_seen.append(options)
        if options.get("preexec_fn"):
            options["preexec_fn"]()
        return subprocess.CompletedProcess(argv, 0, stdout='{"bodies": 7}', stderr="")

    monkeypatch.setattr(subprocess, "run", fake)
    wall, bodies, size = bench._survey_command_wall(4, 2, {1}, threads=1)
    assert bodies == 7 and size == 0
    assert pinned == [(0, {1})]


def test_survey_scaling_needs_two_cpus(monkeypatch):
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0}, raising=False)
    monkeypatch.setattr(os, "sched_setaffinity", lambda pid, cpus: None, raising=False)
    assert bench.unavailable("survey_scaling") == "only one CPU is available to this process"
    with pytest.raises(bench.BenchError, match="only one CPU"):
        bench.bench_survey_scaling(resolution=4, n_max=2, repeats=1)


# ------------------------------------------------------------------ thread rows
@pytest.fixture
def fake_threads(monkeypatch):
    """using_threads recorded (not applied); a fake clock in orbits.bench; four threads."""
    import orbits.threads as threads_module

    state = {"threads": None, "used": []}
    clock = _FakeClock()

    @contextlib.contextmanager
    def using(count):
        before = state["threads"]
        state["threads"] = count
        state["used"].append(count)
        try:
            yield
        finally:
            state["threads"] = before

    monkeypatch.setattr(threads_module, "using_threads", using)
    monkeypatch.setattr(bench, "get_num_threads", lambda: 4)
    monkeypatch.setattr(bench, "time", clock)
    state["clock"] = clock
    return state


def test_search_scaling_compares_all_threads_with_one(monkeypatch, fake_threads):
    from orbits.bodies import region_grid
    from orbits.survey import compute

    def chunk_work(chunk, n_max):
        if fake_threads["threads"]:
            fake_threads["clock"].now += len(chunk) / fake_threads["threads"]

    monkeypatch.setattr(compute, "search_chunk", chunk_work)
    row = bench.bench_search_scaling(resolution=12, n_max=3, repeats=2)
    bodies = len(region_grid(12))
    assert fake_threads["used"] == [1, 4, 1, 4]
    assert row["baseline_s"] == bodies and row["ours_s"] == bodies / 4
    assert row["speedup"] == 4.0 and row["threads"] == 4


def test_survey_threads_compares_all_threads_with_one(monkeypatch, fake_threads):
    from orbits.survey import Survey

    def run(self, *args, **kwargs):
        fake_threads["clock"].now += self.moments.shape[0] / fake_threads["threads"]

    monkeypatch.setattr(Survey, "run", run)
    row = bench.bench_survey_threads(resolution=8, n_max=3)
    assert fake_threads["used"] == [4, 1, 4]
    assert row["baseline_s"] == 25.0 and row["ours_s"] == 25.0 / 4
    assert row["speedup"] == 4.0


def test_survey_tables_pools_and_body_count(monkeypatch, tmp_path):
    import concurrent.futures
    import tempfile

    from orbits.bodies import region_grid

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    monkeypatch.setattr(bench, "get_num_threads", lambda: 3)
    pools = []
    real = concurrent.futures.ThreadPoolExecutor

    class Spy(real):
        def __init__(self, workers, *args, **kwargs):
            pools.append(workers)
            super().__init__(workers, *args, **kwargs)

    monkeypatch.setattr(concurrent.futures, "ThreadPoolExecutor", Spy)
    # 56 bodies in chunks of 20: the last chunk has 16
    row = bench.bench_survey_tables(resolution=12, n_max=3, chunks=10, chunk=20, repeats=2)
    assert pools == [3, 1, 3, 1, 3]
    bodies = len(region_grid(12))
    assert bodies == 56
    assert row["bodies_per_s"] == pytest.approx(bodies / row["ours_s"], rel=1e-12)


def test_survey_bytes_figures_per_layout(monkeypatch):
    from orbits.survey import Survey

    clock = _FakeClock()
    monkeypatch.setattr(bench, "time", clock)
    written = {"compact": (1.0, 1000), "all": (3.0, 5000)}

    def run(self, *args, **kwargs):
        seconds, size = written[self.columns]
        clock.now += seconds
        self.out_dir.mkdir(parents=True)
        (self.out_dir / "part").write_bytes(b"0" * size)

    monkeypatch.setattr(Survey, "run", run)
    row = bench.bench_survey_bytes(resolution=8, n_max=3)
    assert row["ours_s"] == 1.0 and row["baseline_s"] == 3.0 and row["speedup"] == 3.0
    assert row["bytes_per_body"] == 1000 / 25 and row["baseline_bytes_per_body"] == 5000 / 25


# ------------------------------------------------------------------ GPU row (simulator)
def test_cuda_search_compares_the_gpu_with_the_cpu():
    """cuda_search's agreement check must compare the GPU's roots with the CPU's."""
    code = """
        import json
        import orbits.search as search
        from orbits import bench
        real = search.search_bodies
        def off(moments, levels, **kw):
            rows = real(moments, levels, **kw)
            if kw.get("device") == "cpu":
                rows.offset[:] *= 1.001
            return rows
        search.search_bodies = off
        print(json.dumps(bench.bench_cuda_search(resolution=4, n_max=3, repeats=1)))
    """
    (row,) = _rows_under_the_simulator(code, 1)
    assert row["agrees"] is False and "DISAGREE: " in row["note"]


# ------------------------------------------------------------------ benchmarks/scale.py
def _scale_module():
    spec = importlib.util.spec_from_file_location("scale_script", ROOT / "benchmarks" / "scale.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_scale_script_pins_each_set_and_reports_median_ratio(monkeypatch, capsys):
    scale = _scale_module()
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    walls = {frozenset({0}): iter([4.0, 6.0, 5.0]), frozenset({0, 1}): iter([2.0, 3.0, 2.5])}
    pinned = []

    def run_once(resolution, n_max, cpus):
        pinned.append(frozenset(cpus))
        return next(walls[frozenset(cpus)])

    monkeypatch.setattr(scale, "run_once", run_once)
    assert scale.main(["40", "5", "3", "0", "0,1"]) == 0
    assert pinned == [frozenset({0}), frozenset({0, 1})] * 3
    lines = {
        line.split()[0]: line.split()
        for line in capsys.readouterr().out.splitlines()
        if line.startswith(("0 ", "0,1 "))
    }
    assert lines["0"][-1] == "1.00x" and lines["0,1"][-1] == "2.00x"
    assert lines["0,1"][1] == "2.500" and lines["0,1"][3] == "2.000"


def test_scale_script_parses_cpu_ranges():
    scale = _scale_module()
    assert scale.parse_cpus("0") == {0}
    assert scale.parse_cpus("0-1") == {0, 1}
    assert scale.parse_cpus("0-3,8") == {0, 1, 2, 3, 8}
