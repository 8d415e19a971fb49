"""Regenerate the image-regression baselines of ``tests/test_figure_images.py``.

Run from the repository root after an intended change to a figure::

    PYTHONPATH=. python tests/baseline/regenerate.py

then look at every PNG written here and commit them with ``versions.txt``
(the matplotlib minor and FreeType versions that drew them; the test skips
on any other pair).
"""

import importlib.util
from pathlib import Path

HERE = Path(__file__).resolve().parent


def _cases_module():
    spec = importlib.util.spec_from_file_location(
        "test_figure_images", HERE.parent / "test_figure_images.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def cases():
    """The names of the figures compared (one baseline ``<name>.png`` each)."""
    return list(_cases_module().CASES)


def main():
    from orbits.atomic import atomic_path

    module = _cases_module()
    for name in module.CASES:
        with atomic_path(HERE / f"{name}.png") as temporary:
            module.render(name, temporary)
        print(f"wrote {HERE / name}.png")
    (HERE / "versions.txt").write_text(module.versions() + "\n")
    print(f"baselines drawn with {module.versions()}")


if __name__ == "__main__":
    main()
