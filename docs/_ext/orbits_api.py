"""Sphinx extension of the orbits documentation (named in docs/conf.py).

* ``orbits-catalog-schema``: a directive that writes the catalog schema table
  from its one definition in the code, :data:`orbits.search.CATALOG_SCHEMA`
  (and the ``--verify`` column, :data:`orbits.catalog.VERIFIED_SCHEMA`), so
  the documented schema cannot drift from the files.
* The API reference check: every name of ``orbits.__all__`` must have a
  generated entry (a Python object ``orbits.NAME`` documented by autodoc,
  which gives the HTML anchor ``id="orbits.NAME"``).  A missing one is a
  warning, which ``sphinx -W`` turns into a failed build.  To document a new
  public name, add it to the autosummary list of its group in docs/api.md.
"""

import importlib

from docutils import nodes
from docutils.parsers.rst.states import RSTState
from docutils.statemachine import StringList
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

LOGGER = logging.getLogger(__name__)

# names of orbits.__all__ that get no entry of their own
UNDOCUMENTED = {"__version__"}


class CatalogSchema(SphinxDirective):
    """The table of catalog columns: name, unit, meaning."""

    has_content = False

    def run(self):
        from orbits.catalog import VERIFIED_COLUMN, VERIFIED_SCHEMA
        from orbits.search import CATALOG_SCHEMA

        for name in ("orbits.search", "orbits.catalog"):  # rebuild the page when they change
            self.env.note_dependency(importlib.import_module(name).__file__)
        rows = list(CATALOG_SCHEMA.items()) + [(VERIFIED_COLUMN, VERIFIED_SCHEMA)]
        lines = [
            ".. list-table::",
            "   :header-rows: 1",
            "   :widths: 14 8 78",
            "   :class: orbits-schema",
            "",
            "   * - column",
            "     - unit",
            "     - meaning",
        ]
        for name, (unit, meaning) in rows:
            # units are plain text (|I| would be a substitution in rST)
            shown = f"``{unit}``" if unit else "—"
            lines += [f"   * - ``{name}``", f"     - {shown}", f"     - {meaning}"]
        if not isinstance(self.state, RSTState):  # a MyST page: hand the table to rST
            lines = ["```{eval-rst}", *lines, "```"]
        node = nodes.container()
        self.state.nested_parse(StringList(lines, source="orbits.search.CATALOG_SCHEMA"), 0, node)
        return node.children


def missing_api_entries(env):
    """Names of ``orbits.__all__`` with no documented object ``orbits.NAME``."""
    import orbits

    documented = env.get_domain("py").objects
    return sorted(
        name
        for name in orbits.__all__
        if name not in UNDOCUMENTED and f"orbits.{name}" not in documented
    )


def check_api_reference(app, env):
    missing = missing_api_entries(env)
    if missing:
        LOGGER.warning(
            "the API reference has no entry for %d public name(s) of orbits.__all__: %s "
            "(add each to the autosummary list of its group in docs/api.md)",
            len(missing),
            ", ".join(missing),
            type="orbits",
            subtype="api",
        )


def setup(app):
    app.add_directive("orbits-catalog-schema", CatalogSchema)
    app.connect("env-check-consistency", check_api_reference)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
