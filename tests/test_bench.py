"""``orbits bench``: the under-load check runs, reports, and cleans up.

No timing is asserted (the machine is shared); what is tested is that each
row is re-timed beside a CPU-bound child, that the child is stopped, and
that the table prints the check.
"""

import math

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
        {
            "task": "a",
            "ours_s": 1e-3,
            "baseline": "b",
            "baseline_s": 2e-3,
            "speedup": 2.0,
            "note": "n",
            "_ours": (lambda: calls.append("a") or sum(range(20000)), 5),
        },
        {
            "task": "no task of its own",
            "ours_s": 1.0,
            "baseline": "b",
            "baseline_s": math.nan,
            "speedup": math.nan,
            "note": "n",
        },
    ]
    bench.load_check(rows)
    assert len(started) == 1 and started[0].poll() is not None  # stopped
    load = rows[0]["load"]
    assert set(load) == {"idle_s", "loaded_s", "slowdown", "holds"}
    assert load["slowdown"] == load["loaded_s"] / load["idle_s"]
    assert load["holds"] == (load["slowdown"] <= bench.LOAD_LIMIT)
    assert len(calls) == 2 * (1 + 5)  # warm-up + 5, idle and loaded
    assert "_ours" not in rows[0] and "load" not in rows[1]
    text = bench.format_table(
        {
            "machine": {
                "cpu_count": 2,
                "numba_threads": 2,
                "python": "3",
                "numpy": "2",
                "scipy": "1",
                "numba": "0",
            },
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
