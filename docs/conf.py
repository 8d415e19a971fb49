"""Sphinx configuration of the orbits documentation.

Build (from the repository root, with ``pip install ".[docs]"``)::

    python -m sphinx -W --keep-going -b html docs docs/_build/html

The gallery (``docs/examples/plot_*.py``) runs at build time; its output
goes to ``docs/auto_examples`` and the API stubs to ``docs/generated``
(both generated, not committed).
"""

import os
import re
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
# document the package of this checkout, not an installed copy
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(HERE / "_ext"))
# the gallery scripts run in this process: no windows, deterministic output
os.environ.setdefault("MPLBACKEND", "Agg")

import orbits  # noqa: E402

# The Markdown pages link the committed figures as `figures/...` (as seen
# from the repository root); a link docs/figures -> ../figures (made here,
# not committed) lets Sphinx find them under the same paths.
_figures = HERE / "figures"
if not _figures.exists() and not _figures.is_symlink():
    _figures.symlink_to(Path("..") / "figures", target_is_directory=True)

project = "orbits"
author = "orbits developers"
copyright = "2026, orbits developers"
release = orbits.__version__
version = ".".join(release.split(".")[:2])

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
    # docs/_ext: the catalog schema from the code, the API reference check
    "orbits_api",
]

# MathJax from the package sphinx-mathjax-offline (part of the `docs` extra):
# the built site renders formulas without network access.  Without it
# Sphinx falls back to its default MathJax URL.
try:
    import importlib

    importlib.import_module("sphinx-mathjax-offline")
except ImportError:  # pragma: no cover - docs extra not installed
    pass
else:
    extensions.append("sphinx-mathjax-offline")

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
templates_path = ["_templates"]
exclude_patterns = [
    "_build",
    "examples/GALLERY_HEADER.rst",
    "auto_examples/*.ipynb",
    "auto_examples/*.py",
    "Thumbs.db",
    ".DS_Store",
]

# -- MyST -------------------------------------------------------------
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
# anchors for the headings of the README sections included in the pages
myst_heading_anchors = 3

# -- autodoc / autosummary / numpydoc ----------------------------------
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"member-order": "bysource"}
autodoc_typehints = "none"
numpydoc_show_class_members = True
numpydoc_show_inherited_class_members = False
numpydoc_class_members_toctree = False
numpydoc_attributes_as_param_list = True
# numpydoc parses the docstrings; its validation is a lint, not a build error
numpydoc_validation_checks = set()

# -- sphinx-gallery ----------------------------------------------------
sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    # ORBITS_GALLERY_PATTERN (a regex) runs only some examples: for quick
    # local builds while writing pages; CI and releases leave it unset
    "filename_pattern": os.environ.get("ORBITS_GALLERY_PATTERN", r"/plot_"),
    "within_subsection_order": "FileNameSortKey",
    # embed matplotlib FuncAnimations (kept in a variable) as JS players
    "matplotlib_animations": True,
    "abort_on_example_error": True,
    "download_all_examples": False,
    "remove_config_comments": True,
    "show_memory": False,
    "reference_url": {"orbits": None},
    "doc_module": ("orbits",),
    # which examples use which name: each API entry lists them (the
    # minigallery of docs/_templates/autosummary)
    "backreferences_dir": "generated/backreferences",
    "min_reported_time": 1,
    # after sphinx-gallery's own reset of matplotlib (docs/_ext)
    "reset_modules": ("matplotlib", "gallery_setup.reset_matplotlib"),
    "image_scrapers": ("gallery_setup.orbits_figure_scraper", "matplotlib"),
}

# -- HTML --------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"orbits {release}"
html_static_path = ["_static"]
html_css_files = ["orbits.css"]
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "navbar_align": "left",
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
    "secondary_sidebar_items": ["page-toc"],
}
# no (empty) section navigation beside the pages: their formulas, tables and
# the gallery's code need the width
html_sidebars = {
    page: []
    for page in (
        "index",
        "changelog",
        "auto_examples/plot_*",
        "cli",
        "api",
        "conventions",
        "catalog",
        "numerics",
        "checks",
        "errata",
        "benchmarks",
        "contributing",
    )
}
html_show_sourcelink = False


# -- docstrings: |x| is an absolute value, not a reST substitution -------
# Outside inline literals and roles, a bare "|" is escaped, so that the
# plain-text formulas of the docstrings ("|omega0| = 1") render as written.
_LITERAL = re.compile(r"``.+?``|:\w+:`[^`]*`|`[^`]*`")


def _escape_bars(text):
    parts, last = [], 0
    for match in _LITERAL.finditer(text):
        parts.append(re.sub(r"(?<!\\)\|", r"\|", text[last : match.start()]))
        parts.append(match.group(0))
        last = match.end()
    parts.append(re.sub(r"(?<!\\)\|", r"\|", text[last:]))
    return "".join(parts)


_MATH_DIRECTIVE = re.compile(r"^(\s*)\.\. math::")


def _absolute_values(app, what, name, obj, options, lines):
    """Escape bare bars, except in the LaTeX of ``.. math::`` blocks."""
    out, math_indent = [], None
    for line in lines:
        if math_indent is not None:
            indent = len(line) - len(line.lstrip())
            if not line.strip() or indent > math_indent:
                out.append(line)
                continue
            math_indent = None
        match = _MATH_DIRECTIVE.match(line)
        if match:
            math_indent = len(match.group(1))
            out.append(line)
        else:
            out.append(_escape_bars(line))
    lines[:] = out


def setup(app):
    app.connect("autodoc-process-docstring", _absolute_values)
