"""Start-up: `import orbits` and `orbits --help` load no heavy module.

No timing here (the machine is shared): the import-time ratio to
``import numpy`` is measured by ``orbits bench --only startup``.  What is
tested is the cause of a slow start, deterministically: which modules a
fresh interpreter has loaded.
"""

import json
import os
import subprocess
import sys

import pytest

HEAVY = ("numba", "scipy", "pandas", "matplotlib", "tqdm", "llvmlite")


def loaded_after(code):
    script = (
        code + "\nimport sys, json\n"
        "print(json.dumps(sorted({m.split('.')[0] for m in sys.modules})))"
    )
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr
    return set(json.loads(result.stdout.strip().splitlines()[-1]))


def test_import_orbits_loads_nothing_heavy():
    assert not loaded_after("import orbits") & set(HEAVY + ("numpy",))


def test_help_loads_nothing_heavy():
    code = (
        "from orbits.cli import build_parser\n"
        "try:\n    build_parser().parse_args(['--help'])\n"
        "except SystemExit:\n    pass\n"
        "for sub in ('phase', 'catalog', 'verify', 'bench'):\n"
        "    try:\n        build_parser().parse_args([sub, '--help'])\n"
        "    except SystemExit:\n        pass"
    )
    assert not loaded_after(code) & set(HEAVY)


@pytest.mark.parametrize(
    "name",
    ["Body", "phases", "catalog", "Motion", "verify", "spins_with_total_phase", "set_num_threads"],
)
def test_public_names_load_on_first_use(name):
    import orbits

    assert name in orbits.__all__
    assert callable(getattr(orbits, name))


def test_a_submodule_import_keeps_the_function_of_the_same_name():
    code = (
        "import orbits.phases, orbits.catalog, orbits\n"
        "assert callable(orbits.phases) and callable(orbits.catalog)\n"
        "assert not isinstance(orbits.phases, type(orbits))"
    )
    loaded_after(code)


def test_the_package_pickles_by_reference():
    """A notebook function that uses ``orbits.`` could not be sent to dask
    workers: cloudpickle sends a module by reference only when its type is
    exactly ModuleType ("cannot pickle '_Package' object")."""
    import pickle

    import orbits

    assert pickle.loads(pickle.dumps(orbits)) is orbits
    cloudpickle = pytest.importorskip("cloudpickle")

    def user_function():  # as defined in __main__ or a notebook cell
        return float(orbits.total_phase(orbits.Body((0.26, 0.55, 0.793662)), 0.5))

    sent = cloudpickle.loads(cloudpickle.dumps(user_function))
    assert sent() == user_function()
    assert cloudpickle.loads(cloudpickle.dumps(orbits)) is orbits


def test_every_public_name_resolves():
    import orbits

    for name in orbits.__all__:
        getattr(orbits, name)
    with pytest.raises(AttributeError):
        orbits.no_such_name


@pytest.mark.parametrize("value", ["0", "-2", "abc", ""])
def test_an_unusable_numba_thread_count_is_one_line(value):
    """NUMBA_NUM_THREADS=0 was a ValueError traceback from inside numba's import;
    a value numba cannot read was a warning holding a traceback, then ignored."""
    import os

    env = dict(os.environ, NUMBA_NUM_THREADS=value)
    result = subprocess.run(
        [sys.executable, "-m", "orbits", "phase", "--preset", "fig6", "--theta", "0.5"],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
    )
    assert result.returncode == 2, result.stderr
    assert result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr
    assert lines[0].startswith(f"orbits: error: NUMBA_NUM_THREADS={value!r} is not a positive")


def test_the_version_is_the_installed_metadata():
    """orbits._version is the one place (pyproject reads it): no drift."""
    from importlib.metadata import version

    import orbits

    assert orbits.__version__ == version("orbits")


def test_the_collector_is_held_and_released_once(monkeypatch):
    import gc

    from orbits import startup

    monkeypatch.setattr(startup, "_held", False)
    assert gc.isenabled()
    frozen = gc.get_freeze_count()
    try:
        startup.hold_collector()
        assert not gc.isenabled() and startup.collector_held()
        assert startup.release_collector() is True
        assert gc.isenabled() and not startup.collector_held()
        assert gc.get_freeze_count() >= frozen
        assert startup.release_collector() is False  # once
    finally:
        gc.unfreeze()
        gc.enable()


def test_a_collector_the_caller_turned_off_stays_off(monkeypatch):
    import gc

    from orbits import startup

    monkeypatch.setattr(startup, "_held", False)
    gc.disable()
    try:
        startup.hold_collector()
        assert not startup.collector_held()
        assert startup.release_collector() is False
        assert not gc.isenabled()
    finally:
        gc.enable()


def test_deferred_modules_load_on_first_use():
    code = (
        "import sys\n"
        "from orbits import startup\n"
        "assert startup.defer_unused_modules() == ['numpy.f2py', 'numpy.testing']\n"
        "import numpy\n"
        "f2py = getattr(numpy, 'f2py')\n"  # as SciPy's copy of the namespace
        "assert type(f2py).__name__ == '_LazyModule'\n"  # nothing run yet
        "assert 'numpy.f2py.crackfortran' not in sys.modules\n"
        "import numpy.f2py\n"  # an import statement loads it
        "assert numpy.f2py is f2py and type(f2py).__name__ == 'module'\n"
        "assert callable(f2py.run_main)\n"
        "from numpy.testing import assert_allclose\n"
        "assert_allclose(1.0, 1.0)\n"
        "assert startup.defer_unused_modules() == []  # already imported\n"
        "assert startup.defer_unused_modules(['no_such_module.x']) == []\n"
    )
    loaded_after(code)


@pytest.mark.parametrize(
    "argv",
    [
        ["phase", "--preset", "fig6", "--theta", "0.5"],
        ["survey", "--resolution", "6", "--n-max", "3", "--out", "{tmp}/s"],
    ],
)
def test_the_command_line_releases_the_collector(argv, tmp_path):
    """entry() holds the collector through the start-up; the command line
    (before a command) or the survey (after its first chunk) turns it on."""
    argv = [a.format(tmp=tmp_path) for a in argv]
    code = (
        "import gc, sys\n"
        "from orbits.__main__ import entry\n"
        f"sys.argv = ['orbits'] + {argv!r}\n"
        "assert entry() == 0\n"
        "assert gc.isenabled() and gc.get_freeze_count() > 0\n"
        "from orbits import startup\n"
        "assert not startup.collector_held()\n"
        "assert type(sys.modules['numpy.f2py']).__name__ == '_LazyModule'\n"
    )
    loaded_after(code)


def _run_script(body, argv):
    script = (
        "import atexit, sys, threading, time\n"
        "from orbits.__main__ import run\n"
        f"sys.argv = ['orbits'] + {argv!r}\n" + body
    )
    return subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120
    )


@pytest.mark.parametrize(
    ("argv", "code"),
    [(["phase", "--preset", "fig6", "--theta", "0.5"], 0), (["phase", "--theta", "0.5"], 2)],
)
def test_the_quick_exit_flushes_and_runs_the_exit_handlers(argv, code):
    """run() ends the process without the heap's tear-down, but as an exit:
    the exit code, everything printed, the atexit handlers."""
    done = _run_script(
        "atexit.register(lambda: print('handler ran', flush=True))\n"
        "sys.stdout.write('unflushed ')\n"
        "sys.exit(run())\n",
        argv,
    )
    assert done.returncode == code, done.stderr
    assert done.stdout.startswith("unflushed ")
    assert done.stdout.rstrip().endswith("handler ran")
    if code == 0:
        assert "total" in done.stdout
    else:
        assert done.stderr.startswith("orbits: error:") and len(done.stderr.splitlines()) == 1


def test_the_quick_exit_waits_for_a_running_thread():
    """A thread that is not a daemon (none of orbits' own) keeps the ordinary exit."""
    done = _run_script(
        "import orbits.__main__ as script\n"
        "over = threading.Event()\n"
        "entry = script.entry\n"
        "script.entry = lambda: (entry(), over.set())[0]\n"
        "def late():\n"  # still working when the command is over
        "    over.wait()\n"
        "    time.sleep(0.3)\n"
        "    print('thread finished', flush=True)\n"
        "threading.Thread(target=late).start()\n"
        "sys.exit(run())\n",
        ["phase", "--preset", "fig6", "--theta", "0.5"],
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.rstrip().endswith("thread finished")


def test_blas_threads_sleep_in_a_command_and_a_user_setting_is_kept():
    code = (
        "import os, sys\n"
        "from orbits.__main__ import entry\n"
        "sys.argv = ['orbits', 'phase', '--preset', 'fig6', '--theta', '0.5']\n"
        "assert entry() == 0\n"
        "print(os.environ['OPENBLAS_THREAD_TIMEOUT'])\n"
    )
    for given, expected in ((None, "4"), ("12", "12")):
        env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_THREAD_TIMEOUT"}
        if given is not None:
            env["OPENBLAS_THREAD_TIMEOUT"] = given
        done = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=env
        )
        assert done.returncode == 0, done.stderr
        assert done.stdout.strip().splitlines()[-1] == expected


def test_blas_threads_use_no_cpu_while_idle():
    """OpenBLAS's worker threads (one per extra CPU) spun 0.1 s each at load."""
    if len(os.sched_getaffinity(0)) < 2:
        pytest.skip("one CPU: OpenBLAS starts no worker thread")
    code = (
        "import os, sys\n"
        "from orbits import startup\n"
        "startup.calm_blas_threads()\n"
        "import numpy, scipy.linalg, time\n"
        "time.sleep(0.3)\n"
        "me = os.getpid()\n"
        "ticks = 0\n"
        "for tid in os.listdir('/proc/self/task'):\n"
        "    if int(tid) != me:\n"
        "        fields = open(f'/proc/self/task/{tid}/stat').read().rsplit(')', 1)[1].split()\n"
        "        ticks += int(fields[11]) + int(fields[12])\n"
        "print(ticks / os.sysconf('SC_CLK_TCK'))\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_THREAD_TIMEOUT"}
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=env
    )
    assert done.returncode == 0, done.stderr
    # spinning threads take ~0.1 CPU s each; sleeping ones a few ticks at most
    assert float(done.stdout.strip()) < 0.03


def test_a_survey_with_nothing_to_compute_and_a_check_release_the_collector(tmp_path):
    """The survey releases the start-up's hold after its first chunk; a rerun
    that finds every chunk done, and --check, read parts without the hold."""
    out = str(tmp_path / "s")
    runs = [
        ["survey", "--resolution", "6", "--n-max", "3", "--out", out],
        ["survey", "--resolution", "6", "--n-max", "3", "--out", out],  # all done
        ["survey", "--check", out],
    ]
    code = (
        "import gc, sys\n"
        "import orbits.startup as startup\n"
        "from orbits.__main__ import entry\n"
        "import orbits.survey.runner as runner\n"
        "seen = []\n"
        "report = runner.survey_report\n"
        "def watched(*args, **kwargs):\n"
        "    seen.append(gc.isenabled())\n"
        "    return report(*args, **kwargs)\n"
        "runner.survey_report = watched\n"
        "import orbits.survey.report as reports\n"
        "check = reports.check_survey\n"
        "def checked(*args, **kwargs):\n"
        "    seen.append(gc.isenabled())\n"
        "    return check(*args, **kwargs)\n"
        "import orbits.survey\n"
        "orbits.survey.check_survey = checked\n"
        f"for argv in {runs!r}:\n"
        "    sys.argv = ['orbits'] + argv\n"
        "    assert entry() == 0\n"
        "    assert gc.isenabled() and not startup.collector_held()\n"
        "assert seen == [True, True, True], seen\n"
    )
    loaded_after(code)


def test_a_command_that_fails_before_its_first_chunk_gives_the_collector_back(tmp_path):
    """The survey holds the collector until its first chunk; a refusal before
    it (exit 2) must not leave the caller's process without a collector."""
    code = (
        "import gc, sys\n"
        "from orbits.__main__ import entry\n"
        "from orbits import startup\n"
        "sys.argv = ['orbits', 'survey', '--resolution', '6', '--n-max', '3']\n"
        "assert entry() == 2\n"  # no --out
        "assert gc.isenabled() and not startup.collector_held()\n"
    )
    loaded_after(code)
