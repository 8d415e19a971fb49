"""Units of angular velocity and time: the factors to SI (rad/s, s).

A light module at the bottom of the layers (no numba, NumPy or pandas), so
the command line can name the units without loading the kernels.
"""

import math

from .errors import InputError

# what --units says of the revolution units (the CLI's help)
REVOLUTIONS_NOTE = "rpm and Hz are revolutions per minute and per second: 1 Hz = 2 pi rad/s"

# angular-velocity units -> rad/s; rpm and Hz count revolutions (turns of
# 2 pi rad) per minute and per second, as a tachometer does: 1 Hz = 2 pi rad/s
OMEGA_UNITS = {
    "rad/s": 1.0,
    "deg/s": math.pi / 180.0,
    "rpm": 2.0 * math.pi / 60.0,
    "Hz": 2.0 * math.pi,
}

# time units -> s (a day of 86400 s, as Pravec et al. 2005 give periods in h and d)
TIME_UNITS = {
    "s": 1.0,
    "min": 60.0,
    "h": 3600.0,
    "d": 86400.0,
}


def omega_factor(units):
    """rad/s per ``units`` (one of :data:`OMEGA_UNITS`).

    Raises
    ------
    InputError
        An unknown unit (the message lists the known ones).
    """
    try:
        return OMEGA_UNITS[units]
    except (KeyError, TypeError):
        raise InputError(
            f"unknown angular-velocity unit {units!r}; use one of {', '.join(OMEGA_UNITS)}"
        ) from None


def time_factor(unit):
    """Seconds per ``unit`` (one of :data:`TIME_UNITS`).

    Raises
    ------
    InputError
        An unknown unit (the message lists the known ones).
    """
    try:
        return TIME_UNITS[unit]
    except (KeyError, TypeError):
        raise InputError(
            f"unknown time unit {unit!r}; use one of {', '.join(TIME_UNITS)}"
        ) from None


# ----------------------------------------------------------------- notebook display
def html_table(caption, rows):
    """A small HTML table for a notebook's ``_repr_html_``.

    Parameters
    ----------
    caption : str
        The heading (escaped).
    rows : iterable of (name, value, unit)
        ``value`` a float (shown to 10 significant digits), an int or text;
        ``unit`` text, empty where there is none.
    """
    from html import escape

    cells = []
    for name, value, unit in rows:
        if isinstance(value, float):
            shown = f"{value:.10g}"
        else:
            shown = str(value)
        cells.append(
            f"<tr><th style='text-align:left'>{escape(str(name))}</th>"
            f"<td style='text-align:right'>{escape(shown)}</td>"
            f"<td style='text-align:left'>{escape(str(unit))}</td></tr>"
        )
    return (
        f"<table><caption style='text-align:left'><b>{escape(caption)}</b></caption>"
        + "".join(cells)
        + "</table>"
    )
