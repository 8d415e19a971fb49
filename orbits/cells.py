"""Text-cell safety: names written into CSV files, safe for spreadsheets.

A text cell whose first character a spreadsheet takes as the start of a
formula (``= + - @``, tab or carriage return; OWASP "CSV injection") is
written with a leading ``'`` by :func:`neutralize`; :func:`unneutralize`
removes it again on reading, so the round trip is exact (a cell that
already starts with ``'`` is escaped too).  Catalogs and survey tables both
use it; it imports nothing of the package.
"""

# first characters a spreadsheet takes as the start of a formula (OWASP CSV
# injection); the quote itself is escaped too so that reading back is exact
FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")
ESCAPE = "'"


def neutralize(text):
    """A text cell safe for spreadsheets (OWASP): formula starts get a ``'``."""
    if text[:1] in FORMULA_STARTS or text[:1] == ESCAPE:
        return ESCAPE + text
    return text


def unneutralize(text):
    """Inverse of :func:`neutralize`."""
    return text[1:] if text[:1] == ESCAPE else text
