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


# --------------------------------------------------------------- header lines
# characters that end a line for some reader (str.splitlines, pandas' C
# parser, a spreadsheet) or are invisible: C0 and C1 controls, DEL, the
# Unicode line and paragraph separators; and the backslash, which escapes
_SHORT_ESCAPES = {"\\": "\\\\", "\n": "\\n", "\r": "\\r", "\t": "\\t"}


def _needs_escape(character):
    code = ord(character)
    return code < 0x20 or 0x7F <= code <= 0x9F or code in (0x2028, 0x2029) or character == "\\"


def escape_header(text):
    """One header line that stays one line: controls written as escapes.

    A name with a newline (``--name $'a\\n=1+1'``) would otherwise start a
    line of its own in a ``#`` header: a data line for every CSV reader, a
    formula for a spreadsheet.  Backslash, newline, carriage return and tab
    become ``\\\\ \\n \\r \\t``, other control characters (C0, DEL, C1, U+2028,
    U+2029) ``\\xNN`` or ``\\uNNNN``; :func:`unescape_header` reverses it
    exactly.
    """
    if not any(_needs_escape(c) for c in text):
        return text
    parts = []
    for character in text:
        if not _needs_escape(character):
            parts.append(character)
        elif character in _SHORT_ESCAPES:
            parts.append(_SHORT_ESCAPES[character])
        elif ord(character) <= 0xFF:
            parts.append(f"\\x{ord(character):02x}")
        else:
            parts.append(f"\\u{ord(character):04x}")
    return "".join(parts)


def unescape_header(text):
    """Inverse of :func:`escape_header`."""
    if "\\" not in text:
        return text
    import re

    short = {value[1]: key for key, value in _SHORT_ESCAPES.items()}
    return re.sub(
        r"\\(?:([\\nrt])|x([0-9a-f]{2})|u([0-9a-f]{4}))",
        lambda m: short[m[1]] if m[1] else chr(int(m[2] or m[3], 16)),
        text,
    )


def literal_text(text):
    """A name drawn as typed in a figure: no mathtext, no control characters.

    Matplotlib parses text between ``$`` signs as mathtext (``$x^$`` is a
    parse error), and in a title holding mathtext of its own an escaped
    ``\\$`` is drawn with its backslash.  Each ``$`` and ``\\`` of the name
    is therefore written as the math symbol (``$\\$$``, ``$\\backslash$``),
    which draws the character itself in every title.  Control characters
    are drawn as their escapes (:func:`escape_header`), since a font has
    no glyph for them.
    """
    # controls as escapes; the name's own backslashes stay single
    text = "".join(c if c == "\\" else escape_header(c) for c in str(text))
    return "".join(_LITERAL.get(character, character) for character in text)


_LITERAL = {"$": r"$\$$", "\\": r"$\backslash$"}


def exact_number(value):
    """A float as text that reads back to the same double: short (``%g``)
    where that is exact, else the shortest round trip (``repr``).

    >>> exact_number(0.1), exact_number(1.0000000099999999), exact_number(2.0)
    ('0.1', '1.00000001', '2')
    """
    value = float(value)
    short = f"{value:g}"
    return short if float(short) == value else repr(value)


def numbers_label(kind, values):
    """``kind(v1, v2, ...)`` for a body's label: each number as
    :func:`exact_number`, so that nearly equal moments never read as equal
    ones.

    >>> numbers_label("moments", [1.0, 1.00000001, 2.5])
    'moments(1, 1.00000001, 2.5)'
    """
    shown = [exact_number(value) for value in values]
    return f"{kind}({', '.join(shown)})"
