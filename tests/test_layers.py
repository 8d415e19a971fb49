"""Layers only point down: no module of ``orbits`` imports a higher one.

The same contract as ``[tool.importlinter]`` in pyproject.toml (run by
``lint-imports`` in .ci/run), checked here from the source alone, so that it
also runs where import-linter is not installed.  Every ``import`` and
``from ... import`` in every module is read from its syntax tree, those
inside functions included, and its target is resolved to a layer.
"""

import ast
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "orbits"

# Top to bottom; a module may import modules of lower rows only.  The modules
# of one row may not import each other.  A package (core, cli) is one unit:
# its modules may import each other.
LAYERS = [
    ["__main__"],
    ["cli"],
    ["bench"],
    ["animate"],
    ["animation_scene"],
    ["figures"],
    ["plotting"],
    ["survey"],
    ["catalog"],
    ["tumbling"],
    ["checks"],
    ["search"],
    ["motion"],
    ["phases"],
    ["bodies"],
    ["limits", "cells", "units"],
    ["_args", "atomic", "threads", "device"],
    ["core", "errors", "_version", "startup"],
]
RANK = {name: len(LAYERS) - k for k, row in enumerate(LAYERS) for name in row}


def unit_of(module):
    """``orbits.core.phase`` -> ``core``; ``orbits`` itself -> ``None``."""
    parts = module.split(".")
    assert parts[0] == "orbits", module
    return parts[1] if len(parts) > 1 else None


def module_name(path):
    parts = path.relative_to(ROOT).with_suffix("").parts
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def imported_modules(path):
    """``(line, target)`` for every import of an ``orbits`` module in ``path``."""
    name = module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(parts + ([base] if base else []))
            for alias in node.names:
                # "from orbits import figures" imports the module orbits.figures
                candidate = f"{base}.{alias.name}"
                is_module = (ROOT / Path(*candidate.split("."))).with_suffix(".py").exists() or (
                    ROOT / Path(*candidate.split(".")) / "__init__.py"
                ).exists()
                found.append((node.lineno, candidate if is_module else base))
    return [(line, target) for line, target in found if target.split(".")[0] == "orbits"]


def upward_imports(paths):
    """Each import that does not point down, as ``'orbits.x:12 imports orbits.y'``."""
    wrong = []
    for path in paths:
        name = module_name(path)
        unit = unit_of(name)
        if unit is None:  # orbits/__init__.py: the public re-exports, above all
            continue
        for line, target in imported_modules(path):
            other = unit_of(target)
            if other == unit:  # inside one package (core, cli)
                continue
            if other is None or RANK[other] >= RANK[unit]:
                wrong.append(f"{name}:{line} imports {target}")
    return wrong


def package_modules():
    return sorted(PACKAGE.rglob("*.py"))


def test_every_module_has_a_layer():
    units = {unit_of(module_name(path)) for path in package_modules()} - {None}
    assert units == set(RANK), "a new module needs a row in LAYERS and in pyproject.toml"


def test_no_module_imports_a_higher_layer():
    assert upward_imports(package_modules()) == []


def test_no_private_name_crosses_a_module_line():
    crossing = []
    for path in package_modules():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                crossing += [
                    f"{module_name(path)}:{node.lineno} imports {alias.name}"
                    for alias in node.names
                    if alias.name.startswith("_") and not alias.name.startswith("__")
                ]
    assert crossing == []


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        # a function-level import of a higher layer is caught ...
        (
            "def f():\n    from .catalog import catalog\n",
            ["orbits.bodies:2 imports orbits.catalog"],
        ),
        ("import orbits.survey\n", ["orbits.bodies:1 imports orbits.survey"]),
        ("from . import cli\n", ["orbits.bodies:1 imports orbits.cli"]),
        ("from orbits import Body\n", ["orbits.bodies:1 imports orbits"]),
        # ... and so is a sibling of the same row, and one above in the row order
        ("from .phases import phases\n", ["orbits.bodies:1 imports orbits.phases"]),
        # downward imports pass
        ("from .core import phase\nfrom .limits import memory_budget\n", []),
    ],
)
def test_the_check_fails_on_an_upward_import(tmp_path, monkeypatch, source, expected):
    fake_root = tmp_path
    (fake_root / "orbits").mkdir()
    for name in ("catalog", "survey", "cli", "phases", "limits"):
        (fake_root / "orbits" / f"{name}.py").write_text("")
    (fake_root / "orbits" / "core").mkdir()
    (fake_root / "orbits" / "core" / "__init__.py").write_text("")
    (fake_root / "orbits" / "core" / "phase.py").write_text("")
    module = fake_root / "orbits" / "bodies.py"
    module.write_text(source)
    monkeypatch.setitem(globals(), "ROOT", fake_root)
    assert upward_imports([module]) == expected


def test_pyproject_contract_names_the_same_layers():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]
    (contract,) = config["contracts"]
    assert config["root_package"] == "orbits" and contract["type"] == "layers"
    rows = [
        sorted(name.strip().removeprefix("orbits.") for name in row.split("|"))
        for row in contract["layers"]
    ]
    assert rows == [sorted(row) for row in LAYERS]


def test_animation_geometry_needs_no_matplotlib():
    """orbits.animation_scene computes every frame without importing matplotlib."""
    import subprocess
    import sys

    code = (
        "import sys\n"
        "from orbits import Body\n"
        "from orbits.animate import flip_motion\n"
        "from orbits.animation_scene import PoinsotScene\n"
        "import numpy as np\n"
        "motion = flip_motion(Body.preset('fig6'))\n"
        "scene = PoinsotScene(motion, np.linspace(0.0, motion.period, 5))\n"
        "data = scene.frame(4)\n"
        "import math\n"
        "turns = abs(motion.total_phase()) / (2 * math.pi)\n"
        "steps = math.ceil(max(256, 128 * turns) / 4)  # a period over 4 intervals\n"
        "assert scene.subsamples == steps, (scene.subsamples, steps)\n"
        "assert data.herpolhode.shape == (4 * steps + 1, 3)\n"
        "assert not [m for m in sys.modules if m.split('.')[0] in ('matplotlib', 'mpl_toolkits')]\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=ROOT,
        env={**__import__("os").environ, "PYTHONPATH": str(ROOT)},
    )
    assert result.returncode == 0, result.stderr
