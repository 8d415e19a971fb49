"""orbits.cells: text cells neutralised for spreadsheets, and back."""

import pytest


# M26: a cell starting with "-" is a formula start for spreadsheets (OWASP)
@pytest.mark.parametrize("text", ["-1+2", "=1+2", "+A1", "@SUM(A1)", "\tx", "\rx"])
def test_every_formula_start_is_neutralised(text):
    import pandas as pd

    from orbits.catalog import csv_text
    from orbits.cells import neutralize, unneutralize

    assert neutralize(text) == "'" + text
    assert unneutralize(neutralize(text)) == text
    line = csv_text(pd.DataFrame({"body": [text]})).splitlines()[1]
    assert line.startswith("\"'")


# M27: a name that already starts with the escape quote round-trips exactly
@pytest.mark.parametrize("text", ["'quoted", "''", "'=1+2"])
def test_a_leading_quote_is_escaped_so_reading_back_is_exact(text):
    from orbits.cells import neutralize, unneutralize

    assert neutralize(text) == "'" + text
    assert unneutralize(neutralize(text)) == text
