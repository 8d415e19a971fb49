"""Start-up: `import orbits` and `orbits --help` load no heavy module.

No timing here (the machine is shared): the import-time ratio to
``import numpy`` is measured by ``orbits bench --only startup``.  What is
tested is the cause of a slow start, deterministically: which modules a
fresh interpreter has loaded.
"""

import json
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
