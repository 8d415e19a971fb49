"""orbits.core.kernel_cache: a kernel cached by numba is recompiled when a
helper it calls from another file of its package changes.

numba stamps each cached kernel with its own file only, so a kernel that
inlines a helper from another file keeps running the old helper from the
cache after that file changes (a silent wrong number after a ``git pull``
into an editable install).  These tests build a two-file package in a
temporary directory and run it in fresh processes.
"""

import importlib
import os
import pkgutil
import subprocess
import sys
from pathlib import Path

import pytest

import orbits.core
from orbits.core import kernel_cache, launch


def _write_package(root, helper_value):
    package = root / "toy"
    package.mkdir(exist_ok=True)
    (package / "__init__.py").write_text(
        "import os\n"
        "from orbits.core.kernel_cache import track_package\n"
        "if os.environ['TOY_TRACK'] == '1':\n"
        "    track_package(os.path.dirname(__file__))\n"
    )
    (package / "helper.py").write_text(
        f"from numba import njit\n\n\n@njit(cache=True)\ndef value():\n    return {helper_value!r}\n"
    )
    (package / "kernel.py").write_text(
        "from numba import njit\n\nfrom .helper import value\n\n\n"
        "@njit(cache=True)\ndef kernel(x):\n    return x + value()\n"
    )


def _run(root, track):
    """``kernel(1.0)`` and the kernel's cache hits, in a fresh process."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_CACHE")}
    env["PYTHONPATH"] = os.pathsep.join([str(root), os.path.dirname(orbits.core.__path__[0])])
    env["TOY_TRACK"] = "1" if track else "0"
    code = (
        "from toy.kernel import kernel\n"
        "print(kernel(1.0), sum(kernel.stats.cache_hits.values()))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=root, env=env, capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    value, hits = done.stdout.split()
    return float(value), int(hits)


def test_a_changed_helper_recompiles_the_kernels_of_other_files(tmp_path):
    untracked, tracked = tmp_path / "untracked", tmp_path / "tracked"
    for root in (untracked, tracked):
        root.mkdir()
        _write_package(root, 1.0)
    assert _run(untracked, track=False) == (2.0, 0)
    assert _run(tracked, track=True) == (2.0, 0)
    # unchanged: both load the kernel from the cache
    assert _run(untracked, track=False) == (2.0, 1)
    assert _run(tracked, track=True) == (2.0, 1)
    for root in (untracked, tracked):
        _write_package(root, 5.0)  # only helper.py changes
    stale = _run(untracked, track=False)[0]
    if stale != 2.0:
        pytest.skip("this numba recompiles the kernel itself: the scenario tests nothing")
    # numba alone: the old helper from the cache; with the package tracked,
    # compiled again with the new one, then cached again
    assert _run(tracked, track=True) == (6.0, 0)
    assert _run(tracked, track=True) == (6.0, 1)


def test_every_cached_kernel_of_orbits_core_is_tracked():
    """Registered before any kernel is defined, so no kernel escapes it;
    a numba without the locator hook fails here, not silently."""
    from numba.core.registry import CPUDispatcher

    checked = 0
    for info in pkgutil.iter_modules(orbits.core.__path__):
        if info.name == "cuda":  # numba-cuda's kernels (not cached)
            continue
        module = importlib.import_module(f"orbits.core.{info.name}")
        found = []
        for value in vars(module).values():
            if isinstance(value, launch.ParallelKernel):  # both twins are cached
                found += [value.parallel, value.serial]
            else:
                found.append(value)
        for value in found:
            if isinstance(value, CPUDispatcher) and value.__module__ == module.__name__:
                if (
                    getattr(value, "_cache", None) is None
                    or type(value._cache).__name__ == "NullCache"
                ):
                    continue
                assert kernel_cache.tracking(value), f"{module.__name__}.{value.__name__}"
                checked += 1
    assert checked >= 65  # 15 parallel kernels have two twins each


def test_the_fingerprint_follows_every_file(tmp_path):
    (tmp_path / "a.py").write_text("x = 1\n")
    (tmp_path / "b.py").write_text("y = 2\n")
    (tmp_path / "notes.txt").write_text("not source\n")
    first = kernel_cache.sources_fingerprint(tmp_path)
    assert kernel_cache.sources_fingerprint(tmp_path) == first
    (tmp_path / "notes.txt").write_text("changed\n")
    assert kernel_cache.sources_fingerprint(tmp_path) == first
    (tmp_path / "b.py").write_text("y = 3\n")  # same size, other content
    second = kernel_cache.sources_fingerprint(tmp_path)
    assert second != first
    (tmp_path / "b.py").rename(tmp_path / "c.py")  # a file renamed
    assert kernel_cache.sources_fingerprint(tmp_path) not in (first, second)


def test_a_private_temporary_cache_where_no_other_can_be_written(tmp_path, monkeypatch):
    """A read-only install with HOME unset or read-only: numba found no
    locator and 'import orbits' failed (RuntimeError: cannot cache function
    'cel': no locator available)."""
    import tempfile

    from orbits.core import elliptic

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    monkeypatch.setattr(kernel_cache._IMPL, "_locator_classes", [kernel_cache.PackageLocator])
    function = elliptic.cel.py_func
    source = function.__code__.co_filename
    locator = kernel_cache.PackageLocator.from_function(function, source)
    root = tmp_path / f"orbits-numba-{os.getuid()}"
    assert locator.get_cache_path().startswith(str(root))
    assert (root.stat().st_mode & 0o777) == 0o700
    # never a directory another user could have planted (numba's index is a
    # pickle): the process compiles into a fresh private one of its own
    monkeypatch.setattr(kernel_cache, "_PROCESS_DIRECTORY", [])
    root.chmod(0o777)
    fresh = kernel_cache.PackageLocator.from_function(function, source).get_cache_path()
    own = Path(fresh).parent
    assert own != root and own.parent == tmp_path and own.name.startswith("orbits-numba-run-")
    assert (own.stat().st_mode & 0o777) == 0o700 and own.stat().st_uid == os.getuid()
    root.chmod(0o700)
    os.rename(root, tmp_path / "real")
    root.symlink_to(tmp_path / "real")
    again = kernel_cache.PackageLocator.from_function(function, source).get_cache_path()
    assert Path(again).parent == own


# ------------------------------------------------------------------------
# Each test below kills a mutant of orbits/core/launch.py that passed the suite (a
# mutation audit of the core kernels, 2026-11-29: 49 mutants, 11 survivors
# that changed an output).


def test_serial_twin_never_loads_the_parallel_code_from_the_cache(tmp_path):
    """L1: the serial twin is compiled under its own name ``<name>_serial``,
    so it never shares numba's on-disk cache entry with the parallel one
    (whose key does not include ``parallel``).  Process 1 runs the parallel
    kernel (filling the cache); process 2 runs only the serial twin and must
    not start numba's threading layer (mutant: same name, the serial twin
    loads the cached parallel code and starts the layer)."""
    import os
    import subprocess
    import sys

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    # this tree's orbits first (not whatever the environment installed)
    tree = str(Path(__file__).resolve().parents[1])
    env["PYTHONPATH"] = tree + os.pathsep + env.get("PYTHONPATH", "")
    first = (
        "import numpy as np\n"
        "from orbits.core.tasks import start_threads\n"
        "out = np.zeros(64); start_threads.parallel(out); assert (out == 1).all()\n"
    )
    second = (
        "import numpy as np, numba\n"
        "from orbits.core.tasks import start_threads\n"
        "out = np.zeros(64); start_threads.serial(out); assert (out == 1).all()\n"
        "try:\n"
        "    numba.threading_layer(); print('STARTED')\n"
        "except ValueError:\n"
        "    print('NOT STARTED')\n"
    )
    for code in (first, second):
        done = subprocess.run(
            [sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300
        )
        assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "NOT STARTED"
