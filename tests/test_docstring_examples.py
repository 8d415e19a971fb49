"""The Examples sections of the public docstrings run as written (doctest).

The API reference shows them; this keeps them true.  A module listed here
must hold at least one example, so a deleted Examples section fails too.
"""

import doctest
import importlib

import pytest

MODULES = ["orbits.checks", "orbits.tumbling", "orbits.threads"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_run(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE, verbose=False)
    assert result.attempted > 0, f"{name} has no examples"
    assert result.failed == 0
