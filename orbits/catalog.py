"""Catalogs of closed orbits: building them for many bodies, CSV in and out.

A catalog is a CSV file: a few ``#`` comment lines (package version, the
command that made it) and then one row per closed orbit with the columns
of :data:`orbits.search.CATALOG_COLUMNS` (plus ``closure_error`` when
verified).  Floats are written with 17 significant digits, so they read
back bit for bit::

    pandas.read_csv(path, comment="#")

:func:`read_catalog` does the same and checks the schema.
"""

import numpy as np
import pandas as pd

from ._version import __version__
from .atomic import write_csv_atomic
from .bodies import Body
from .errors import InputError, OrbitsError
from .search import CATALOG_COLUMNS, closed_orbits

VERIFIED_COLUMN = "closure_error"
CLOSURE_TOLERANCE = 1e-8
READ_HINT = 'read with pandas.read_csv(path, comment="#")'


def catalog(bodies, n_max=10, q_max=1, *, verify=False, progress=None):
    """Closed orbits of one or many bodies, as one DataFrame.

    Parameters
    ----------
    bodies : Body or iterable of Body
    n_max, q_max : int
        As :func:`orbits.closed_orbits`.
    verify : bool
        Add the ``closure_error`` column: the angle (radians) by which each
        orbit, integrated independently (:func:`orbits.checks.closure_errors`),
        fails to return to its starting orientation after q periods.
    progress : callable, optional
        Called with 1 after each body.

    Returns
    -------
    pandas.DataFrame
        The rows of every body in turn, each body's sorted by theta.
    """
    from .checks import closure_errors
    if isinstance(bodies, Body):
        bodies = [bodies]
    frames = []
    for body in bodies:
        frame = closed_orbits(body, n_max=n_max, q_max=q_max)
        if verify:
            frame[VERIFIED_COLUMN] = closure_errors(
                body.moments, frame["dtheta"].to_numpy(), frame["q"].to_numpy())
        frames.append(frame)
        if progress is not None:
            progress(1)
    if not frames:
        raise InputError("no bodies given")
    return pd.concat(frames, ignore_index=True)


def write_catalog(frame, path, command=None):
    """Write a catalog CSV atomically with its provenance header.

    ``command`` is recorded as given (the CLI passes its own command line).
    """
    header = [f"orbits {__version__} closed-orbit catalog",
              f"command: {command if command else '(Python API)'}",
              READ_HINT]
    write_csv_atomic(frame, path, header_lines=header)


def read_catalog(path):
    """Read a catalog CSV and check its schema.

    Returns
    -------
    pandas.DataFrame
        With ``attrs["header"]``, the comment lines of the file.

    Raises
    ------
    InputError
        Missing file, wrong or misordered columns, bad branch labels,
        non-integer ``n``/``q``, or non-finite numbers.
    """
    try:
        with open(path) as handle:
            header = []
            for line in handle:
                if not line.startswith("#"):
                    break
                header.append(line[1:].strip())
        frame = pd.read_csv(path, comment="#")
    except FileNotFoundError:
        raise InputError(f"no catalog at {path}") from None
    except (pd.errors.ParserError, UnicodeDecodeError, pd.errors.EmptyDataError) as error:
        raise InputError(f"{path} is not a catalog CSV: {error}") from None
    columns = list(frame.columns)
    expected = list(CATALOG_COLUMNS)
    if columns[:len(expected)] != expected:
        raise InputError(f"{path}: columns {columns} do not start with the catalog "
                         f"schema {expected}")
    extra = columns[len(expected):]
    if extra not in ([], [VERIFIED_COLUMN]):
        raise InputError(f"{path}: unexpected columns {extra}")
    if not frame["branch"].isin(["SAM", "LAM"]).all():
        raise InputError(f"{path}: branch must be SAM or LAM")
    for name in ("n", "q"):
        if not pd.api.types.is_integer_dtype(frame[name]) or (frame[name] < 1).any():
            raise InputError(f"{path}: column {name} must hold integers >= 1")
    # closes_after is a fraction such as "1/2"; an all-integer column reads as int
    frame["closes_after"] = frame["closes_after"].astype(str)
    if not frame["closes_after"].str.fullmatch(r"[1-9][0-9]*(/2)?").all():
        raise InputError(f"{path}: closes_after must be a whole or half number of periods")
    numeric = frame[expected[1:5] + expected[8:] + extra]
    if not np.all(np.isfinite(numeric.select_dtypes("number").to_numpy())):
        raise InputError(f"{path}: non-finite numbers")
    frame.attrs["header"] = header
    return frame


def bodies_from_csv(path):
    """Bodies listed in a CSV with columns ``I1, I2, I3`` (and optionally ``name``).

    Moments may be in any order and scale on each row.

    Raises
    ------
    InputError
        Missing file or columns; the row number of an invalid body.
    """
    try:
        table = pd.read_csv(path, comment="#")
    except FileNotFoundError:
        raise InputError(f"no bodies file at {path}") from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as error:
        raise InputError(f"{path} is not a CSV of bodies: {error}") from None
    missing = {"I1", "I2", "I3"} - set(table.columns)
    if missing:
        raise InputError(f"{path}: missing column(s) {', '.join(sorted(missing))} "
                         "(need I1, I2, I3 and optionally name)")
    if table.empty:
        raise InputError(f"{path}: no bodies")
    bodies = []
    for row_number, row in enumerate(table.itertuples(index=False), start=1):
        name = str(row.name) if "name" in table.columns else f"row {row_number}"
        try:
            moments = [float(row.I1), float(row.I2), float(row.I3)]
            bodies.append(Body(moments, name=name))
        except (OrbitsError, ValueError) as error:
            raise InputError(f"{path}, row {row_number} ({name}): {error}") from None
    return bodies
