"""Thread control (orbits.threads): the requested count reaches every
parallel kernel, from whichever Python thread launches it."""

import json
import os
import subprocess
import sys
import threading
from fractions import Fraction

import numba
import numpy as np
import pytest

import orbits
from orbits import ArgumentTypeError, InputError
from orbits.core import checks as core_checks
from orbits.core import launch
from orbits.core import search as core_search
from orbits.survey import compute_chunk

FIG6 = (0.26, 0.55, 0.793662)
TOP = numba.config.NUMBA_NUM_THREADS


@pytest.fixture
def restore_threads():
    before = orbits.get_num_threads()
    yield
    orbits.set_num_threads(before)


@pytest.mark.parametrize(
    "value",
    [2**64, 10**400, Fraction(10**400, 3), -(2**70), 0, TOP + 1, 1.5],
    ids=["2**64", "10**400", "Fraction(10**400, 3)", "-2**70", "0", "TOP+1", "1.5"],
)
def test_counts_out_of_range_are_input_errors(value, restore_threads):
    """Huge ints and Fractions were a TypeError from np.isfinite."""
    before = orbits.get_num_threads()
    with pytest.raises(InputError, match="threads must be an integer from 1 to") as caught:
        orbits.set_num_threads(value)
    assert not isinstance(caught.value, ArgumentTypeError)
    assert orbits.get_num_threads() == before


def test_whole_numbers_of_any_real_type_are_counts(restore_threads):
    for value in (Fraction(1, 1), np.int8(1), np.float32(1.0), 1.0):
        orbits.set_num_threads(value)
        assert orbits.get_num_threads() == 1 and type(orbits.get_num_threads()) is int


def _threads_seen(monkeypatch, module, name):
    """Record numba's thread count at each launch of ``module.name``."""
    seen = []
    kernel = getattr(module, name)

    def recording(*args):
        # the serial twin (core.launch) runs on one thread whatever numba's count
        seen.append(1 if launch.runs_serial() else numba.get_num_threads())
        return kernel(*args)

    monkeypatch.setattr(module, name, recording)
    return seen


CALLS = {
    "search_bodies": (
        core_search,
        "search_many",
        lambda: orbits.search.search_bodies([FIG6, (1.0, 2.0, 2.5)], [2 * np.pi * 2.5]),
    ),
    "compute_chunk": (core_search, "search_many", lambda: compute_chunk([FIG6, FIG6], 3)),
    "closure_errors": (
        core_checks,
        "closure_batch",
        lambda: orbits.closure_errors(FIG6, [0.01, -0.01], 1),
    ),
    "verify_body": (core_checks, "check_batch", lambda: orbits.checks.verify_body(FIG6, 2)),
}


@pytest.mark.parametrize("call", sorted(CALLS))
@pytest.mark.parametrize("count", sorted({1, TOP}))
def test_the_count_reaches_kernels_launched_from_another_thread(
    call, count, monkeypatch, restore_threads
):
    """numba's own count is per Python thread: set_num_threads(1) in the main
    thread did not reach a search launched from another (2 threads ran)."""
    module, name, run = CALLS[call]
    seen = _threads_seen(monkeypatch, module, name)
    orbits.set_num_threads(count)
    errors = []

    def work():
        try:
            run()
        except Exception as error:  # noqa: BLE001 - re-raised below
            errors.append(error)

    other = threading.Thread(target=work)
    other.start()
    other.join()
    if errors:
        raise errors[0]
    run()  # and from this thread
    assert seen and set(seen) == {count}


def _bench_with_numba_threads(value):
    """``orbits bench --quick --only phase --no-load-check --json`` with
    ``NUMBA_NUM_THREADS=value`` in a fresh process (numba reads it at import)."""
    return subprocess.run(
        [sys.executable, "-m", "orbits", "bench", "--quick", "--only", "phase"]
        + ["--no-load-check", "--json"],
        capture_output=True,
        text=True,
        timeout=300,
        env=dict(os.environ, NUMBA_NUM_THREADS=value),
    )


@pytest.mark.parametrize(
    "value",
    ["1_0", "+1_0", "\u0663", "\uff11\uff10", "0", "-1"],
    ids=["1_0", "+1_0", "arabic-indic-3", "fullwidth-10", "0", "-1"],
)
def test_a_thread_count_that_is_not_plain_ascii_digits_is_refused(value):
    """int() reads 1_0 as 10 and an Arabic-Indic three as 3, and so does numba:
    ``NUMBA_NUM_THREADS=1_0 orbits bench`` ran on "10 numba threads".  Refused
    in one line, exit 2, before numba is loaded (as 0 and -1 were)."""
    result = _bench_with_numba_threads(value)
    assert result.returncode == 2, result.stderr
    assert result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr
    assert lines[0].startswith(
        f"orbits: error: NUMBA_NUM_THREADS={value!r} is not a positive whole number"
    )


@pytest.mark.parametrize("value, count", [("2", 2), ("+3", 3), (" 2\n", 2)])
def test_a_plain_ascii_thread_count_reaches_numba(value, count):
    """ASCII digits with an optional sign and surrounding whitespace, as a
    count is typed on the command line, are still read."""
    result = _bench_with_numba_threads(value)
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)["machine"]["numba_threads"] == count


# ------------------------------------------- serial twins (orbits.core.launch)


def _run_script(source, env=None, timeout=240):
    return subprocess.run(
        [sys.executable, "-c", source],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=dict(os.environ, **(env or {})),
    )


FORK_SCRIPT = """
import multiprocessing as mp
import numba, numpy as np, orbits
from orbits.core import launch

b = orbits.Body.preset("fig6")
big = np.linspace(0.01, 1.5, 30_000)  # above SERIAL_BELOW: a parallel launch


def work(i):
    return (
        launch.serial_only(),
        orbits.total_phase(b, big).tobytes(),
        float(orbits.total_phase(b, 0.5)),
        orbits.catalog(b, n_max=4)["dtheta"].to_numpy().tobytes(),
    )


if __name__ == "__main__":
    first = orbits.total_phase(b, 0.5), orbits.catalog(b, n_max=4)
    try:
        numba.threading_layer()
        started = True
    except ValueError:
        started = False
    print("small calls started a threading layer:", started)
    {parent_runs_big}
    with mp.get_context("fork").Pool(2) as pool:
        results = pool.map_async(work, range(4)).get(timeout=180)
    expected = work(0)[1:]  # after the fork, in the parent
    print("children serial only:", sorted({r[0] for r in results}))
    print("children agree:", all(r[1:] == expected for r in results))
"""


# the parent's calls, and whether they start numba's threading layer (a
# large call on one numba thread runs the serial twin and starts nothing)
PARENT_RUNS = {
    "small calls": ("pass", False),
    "a parallel call": ("orbits.total_phase(b, big)", TOP > 1),
    # numba's set/get_num_threads start its layer without any kernel
    "set_num_threads": ("orbits.set_num_threads(orbits.get_num_threads())", True),
    "a large call refused": (
        "try:\n        orbits.total_phase([1.0, 1.0, 2.0], big)\n"
        "    except orbits.SymmetricTopError:\n        pass",
        TOP > 1,
    ),
}


@pytest.mark.skipif(not hasattr(os, "fork"), reason="no fork on this platform")
@pytest.mark.parametrize("parent", sorted(PARENT_RUNS))
def test_a_forked_pool_works_after_the_parent_computed(parent):
    """GNU OpenMP cannot run in a child forked from a process that used it:
    after any orbits call in the parent, every child of a fork Pool (Linux's
    default start method) printed "Terminating: fork() called from a process
    already using GNU OpenMP" and Pool.map waited forever.  Small calls now
    never start the threading layer, and a child forked after a parallel
    launch runs the serial twins, with the same numbers."""
    code, started = PARENT_RUNS[parent]
    source = FORK_SCRIPT.replace("{parent_runs_big}", code)
    result = _run_script(source)
    assert result.returncode == 0, result.stderr
    assert "Terminating" not in result.stderr
    lines = result.stdout.splitlines()
    assert "small calls started a threading layer: False" in lines
    assert f"children serial only: [{started}]" in lines
    assert "children agree: True" in lines


def test_serial_and_parallel_twins_give_the_same_numbers(restore_threads):
    """The serial twin (one thread: threads_for picks it) and the parallel
    kernel are the same source: the same bits for every element."""
    body = orbits.Body.preset("t-handle")
    theta = np.concatenate([np.linspace(0.0, np.pi / 2, 25_000), [1e-300, np.pi / 2 - 1e-9]])
    spins = np.column_stack([np.cos(theta), np.zeros_like(theta), np.sin(theta)])
    times = np.linspace(0, 50, 25_000)
    runs = []
    for count in sorted({1, TOP}):  # on one numba thread both runs are serial
        orbits.set_num_threads(count)
        runs.append(
            (
                orbits.total_phase(body, theta).tobytes(),
                orbits.phases(body, theta).select_dtypes(float).to_numpy().tobytes(),
                orbits.spin_phases(body, spins)["total_phase"].to_numpy().tobytes(),
                orbits.Motion.from_spin(body, 0.7).state(times).omega.tobytes(),
            )
        )
    assert all(run == runs[0] for run in runs)


WORKQUEUE_SCRIPT = """
from concurrent.futures import ThreadPoolExecutor
import numba, numpy as np, orbits

b = orbits.Body.preset("fig6")
big = np.linspace(0.01, 1.5, 30_000)
bodies = [b.moments, (1.0, 2.0, 2.5), (0.3, 0.5, 0.7)]


def work(i):
    branch, level, offset, counts, info = orbits.search_bodies(bodies, [2 * np.pi * 2.5])
    valid = np.arange(branch.shape[1]) < counts[:, None]  # slots beyond are unset
    return (
        orbits.total_phase(b, big).tobytes(),
        offset[valid].tobytes(),
        branch[valid].tobytes(),
        counts.tobytes(),
    )


numba.get_num_threads()  # starts the layer (with one thread no kernel would)
expected = work(0)
with ThreadPoolExecutor(8) as pool:
    results = list(pool.map(work, range(32)))
print("layer:", numba.threading_layer())
print("threads agree:", all(r == expected for r in results))
"""


def test_concurrent_calls_under_the_workqueue_layer():
    """numba's fallback layer aborts the process ("Concurrent access") when two
    Python threads launch parallel kernels at once; there one launch runs at
    a time and the others take the serial twin."""
    result = _run_script(WORKQUEUE_SCRIPT, env={"NUMBA_THREADING_LAYER": "workqueue"})
    assert result.returncode == 0, result.stderr
    assert "layer: workqueue" in result.stdout.splitlines()
    assert "threads agree: True" in result.stdout.splitlines()


# ------------------------------------------------------------------------
# Each test below kills a mutant of orbits/threads.py that passed the suite (a
# mutation audit of the core kernels, 2026-11-29: 49 mutants, 11 survivors
# that changed an output).


def test_using_threads_restores_the_count():
    """TH1: using_threads(count) must restore the previous count on exit, also
    after an exception (mutant: the restore is dropped)."""
    import numba

    from orbits.threads import get_num_threads, set_num_threads, using_threads

    top = numba.config.NUMBA_NUM_THREADS
    if top < 2:
        pytest.skip("needs NUMBA_NUM_THREADS >= 2")
    before = get_num_threads()
    try:
        set_num_threads(top)
        with using_threads(1):
            assert get_num_threads() == 1
        assert get_num_threads() == top and numba.get_num_threads() == top
        with pytest.raises(RuntimeError):
            with using_threads(1):
                raise RuntimeError("inside")
        assert get_num_threads() == top
    finally:
        set_num_threads(before)
