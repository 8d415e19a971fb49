"""Catalogs of closed orbits: building them for many bodies, CSV in and out.

A catalog is a CSV file: a few ``#`` comment lines (package version, the
command that made it, the row count and the SHA-256 of the data section)
and then one row per closed orbit with the columns of
:data:`orbits.search.CATALOG_COLUMNS` (plus ``closure_error`` when
verified).  Floats are written as the shortest decimal that reads back to
the same double, so they read back bit for bit::

    orbits.read_catalog(path)            # also checks schema and checksum
    pandas.read_csv(path, comment="#")   # pandas >= 3; pandas 2.x: add
                                         # float_precision="round_trip"

Text cells are always quoted (so a ``#`` inside a name is not a comment),
and a name that a spreadsheet would run as a formula (first character
``= + - @``, tab or carriage return) is written with a leading ``'`` as
OWASP recommends; :func:`read_catalog` removes it again.

Bodies files (``--bodies``) are read strictly by :func:`read_bodies_csv`.
"""

import csv
import hashlib
import io
import math
import os
import re
import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ._args import (
    below_normal,
    below_normal_message,
    callback,
    caller_stacklevel,
    flag,
    held_warnings,
    integer,
    listlike,
    path_argument,
    read_as_zero,
    real_array,
    utf8_text,
    warn,
)
from ._version import __version__
from .atomic import atomic_path, csv_float_options, write_stdout
from .bodies import FLAT_SLACK, Body, flat_excess, validate_moments
from .cells import escape_header, neutralize, unescape_header, unneutralize
from .errors import ArgumentTypeError, InputError, OrbitsError
from .limits import (
    MAX_SECONDS,
    about_bytes,
    about_duration,
    check_search_bounds,
    memory_budget,
    plural,
    read_input_bytes,
    read_input_text,
    search_estimate,
)
from .search import CATALOG_COLUMNS, UnresolvedOrbitsWarning, closed_orbits, phase_levels
from .tumbling import SPIN_VECTOR_RTOL

VERIFIED_COLUMN = "closure_error"
#: unit and meaning of the ``--verify`` column, as in :data:`orbits.search.CATALOG_SCHEMA`
VERIFIED_SCHEMA = (
    "rad",
    "(``--verify`` only) the angle by which the orientation after q periods differs "
    "from the start, by an independent integration of Euler's equations",
)
CLOSURE_TOLERANCE = 1e-8
READ_HINT = (
    'read with orbits.read_catalog(path), or pandas.read_csv(path, comment="#") '
    '(pandas 2.x: add float_precision="round_trip")'
)
ROWS_KEY = "rows: "
CHECKSUM_KEY = "sha256 of the data section: "


# --------------------------------------------------------------- building
def catalog(bodies, n_max=10, q_max=1, *, verify=False, progress=None):
    """Closed orbits of one or many bodies, as one DataFrame.

    Parameters
    ----------
    bodies : Body or iterable of Body (or of moments, shape (3,))
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

    Raises
    ------
    InputError
        No bodies, ``n_max``/``q_max`` not integers >= 1, or a search whose
        memory or time would exceed the machine (see
        :func:`check_search_bounds`; refused before any work).

    Warns
    -----
    UnresolvedOrbitsWarning
        Per body whose orbits up to ``n_max`` include some closer than
        ``|dtheta| = 2.2e-308`` to the separatrix (left out), at the
        caller's line, naming the body (``body k of N``, and its name).
    """
    from .checks import closure_errors

    if isinstance(bodies, Body):
        bodies = [bodies]
    if not listlike(bodies):
        raise ArgumentTypeError(
            f"bodies must be a Body or an iterable of Body objects "
            f"(or moments), got {type(bodies).__name__}"
        )
    bodies = [b if isinstance(b, Body) else Body(b) for b in bodies]
    if not bodies:
        raise InputError("no bodies given")
    n_max, q_max = integer("n_max", n_max, minimum=1), integer("q_max", q_max, minimum=1)
    verify, progress = flag("verify", verify), callback("progress", progress)
    check_search_bounds(n_max, q_max, len(bodies), "the catalog")
    frames = []
    for index, body in enumerate(bodies):
        # which body of the list (two unnamed bodies gave two identical lines)
        where = f"body {index + 1} of {len(bodies)}: " if len(bodies) > 1 else ""
        frame = _labelled_search(body, n_max, q_max, where)
        if verify:
            frame[VERIFIED_COLUMN] = closure_errors(
                body.moments, frame["dtheta"].to_numpy(), frame["q"].to_numpy()
            )
        frames.append(frame)
        if progress is not None:
            progress(1)
    return pd.concat(frames, ignore_index=True)


# --------------------------------------------------------------- nearest orbits
# extra columns of nearest_orbits: the starting spin in the body's own axes
# (in the caller's unit) and the period in seconds
NEAREST_COLUMNS = ("omega_x", "omega_y", "omega_z", "period_s")


def nearest_orbits(body, omega, k=3, q_max=1, *, units="rad/s"):
    """The ``k`` closed orbits nearest a real spin, started at its ``|L|``.

    A throw sets the angular momentum; the closed orbits of the body
    (``Delta alpha = 2 pi n/q``, :func:`orbits.closed_orbits`) are ranked by
    how far their total phase (eqn:GeometricPhase) is from the spin's, on
    the spin's branch first:

    1. orbits on the spin's branch (SAM or LAM) before the other branch;
    2. then ``|Delta alpha_orbit - Delta alpha_spin|`` (radians): the change
       of the precession gained per period that closes the orbit;
    3. ties by ``|D_orbit - D_spin|`` (``D = M^2/(2E)`` over ``|I|``, the
       polhode's level).

    The total phase depends on the orbit only (not on where on the polhode
    the spin starts), so the ranking holds for any spin.  On the spin's
    branch every level ``2 pi m`` above ``Delta alpha_spin`` has an orbit
    (the phase grows without bound towards the separatrix), so a search up
    to ``n_max = ceil(Delta alpha_spin / 2 pi) + k`` holds the ``k``
    nearest.  Each orbit's ``omega_*`` start where its polhode meets the
    given spin's azimuth about I3 (a LAM polhode that does not reach it:
    its crossing of ``omega3 = 0`` nearest it), with the spin's signs, so
    that it starts close to the throw; it is scaled so that its
    ``|L| = |I omega0|`` is the given spin's.  (The catalog columns, as in
    every catalog, are those of the orbit's ``phi = 0`` spin.)

    Parameters
    ----------
    body : Body or array_like, shape (3,)
    omega : array_like, shape (3,)
        The spin in the body's own axes (:attr:`Body.frame` turns them to
        the principal axes: x y z of :meth:`Body.box`, the order of the
        moments of ``Body(moments)``), in ``units``.
    k : int
        Number of orbits (>= 1).
    q_max : int
        Also the orbits closing after up to ``q_max`` periods (``2 pi p/q``).
    units : {"rad/s", "deg/s", "rpm", "Hz"}
        Unit of ``omega`` and of the ``omega_*`` columns; ``rpm`` and
        ``Hz`` are revolutions per minute and per second (1 Hz = 2 pi rad/s).

    Returns
    -------
    pandas.DataFrame
        ``k`` rows, nearest first, with the catalog columns
        (:data:`orbits.CATALOG_COLUMNS`, for ``|I| = 1`` and
        ``|omega0| = 1`` as in every catalog) and :data:`NEAREST_COLUMNS`:
        ``omega_x, omega_y, omega_z``, the orbit's starting spin in the
        body's own axes in ``units`` (``Motion(body, body.frame @ omega)``,
        omega in rad/s, is the orbit, with the throw's ``|L|``), and ``period_s``,
        its period T (eqn:TK) in seconds for moments in any unit (the
        period does not depend on their scale).  ``attrs`` holds the spin's
        ``total_phase``, ``branch``, ``momentum`` (in the moments' unit
        times rad/s: kg m^2 gives J s) and ``D``.

    Raises
    ------
    AngleError
        ``omega`` not a finite nonzero 3-vector.
    SeparatrixError
        ``omega`` on the separatrix (no closed orbits accumulate at a finite
        phase there: its phase is infinite).
    InputError
        ``k`` or ``q_max`` not integers >= 1, an unknown unit, a search
        beyond the machine (a spin very close to the separatrix), or orbits
        among the ``k`` nearest that lie closer than ``|dtheta| = 2.2e-308``
        to the separatrix (levels above ``attrs["reach"]`` of
        :func:`orbits.closed_orbits`: no double holds them, and ranking the
        others would skip them).
    """
    from .errors import AngleError
    from .motion import Motion
    from .units import omega_factor

    if not isinstance(body, Body):
        body = Body(body)
    k = integer("k", k, minimum=1)
    q_max = integer("q_max", q_max, minimum=1)
    factor = omega_factor(units)
    given = real_array("omega", omega, AngleError)
    if given.shape != (3,) or not np.all(np.isfinite(given)):
        raise AngleError(f"omega must be a finite 3-vector, got {omega!r}")
    own = given * factor
    # the constructor takes omega along the principal axes (as from_omega)
    spin = Motion(body, body.frame @ own)
    alpha = spin.total_phase()
    # D / |I| on the unit moments (exact power-of-two scaling: |I| of moments
    # beyond 1e+-154 squared to inf or 0 in numpy's norm)
    d_spin = math.ldexp(spin.D, -body.exponent) / float(np.linalg.norm(body.unit_moments))
    n_max = int(math.ceil(alpha / (2.0 * math.pi))) + k
    # the search's own refusal would name --n-max, which is no option here
    memory, seconds = search_estimate(n_max, q_max, 1)
    if not (memory <= memory_budget() and seconds <= MAX_SECONDS):
        raise InputError(
            f"the {k} closed orbits nearest this spin need a search up to n = {n_max} "
            f"({about_bytes(memory)} of memory, {about_duration(seconds)}), beyond this "
            "machine; lower k (--nearest) or --q-max, or take a spin farther from the "
            "separatrix"
        )
    # the search's n_max is ours, not the caller's: say what it was for.  The
    # orbits it leaves out next to the separatrix are not a warning about
    # this result: they are farther than the k chosen, or the call is refused
    # (_refuse_unheld_nearest)
    frame = _labelled_search(
        body,
        n_max,
        q_max,
        f"the {k} closed orbits nearest this spin (total phase {alpha:.6g} rad, a "
        f"search up to n = {n_max}): ",
        drop=UnresolvedOrbitsWarning,
    )
    distance = np.abs(frame["total_phase"].to_numpy() - alpha)
    other = (frame["branch"].astype(str) != spin.branch).to_numpy()
    level = np.abs(frame["D"].to_numpy() - d_spin)
    order = np.lexsort((level, distance, other))[:k]
    _refuse_unheld_nearest(frame, order, distance, other, spin, alpha, k, n_max, q_max)
    frame = frame.iloc[order].reset_index(drop=True)
    columns = {name: [] for name in NEAREST_COLUMNS}
    unheld = []  # (row, relative period error) of starting spins that miss their orbit
    for theta, dtheta in frame[["theta", "dtheta"]].to_numpy():
        unit = Motion.from_spin(body, dtheta=float(dtheta))  # |omega0| = 1
        speed = spin.momentum / unit.momentum  # the throw's |L|
        orbit = Motion.from_spin(body, dtheta=float(dtheta), speed=speed)
        # the unit-speed polhode on the unit moments (the angles do not depend
        # on their scale), then scaled to the throw: no square of the moments
        # or of |L| at the caller's scale (they overflowed or went subnormal
        # beyond 1e+-154)
        start = _start_near(body.unit_moments, theta, dtheta, spin.omega0)
        start = body.frame.T @ (start * speed) / factor
        off = _start_off(body, body.frame @ (start * factor), orbit)
        if not off <= SPIN_VECTOR_RTOL:
            unheld.append((len(columns["period_s"]), off))
        for name, value in zip(NEAREST_COLUMNS, [*start, orbit.period]):
            columns[name].append(float(value))
    for name in NEAREST_COLUMNS:
        frame[name] = np.array(columns[name])
    if unheld:
        rows = ", ".join(str(row) for row, _ in unheld[:5]) + (" ..." if len(unheld) > 5 else "")
        worst = max(off for _, off in unheld)
        warnings.warn(
            f"the omega_x, omega_y, omega_z of rows {rows} do not hold their orbits: "
            f"started from them as doubles, the period or phase is up to "
            f"{'beyond the separatrix' if math.isinf(worst) else f'{worst:.2g}'} off "
            "(the orbits lie within a double's rounding of the separatrix); every other "
            "column is of the orbit of dtheta: start from Motion.from_spin(body, dtheta=...)",
            UnresolvedOrbitsWarning,
            stacklevel=caller_stacklevel(),
        )
    frame.attrs = {
        "total_phase": alpha,
        "branch": spin.branch,
        "momentum": spin.momentum,
        "D": d_spin,
    }
    return frame


def _refuse_unheld_nearest(frame, order, distance, other, spin, alpha, k, n_max, q_max):
    """Refuse a ranking that orbits left out next to the separatrix could change.

    The search leaves out the levels above a branch's phase at
    ``|dtheta| = 2.2e-308`` (``attrs["reach"]``): they exist, but no double
    holds their orbit.  On the spin's branch they rank before every orbit
    of the other branch, and the nearest of them to the spin is the first
    level above the reach; the ``k`` chosen rows are the nearest only if all
    lie on the spin's branch and nearer than that level (strictly: on a tie
    the left-out orbit's ``D``, the tie-break, is unknown).
    """
    if not frame.attrs["unresolved_by_branch"][spin.branch]:
        return
    reach = frame.attrs["reach"][spin.branch]
    p, q, values = phase_levels(n_max, q_max)
    left = np.flatnonzero(values > reach)  # not empty: a level was left out
    bound = values[left[0]] - alpha
    chosen = distance[order]
    if len(order) == k and not other[order].any() and chosen.max() < bound:
        return
    # the left-out level nearest the spin: among the k nearest (it is nearer
    # than the k-th stored row, or the spin's branch has fewer than k rows)
    j = left[np.argmin(np.abs(values[left] - alpha))]
    level = f"2 pi {p[j]}" + (f"/{q[j]}" if q[j] != 1 else "")
    # lowering k helps only where the nearest stored orbit is nearer than it
    fewer = k > 1 and len(order) and not other[order[0]] and chosen[0] < bound
    nearest = (
        "the closed orbit nearest it is" if k == 1 else f"the {k} closed orbits nearest it include"
    )
    raise InputError(
        f"this spin (total phase {alpha:.6g} rad, {spin.branch}) lies so near the "
        f"separatrix that {nearest} Delta alpha = {level} = {values[j]:.6g} rad, "
        f"which lies closer than |dtheta| = 2.2e-308 to it (as every level above "
        f"{reach:.6g} rad on {spin.branch}) and cannot be stored in double precision; "
        + ("lower k (--nearest) or " if fewer else "")
        + "take a spin farther from the separatrix"
    )


def _labelled_search(body, n_max, q_max, label, drop=()):
    """:func:`~orbits.search.closed_orbits` with its warnings told at the
    caller's line, each message after ``label``; those of the classes in
    ``drop`` are not told."""
    with held_warnings() as caught:  # not catch_warnings: not thread-safe
        frame = closed_orbits(body, n_max=n_max, q_max=q_max)
    for message, category in caught:
        if not issubclass(category, drop):
            warn(f"{label}{message}", category)
    return frame


def _start_off(body, omega, orbit):
    """Relative error of the period and total phase of the orbit through
    ``omega`` (principal axes, rad/s) against ``orbit``'s (a Motion), the
    larger; inf where it lies on the separatrix."""
    from .motion import Motion

    try:
        start = Motion(body, omega)
        return max(
            abs(start.period / orbit.period - 1.0),
            abs(start.total_phase() / orbit.total_phase() - 1.0),
        )
    except OrbitsError:
        return math.inf


def _start_near(moments, theta, dtheta, spin):
    """The point of the polhode of the ``phi = 0`` spin at ``theta = theta_crit +
    dtheta`` (``|omega0| = 1``; both angles given) at the azimuth of ``spin`` about I3.

    On the orbit, ``omega = (r c, r s, z)`` (principal axes, ``c, s`` the
    cosine and sine of the spin's azimuth) keeps ``2E`` and ``M^2``
    (eqn:E, eqn:J), so ``I1 (I3-I1) x^2 + I2 (I3-I2) y^2 = 2EI3 - M^2``,
    ``I2 (I2-I1) y^2 + I3 (I3-I1) z^2 = M^2 - 2EI1`` and ``I1 (I2-I1) x^2
    - I3 (I3-I2) z^2 = 2EI2 - M^2``.  The three invariants are taken from
    the spin (``2EI2 - M^2 = sin(dtheta) (2 cos(dtheta) sqrt(I1 (I2-I1)
    I3 (I3-I2)) + sin(dtheta) (I1 (I2-I1) - I3 (I3-I2)))``, no cancellation
    next to the separatrix; from 2E and M^2 it kept only ~1e-16 / |dtheta|
    of its digits), and ``z^2`` from the third on SAM (a sum of
    non-negative terms), on LAM from the second or the third, whichever
    rounds less (the third divides a difference by ``I3 - I2``).  A LAM polhode
    that does not reach that azimuth is started where it crosses
    ``omega3 = 0`` nearest it.  Components keep the signs of the
    spin's, so the orbit starts close to the throw.
    """
    i1, i2, i3 = (float(v) for v in moments)
    largest = max(abs(float(v)) for v in spin)  # only its direction counts
    w1, w2, w3 = (math.ldexp(float(v), -math.frexp(largest)[1]) for v in spin)
    norm = math.hypot(w1, w2)
    c, s = (abs(w1) / norm, abs(w2) / norm) if norm > 0.0 else (1.0, 0.0)
    sin_t, cos_t = math.sin(theta), math.cos(theta)
    sin_d, cos_d = math.sin(dtheta), math.cos(dtheta)
    low, high = i1 * (i2 - i1), i3 * (i3 - i2)  # tan(theta_crit)^2 = high / low
    gap_3 = i1 * (i3 - i1) * sin_t * sin_t  # 2EI3 - M^2
    gap_1 = i3 * (i3 - i1) * cos_t * cos_t  # M^2 - 2EI1
    # 2EI2 - M^2 = low sin^2(theta) - high cos^2(theta), < 0 on SAM and > 0 on
    # LAM, from dtheta and the moments alone (theta_crit rounded to a double
    # cost ~eps / cos(theta_crit) of it on a body with I1 ~ I2)
    gap_2 = sin_d * (2.0 * cos_d * math.sqrt(low * high) + sin_d * (low - high))
    r_sq = gap_3 / (i1 * (i3 - i1) * c * c + i2 * (i3 - i2) * s * s)
    x_part, y_part = low * r_sq * c * c, i2 * (i2 - i1) * r_sq * s * s
    z_sq = (x_part - gap_2) / high  # SAM: a sum of non-negative terms
    # LAM: a difference either way; from M^2 - 2EI1 where its rounding is the
    # smaller (I2 ~ I3: the one above divides by I3 - I2; next to the
    # separatrix near I2: this one cancels)
    if gap_2 > 0.0 and (gap_1 + y_part) / (i3 * (i3 - i1)) < (x_part + gap_2) / high:
        z_sq = (gap_1 - y_part) / (i3 * (i3 - i1))
    if z_sq < 0.0:  # LAM, azimuth beyond the polhode's reach: its crossing of omega3 = 0
        x_sq = gap_2 / (i1 * (i2 - i1))
        y_sq = gap_1 / (i2 * (i2 - i1))
        x, y, z = math.sqrt(x_sq), math.sqrt(y_sq), 0.0
    else:
        r = math.sqrt(r_sq)
        x, y, z = r * c, r * s, math.sqrt(z_sq)
    return np.array(
        [math.copysign(x, w1), math.copysign(y, w2), math.copysign(z, w3) if z else 0.0]
    )


# --------------------------------------------------------------- CSV text
def csv_text(frame):
    """The CSV text of a DataFrame: floats exact, text quoted and neutralised.

    Floats are written by ``repr`` (the shortest decimal that reads back to
    the same double), integers as integers, every text cell quoted (a ``#``
    or ``,`` inside a name stays data) and passed through :func:`neutralize`.
    """
    buffer = io.StringIO()
    buffer.write(",".join(frame.columns) + "\n")
    writer = csv.writer(buffer, quoting=csv.QUOTE_NONNUMERIC, lineterminator="\n")
    columns = []
    for name in frame.columns:
        values = frame[name]
        if values.dtype.kind in "fiu":
            columns.append(values.tolist())
        elif values.dtype.kind == "b":
            columns.append([str(v) for v in values.tolist()])
        else:
            columns.append([neutralize(str(v)) for v in values.tolist()])
    writer.writerows(zip(*columns))
    return buffer.getvalue()


# --------------------------------------------------------------- write / read
def write_catalog(frame, path, command=None, notes=()):
    """Write a catalog CSV atomically with its provenance header.

    ``command`` is recorded as given (the CLI passes its own command line);
    ``notes`` are extra header lines (e.g. the rows ``--skip-invalid``
    skipped).  The header ends with the row count and the SHA-256 of the
    data section (every byte after the header), which :func:`read_catalog`
    checks.  Control characters in a header line (a newline in a body's
    name or the command) are escaped (:func:`orbits.cells.escape_header`),
    so each stays one ``#`` line; :func:`read_catalog` unescapes them.
    ``path`` ``"-"`` writes to standard output.

    Parameters
    ----------
    frame : pandas.DataFrame
        Catalog rows (:data:`orbits.CATALOG_COLUMNS`, optionally
        ``closure_error`` and the nearest-orbit columns).
    path : str or Path
        The file, replaced atomically, or ``"-"``.
    command : str, optional
        The command that made it, for the header (None or ``""``: "(Python
        API)").
    notes : str or iterable of str
        Extra header lines.

    Raises
    ------
    ArgumentTypeError
        ``frame`` is not a pandas DataFrame, ``path`` is not a path (str or
        os.PathLike), ``command`` not a str or None, ``notes`` not text.
    InputError
        ``path`` ``"-"`` while standard output is closed; an unwritable
        path; a frame :func:`read_catalog` would refuse (columns not the
        schema, non-finite numbers, a row that is no closed orbit), checked
        before anything is written.
    """
    path = path_argument("path", path)
    if not isinstance(frame, pd.DataFrame):
        raise ArgumentTypeError(
            f"write_catalog needs a pandas DataFrame (e.g. from orbits.catalog), "
            f"got {type(frame).__name__}"
        )
    if frame.columns.duplicated().any():
        twice = sorted({str(name) for name in frame.columns[frame.columns.duplicated()]})
        raise InputError(f"write_catalog: the frame has columns given twice: {twice}")
    for name in frame.columns:
        if frame[name].dtype.kind == "f" and not np.all(np.isfinite(frame[name].to_numpy())):
            raise InputError(f"write_catalog: the frame's column {name} has non-finite numbers")
    data = csv_text(frame)
    # what read_catalog would refuse is not written (columns not the schema,
    # NaN, an edited row): checked on the very text, before the file exists
    _catalog_frame("write_catalog: the frame", data.encode())
    command, notes = _header_text(command, notes)
    header = [
        f"orbits {__version__} closed-orbit catalog",
        f"command: {command if command else '(Python API)'}",
        READ_HINT,
    ]
    header += [" ".join(str(note).split()) for note in notes]
    header += [
        f"{ROWS_KEY}{len(frame)}",
        f"{CHECKSUM_KEY}{hashlib.sha256(data.encode()).hexdigest()}",
    ]
    # one line each, whatever the command or a name holds (read_catalog unescapes)
    text = "".join(f"# {escape_header(line)}\n" for line in header) + data
    if os.fspath(path) == "-":
        write_stdout(text, "the catalog")
        return
    with atomic_path(path) as temporary:
        with open(temporary, "w", newline="", encoding="utf-8") as handle:
            handle.write(text)


def _header_text(command, notes):
    """``(command, notes)`` of :func:`write_catalog`, checked: text UTF-8 can hold.

    ``command`` None or a str; ``notes`` one str or an iterable of str (a
    bytes note wrote a line per byte value, ``command=0`` read as none).
    """
    if command is not None and not isinstance(command, str):
        raise ArgumentTypeError(f"command must be a str or None, got {type(command).__name__}")
    if command is not None:
        command = utf8_text("command", command)
    if isinstance(notes, str):  # one note (iterating it wrote a line per letter)
        notes = [notes]
    if isinstance(notes, (bytes, bytearray)) or not hasattr(notes, "__iter__"):
        raise ArgumentTypeError(
            f"notes must be a str or an iterable of str, got {type(notes).__name__}"
        )
    notes = list(notes)
    for note in notes:
        if not isinstance(note, str):
            raise ArgumentTypeError(f"each note must be a str, got {type(note).__name__}")
        utf8_text("a note", note)
    return command, notes


def _split_header(raw):
    """Header lines (without ``# ``) and the data bytes of a catalog file."""
    header, position = [], 0
    while raw.startswith(b"#", position):
        end = raw.find(b"\n", position)
        end = len(raw) if end < 0 else end + 1
        header.append(unescape_header(raw[position + 1 : end].decode("utf-8").strip()))
        position = end
    return header, raw[position:]


def read_catalog(path, *, check=True):
    """Read a catalog CSV and check its checksum, row count and schema.

    Parameters
    ----------
    path : str or Path
    check : bool
        Require and check the row count and SHA-256 lines of the header
        (default).  ``False`` reads a catalog without them (e.g. written by
        hand) but still checks the schema and types.

    Returns
    -------
    pandas.DataFrame
        With ``attrs["header"]``, the comment lines of the file.  Floats
        are bit for bit those written; names come back unneutralised.

    Raises
    ------
    InputError
        Missing file; no or wrong checksum (a changed, added or removed
        byte, e.g. a truncated file); row count not as recorded; wrong or
        misordered columns; a cell of the wrong type (``abc`` in a numeric
        column); bad branch labels; ``n``/``q`` not integers >= 1;
        non-finite numbers; a row that is no closed orbit as the search
        writes it (``n/q`` not above 1 or not in lowest terms, ``dtheta``
        on the wrong side for its branch, ``total_phase`` or ``residual``
        beyond ``1e-10 * 2 pi n/q``, ``theta`` not ``theta_crit + dtheta``,
        columns that break the identities between them, ``m`` not ``k^2``
        of the row's moments and ``D`` or not in ``(0, 1]``), with or
        without ``check``.
    """
    path = path_argument("path", path)
    check = flag("check", check)
    raw = read_input_bytes(path, "catalog")  # no limit: the file orbits wrote
    try:
        header, data = _split_header(raw)
    except UnicodeDecodeError:
        raise InputError(f"{path} is not a catalog CSV (not UTF-8 text)") from None
    recorded = {
        key: line[len(key) :]
        for line in header
        for key in (ROWS_KEY, CHECKSUM_KEY)
        if line.startswith(key)
    }
    if check:
        if len(recorded) != 2:
            raise InputError(
                f"{path}: no row count and checksum in the header (not an "
                "orbits catalog, or written before checksums; "
                "read_catalog(path, check=False) skips the check)"
            )
        if hashlib.sha256(data).hexdigest() != recorded[CHECKSUM_KEY]:
            raise InputError(
                f"{path} is damaged: the data section does not match its "
                "SHA-256 (changed, truncated or extended)"
            )
    frame = _catalog_frame(path, data, recorded[ROWS_KEY] if check else None)
    frame.attrs["header"] = header
    return frame


def _catalog_frame(path, data, rows=None):
    """The catalog frame of a data section (bytes), every check of :func:`read_catalog`.

    ``rows``: the row count the header records, checked when given.  Also
    what :func:`write_catalog` checks before it writes (named ``path``).
    """
    dtypes = {name: float for name in CATALOG_COLUMNS + (VERIFIED_COLUMN,) + NEAREST_COLUMNS}
    dtypes.update(body=str, branch=str, n="int64", q="int64", closes_after=str)
    try:
        frame = pd.read_csv(
            io.BytesIO(data), dtype=dtypes, keep_default_na=False, **csv_float_options()
        )
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as error:
        raise InputError(f"{path} is not a catalog CSV: {_one_line(error)}") from None
    except (ValueError, TypeError) as error:
        raise InputError(
            f"{path}: a cell has the wrong type for its column ({_one_line(error)})"
        ) from None
    if rows is not None and str(len(frame)) != rows.strip():
        raise InputError(
            f"{path} is damaged: {len(frame)} rows, the header records {rows.strip()}"
        )
    columns = list(frame.columns)
    expected = list(CATALOG_COLUMNS)
    if columns[: len(expected)] != expected:
        raise InputError(
            f"{path}: columns {columns} do not start with the catalog schema {expected}"
        )
    extra = columns[len(expected) :]
    if extra not in ([], [VERIFIED_COLUMN], list(NEAREST_COLUMNS)) and extra != [
        VERIFIED_COLUMN,
        *NEAREST_COLUMNS,
    ]:
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
    textual = {"body", "branch", "n", "q", "closes_after"}
    numeric = frame[[name for name in expected + extra if name not in textual]]
    for name in numeric.columns:
        if numeric[name].dtype.kind != "f":
            raise InputError(f"{path}: column {name} must hold numbers")
    if not np.all(np.isfinite(numeric.to_numpy(dtype=float))):
        raise InputError(f"{path}: non-finite numbers")
    _check_orbit_rows(path, frame)
    frame["body"] = frame["body"].map(unneutralize).astype(frame["body"].dtype)
    return frame


def _check_orbit_rows(path, frame):
    """Refuse rows that no search writes: each must be a closed orbit of its level.

    The checksum finds damage, not a hand edit whose checksum was rewritten
    with it; these cheap checks find the edits that would change what a
    row means: a level ``n/q`` not above 1 or not in lowest terms, a
    ``dtheta`` on the wrong side of the separatrix for its branch (SAM
    below it, LAM above), a total phase (or residual) more than
    :data:`orbits.search.RESIDUAL_TOLERANCE` of its level away from
    ``2 pi n/q``, a ``theta`` that is not ``theta_crit + dtheta`` (to an
    ulp: so an edited ``dtheta``, ``theta`` or ``theta_crit`` shows; the
    phases are not evaluated again, since the moments columns are
    ``I/|I|`` rounded and a nearly symmetric body's phase depends on that
    rounding beyond the tolerance).  (A row given twice is not refused: a bodies file may
    list one body twice under one name, and its catalog repeats its rows.)
    """
    import math

    from .search import RESIDUAL_TOLERANCE

    if frame.empty:
        return
    n, q = frame["n"].to_numpy(), frame["q"].to_numpy()
    dtheta = frame["dtheta"].to_numpy(dtype=float)
    theta = frame["theta"].to_numpy(dtype=float)
    sam = frame["branch"].to_numpy() == "SAM"
    target = 2.0 * math.pi * n / q
    # a little over the search's own bound: 2 pi n/q rounds differently here
    allowed = RESIDUAL_TOLERANCE * target * (1.0 + 1e-6) + 4.0 * np.spacing(target)
    reasons = [
        (n <= q, "its level n/q is not above 1 (2 pi n/q <= 2 pi has no closed orbit)"),
        (np.gcd(n, q) != 1, "n/q is not in lowest terms"),
        (sam & ~(dtheta < 0.0), "a SAM orbit must have dtheta < 0 (theta below theta_crit)"),
        (~sam & ~(dtheta > 0.0), "a LAM orbit must have dtheta > 0 (theta above theta_crit)"),
        (
            ~(np.abs(frame["total_phase"].to_numpy(dtype=float) - target) <= allowed),
            "its total_phase is not 2 pi n/q",
        ),
        (
            ~(np.abs(frame["residual"].to_numpy(dtype=float)) <= allowed),
            "its residual is too large",
        ),
        (
            # theta is theta_crit + dtheta, rounded once (eqn:thetacrit's offset)
            ~(
                np.abs(theta - (frame["theta_crit"].to_numpy(dtype=float) + dtheta))
                <= np.spacing(np.abs(theta))
            ),
            "its theta is not theta_crit + dtheta",
        ),
    ]
    reasons += _identity_problems(frame)
    for bad, why in reasons:
        if bad.any():
            rows = np.flatnonzero(bad)
            more = f" (and {rows.size - 1} more)" if rows.size > 1 else ""
            edited = (
                "" if "regenerate" in why else "; not a catalog orbits wrote (edited by hand?)"
            )
            raise InputError(f"{path}, data row {rows[0] + 1}{more}: {why}{edited}")


# the identities between a row's columns hold to a few ulps (measured on
# 7,105 rows of the committed catalogs and of near-symmetric, near-flat and
# thin bodies: |I| 0.5 ulp, dynamic - geometric 6, 2ET/M 3, M^2/(2E) 4)
IDENTITY_ULPS = 32


def _identity_problems(frame):
    """``(bad, why)`` for the identities every row holds, whatever its moments' rounding.

    ``I1^2 + I2^2 + I3^2 = 1`` (the unit-norm moments), ``total_phase =
    dynamic_phase - geometric_phase``, ``dynamic_phase = 2 E T / M``
    (Montgomery's 2ET/M), ``D = M^2 / (2E)`` and ``closes_after`` of
    ``n/q`` (:func:`orbits.search.closes_after`): an edited moment, period,
    energy, |L|, D, m or phase shows, though the phases are not evaluated again;
    and ``m`` is ``k^2`` of eqn:TK from the row's moments and ``D``
    (:func:`_is_k_squared`), in ``(0, 1]``.
    """
    from .search import closes_after

    def close(got, want):
        scale = np.maximum(np.abs(got), np.abs(want))
        return np.abs(got - want) <= IDENTITY_ULPS * np.spacing(scale)

    column = {
        name: frame[name].to_numpy(dtype=float)
        for name in CATALOG_COLUMNS
        if name not in ("body", "branch", "n", "q", "closes_after")
    }
    norm = np.sqrt(column["I1"] ** 2 + column["I2"] ** 2 + column["I3"] ** 2)
    energy, momentum = column["energy"], column["momentum"]
    m = column["m"]
    k_squared = _is_k_squared(column, frame["branch"].to_numpy() == "SAM")
    return [
        (~close(norm, np.ones_like(norm)), "its moments I1, I2, I3 are not of unit norm"),
        (
            ~((column["I1"] < column["I2"]) & (column["I2"] < column["I3"])),
            "its moments are not I1 < I2 < I3",
        ),
        (
            ~close(column["dynamic_phase"] - column["geometric_phase"], column["total_phase"]),
            "its total_phase is not dynamic_phase - geometric_phase",
        ),
        (
            ~close(2.0 * energy * column["period"] / momentum, column["dynamic_phase"]),
            "its dynamic_phase is not 2 E T / M (energy, period, momentum)",
        ),
        (~close(momentum * momentum / (2.0 * energy), column["D"]), "its D is not M^2 / (2E)"),
        (
            k_squared & (m > 1.0) & (m <= 1.0 + 16.0 * _EPS_ONE),
            "its m is above 1 by rounding, as orbits wrote it before 2026-11-29 near "
            "the separatrix (now m <= 1); regenerate the catalog with the command "
            "in its header",
        ),
        (
            ~(k_squared & (m > 0.0) & (m <= 1.0)),
            "its m is not k^2 of its moments and D (eqn:TK), in (0, 1]",
        ),
        (
            frame["closes_after"].astype(str).to_numpy()
            != np.asarray(closes_after(frame["n"].to_numpy(), frame["q"].to_numpy())),
            "its closes_after is not that of n/q",
        ),
    ]


# an ulp of 1 (above it): m's rounding near the separatrix before 2026-11-29
_EPS_ONE = float(np.spacing(1.0))


def _is_k_squared(column, sam):
    """Whether each row's ``m`` is ``k^2`` of eqn:TK from its ``I1, I2, I3, D``.

    ``m = (I2-I1)(I3-D) / ((I3-I2)(D-I1))`` on SAM, its ``1 <-> 3`` image on
    LAM, to :data:`IDENTITY_ULPS` ulps of ``m`` times the quotient's
    condition number ``I3/|I3-D| + D/|D-I1| + I2/(I2-I1) + I3/(I3-I2)``
    (the rounding of the moment and ``D`` columns; at most 2.2 of those
    measured on 5,032 rows of the committed catalogs and of near-symmetric,
    near-flat and thin bodies up to n = 60).  The range ``(0, 1]`` is
    checked beside it (:func:`_identity_problems`).
    """
    i1, i2, i3, d, m = (column[name] for name in ("I1", "I2", "I3", "D", "m"))
    with np.errstate(all="ignore"):  # an edited cell of 1e308 or 0 is refused, not warned of
        quotient = np.where(
            sam,
            (i2 - i1) * (i3 - d) / ((i3 - i2) * (d - i1)),
            (i3 - i2) * (d - i1) / ((i2 - i1) * (i3 - d)),
        )
        condition = i3 / np.abs(i3 - d) + d / np.abs(d - i1) + i2 / (i2 - i1) + i3 / (i3 - i2)
        return np.abs(quotient - m) <= IDENTITY_ULPS * np.spacing(m) * condition


def _one_line(error):
    return " ".join(str(error).split())


# --------------------------------------------------------------- bodies files
# a plain decimal number in ASCII digits: no True, 1_000, 0x10, nan, inf, empty cell
NUMBER = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
BODY_FILE_COLUMNS = ("I1", "I2", "I3", "name")


@dataclass
class BodiesFile:
    """The bodies of a ``--bodies`` CSV, as read by :func:`read_bodies_csv`.

    Attributes
    ----------
    moments : ndarray, shape (n, 3)
        As given on each row (any order and scale), validated.
    names : list of str or None
        The ``name`` column, verbatim; None when the file has none.
    rows : ndarray of int
        The 1-based data-row number of each body (header not counted).
    skipped : list of (int, str)
        Rows skipped by ``skip_invalid``: row number and the reason.
    """

    path: str
    moments: np.ndarray
    names: list
    rows: np.ndarray
    skipped: list = field(default_factory=list)

    def bodies(self):
        """One :class:`Body` per row, named by ``name`` or ``row N``."""
        result = []
        for k, (moments, row) in enumerate(zip(self.moments, self.rows)):
            name = self.names[k] if self.names is not None else f"row {row}"
            try:
                result.append(Body(moments, name=name))
            except OrbitsError as error:
                raise InputError(f"{self.path}, row {row}: {error}") from None
        return result

    def skipped_note(self):
        """One header line listing the skipped rows (empty if none)."""
        if not self.skipped:
            return []
        rows = ", ".join(str(row) for row, _ in self.skipped)
        return [
            f"skipped {plural(len(self.skipped), 'invalid row')} of {self.path} "
            f"(--skip-invalid): {rows}"
        ]


def read_bodies_csv(path, skip_invalid=False):
    """Read a bodies CSV strictly (columns ``I1, I2, I3`` and optionally ``name``).

    The first line is the header; lines before it starting with ``#`` are
    comments.  Every data row must have exactly the header's fields (no
    implicit index column); cells are plain decimal numbers (``True``,
    ``1_000``, ``nan``, an empty cell are errors); names are kept verbatim,
    ``#`` included (quote a name holding a comma).  Validation is
    vectorised, so a bad row in a large file fails fast.

    Parameters
    ----------
    skip_invalid : bool
        Skip bad rows (listed in :attr:`BodiesFile.skipped`) instead of
        raising.

    Raises
    ------
    InputError
        Missing or unreadable file, bad header, no bodies, or (without
        ``skip_invalid``) the first bad row, named by its row number, with
        the count of further bad rows.
    """
    skip_invalid = flag("skip_invalid", skip_invalid)
    text = read_input_text(path, "bodies file")
    lines = text.split("\n")
    start = 0
    while start < len(lines) and (lines[start].startswith("#") or not lines[start].strip("\r")):
        start += 1
    rest = "\n".join(lines[start:])
    _check_quotes_close(path, rest, start)
    try:
        raw_header = next(csv.reader(io.StringIO(rest), strict=True), [])
    except csv.Error as error:
        raise InputError(f"{path} is not a CSV of bodies: {error}") from None
    header = _check_header(path, raw_header)
    cells = _arrow_cells(rest, raw_header) if _have_pyarrow() else None
    if cells is None:
        cells = _python_cells(path, rest, header, start)
    return _validated(path, header, cells, skip_invalid)


def _check_quotes_close(path, rest, start):
    """Refuse a quote that is never closed (both parsers would swallow the rest).

    An unclosed quote makes every later line part of one cell: Arrow and the
    csv module (not strict) read three bodies as one whose name holds the
    other two.  Only a file with an odd number of quotes can hold one, so
    the record-by-record scan runs only then.  ``start`` is the number of
    comment and blank lines before the header.
    """
    if rest.count('"') % 2 == 0:
        return
    reader = csv.reader(io.StringIO(rest), strict=True)
    done = 0  # lines of rest read by whole records
    try:
        for _ in reader:
            done = reader.line_num
    except csv.Error as error:
        if "unexpected end of data" not in str(error):
            return  # another defect: the parsers name it
        raise InputError(
            f"{path}, line {start + done + 1}: a quote opened on this line is never "
            "closed, so every later line would be read into one cell; close the quote"
        ) from None


def header_problems(header, required, allowed):
    """What is wrong with a CSV header, in words, or '' when nothing is.

    ``header``: the stripped column names; every name of ``required`` must
    be there, no name outside ``allowed``, none twice.
    """
    missing = [name for name in required if name not in header]
    unknown = [name for name in header if name not in allowed]
    repeated = sorted({name for name in header if header.count(name) > 1})
    return "; ".join(
        filter(
            None,
            [
                missing and f"missing column(s) {', '.join(missing)}",
                unknown and f"unknown column(s) {', '.join(map(repr, unknown))}",
                repeated and f"repeated column(s) {', '.join(repeated)}",
            ],
        )
    )


def _check_header(path, raw_header):
    if not raw_header:
        raise InputError(f"{path}: no header line (need I1, I2, I3 and optionally name)")
    header = [cell.strip() for cell in raw_header]
    what = header_problems(header, ("I1", "I2", "I3"), BODY_FILE_COLUMNS)
    if what:
        raise InputError(f"{path}: {what} (the header must name I1, I2, I3 and optionally name)")
    return header


@dataclass
class _Cells:
    """The data rows of a bodies file, parsed but not yet validated."""

    count: int
    moments: np.ndarray  # (count, 3); NaN where a cell is not a number
    problems: dict  # row index -> first reason
    whole: np.ndarray  # bool: the row has the header's number of fields
    names: list = None


def _have_pyarrow():
    from importlib.util import find_spec

    return find_spec("pyarrow") is not None


def _arrow_cells(rest, raw_header):
    """Parse with pyarrow's CSV reader (every cell as text), or None to fall back.

    Several times faster than the csv module on large files.  Rows with the
    wrong number of fields are collected by Arrow's invalid-row handler (its
    row numbers count records, like ours: blank lines are not rows).
    Numbers are converted by Arrow's correctly rounded parser, which like
    :data:`NUMBER` refuses ``True``, ``1_000``, ``0x10`` and empty cells;
    ``nan`` and ``inf`` are refused below.  Anything unusual (a stray quote,
    a parse error) returns None: the csv-module path then handles the file.
    """
    import pyarrow as pa
    from pyarrow import csv as pacsv

    if any("\n" in cell or "\r" in cell for cell in raw_header):
        return None
    names = [f"c{k}" for k in range(len(raw_header))]
    data = rest.encode("utf-8")
    if _stray_quote(data):
        return None
    ragged = []  # (0-based data row, its number of fields)

    def collect(row):
        ragged.append((row.number, row.actual_columns))
        return "skip"

    try:
        table = pacsv.read_csv(
            io.BytesIO(data),
            # one thread: the handler then gets row numbers (and it is as fast)
            read_options=pacsv.ReadOptions(column_names=names, skip_rows=1, use_threads=False),
            parse_options=pacsv.ParseOptions(
                newlines_in_values=True, ignore_empty_lines=True, invalid_row_handler=collect
            ),
            convert_options=pacsv.ConvertOptions(
                column_types={name: pa.string() for name in names},
                strings_can_be_null=False,
                quoted_strings_can_be_null=False,
            ),
        )
    except (pa.ArrowInvalid, pa.ArrowNotImplementedError):
        return None
    if any(number is None for number, _ in ragged):
        return None
    header = [cell.strip() for cell in raw_header]
    count = table.num_rows + len(ragged)
    problems = {}
    whole = np.ones(count, dtype=bool)
    for number, fields in ragged:
        # Arrow numbers records from 1 with the header as record 1
        problems[number - 2] = (
            f"{fields} fields, the header has {len(header)} (no implicit index column)"
        )
        whole[number - 2] = False
    place = np.flatnonzero(whole)  # full row index of each row of the table
    columns = []
    for column in ("I1", "I2", "I3"):
        found = {}
        values = _arrow_numbers(column, table.column(names[header.index(column)]), found)
        if values is None:
            return None
        full = np.full(count, np.nan)
        full[place] = values
        for k, reason in found.items():
            problems.setdefault(int(place[k]), reason)
        columns.append(full)
    moments = np.column_stack(columns) if count else np.empty((0, 3))
    names_list = None
    if "name" in header:
        names_list = [""] * count
        for k, name in zip(place.tolist(), table.column(names[header.index("name")]).to_pylist()):
            names_list[k] = name
    return _Cells(count, moments, problems, whole, names_list)


def _stray_quote(data):
    """Whether a quote may stand where the csv module's strict mode refuses it.

    Arrow reads ``"a"b`` as ``ab``; the csv module (strict) refuses a
    closing quote followed by anything but a delimiter.  A quote between two
    characters that are neither delimiters nor quotes marks such a place (or
    a quote inside an unquoted cell, which the csv module then accepts):
    those files take the csv-module path.  Vectorised: ~0.1 s per 30 MB.
    """
    raw = np.frombuffer(data, dtype=np.uint8)
    where = np.flatnonzero(raw == ord('"'))
    if where.size == 0:
        return False
    padded = np.concatenate([[ord("\n")], raw, [ord("\n")]]).astype(np.uint8)
    may_precede, may_follow = np.zeros(256, dtype=bool), np.zeros(256, dtype=bool)
    may_precede[list(b',\n"')] = True
    may_follow[list(b',\r\n"')] = True
    return bool(np.any(~may_precede[padded[where]] & ~may_follow[padded[where + 2]]))


def _arrow_numbers(column, given, problems, whole=None):
    """Float64 values of a text column (NaN where not a number); None to fall back.

    Cells that are not plain decimal numbers are added to ``problems`` (row
    index -> reason), except rows where ``whole`` is False (already wrong).
    """
    import pyarrow as pa
    import pyarrow.compute as pc

    text = pc.utf8_trim_whitespace(given)
    count = len(given)
    try:
        values = pc.cast(text, pa.float64())
        suspects = np.zeros(count, dtype=bool)
    except pa.ArrowInvalid:
        ok = pc.match_substring_regex(text, f"^(?:{NUMBER.pattern})$")
        suspects = ~ok.to_numpy(zero_copy_only=False)
        try:
            values = pc.cast(pc.if_else(ok, text, "nan"), pa.float64())
        except pa.ArrowInvalid:
            return None
    values = np.array(values.to_numpy(zero_copy_only=False), dtype=float)
    # nan, inf, infinity: parsed by Arrow, refused here (an overflowing
    # decimal such as 1e400 is a number; the moments check refuses it)
    suspects |= ~np.isfinite(values)
    for k in np.flatnonzero(suspects):
        cell = given[int(k)].as_py()
        if not NUMBER.fullmatch(cell.strip()):
            values[k] = np.nan
            if whole is None or whole[k]:
                problems.setdefault(int(k), f"{column} {cell!r} is not a number")
    for k in np.flatnonzero(values == 0.0):
        _note_underflow(column, given[int(k)].as_py(), 0.0, int(k), problems, whole)
    return values


def _note_underflow(column, cell, value, k, problems, whole):
    """A cell such as ``1e-400`` reads as 0: say so, not "moments (0, ...)"."""
    sign = read_as_zero(cell, value)
    if sign is not None and (whole is None or whole[k]):
        problems.setdefault(
            k,
            f"{column} {cell.strip()} is {sign}below the smallest normal double "
            "(2.2e-308): it reads as 0",
        )


def _python_cells(path, rest, header, start=0):
    """Parse with the csv module: slower, but names every malformed row."""
    reader = csv.reader(io.StringIO(rest), strict=True)
    records = []
    try:
        for record in reader:
            records.append(record)
    except csv.Error as error:
        raise InputError(
            f"{path}, line {start + reader.line_num}: not a CSV of bodies: {error}"
        ) from None
    data = [r for r in records[1:] if r]  # blank lines
    width = len(header)
    count = len(data)
    problems = {}
    lengths = np.fromiter((len(r) for r in data), dtype=np.int64, count=count)
    for k in np.flatnonzero(lengths != width):
        problems[int(k)] = (
            f"{lengths[k]} fields, the header has {width} (no implicit index column)"
        )
    whole = lengths == width
    columns = []
    for column in ("I1", "I2", "I3"):
        j = header.index(column)
        values = [r[j] if len(r) == width else "0" for r in data]
        numbers = None
        if _have_pyarrow():
            import pyarrow as pa

            numbers = _arrow_numbers(column, pa.array(values, pa.string()), problems, whole)
        if numbers is None:
            numbers = np.full(count, np.nan)
            for k, cell in enumerate(values):
                if NUMBER.fullmatch(cell.strip()):
                    numbers[k] = float(cell)
                    _note_underflow(column, cell, numbers[k], k, problems, whole)
                elif whole[k]:
                    problems.setdefault(k, f"{column} {cell!r} is not a number")
        columns.append(numbers)
    moments = np.column_stack(columns) if count else np.empty((0, 3))
    names = None
    if "name" in header:
        j = header.index("name")
        names = [r[j] if len(r) == width else "" for r in data]
    return _Cells(count, moments, problems, whole, names)


def _validated(path, header, cells, skip_invalid):
    """Check the moments of every row; raise or skip the bad rows."""
    count, moments, problems, names = cells.count, cells.moments, cells.problems, cells.names
    if not count:
        raise InputError(f"{path}: no bodies")
    _check_rows(moments, names, problems)
    candidate = np.array(sorted(set(range(count)) - set(problems)), dtype=np.int64)
    for k in _invalid_moments(moments[candidate]):
        index = int(candidate[k])
        problems[index] = _body_error(moments[index])

    def label(k):
        return f"{path}, row {k + 1}" + (
            f" ({names[k]!r})" if names is not None and cells.whole[k] else ""
        )

    bad = sorted(problems)
    if bad and not skip_invalid:
        more = len(bad) - 1
        tail = f"; {plural(more, 'more bad row')} (--skip-invalid skips them)" if more else ""
        raise InputError(f"{label(bad[0])}: {problems[bad[0]]}{tail}")
    keep = np.ones(count, dtype=bool)
    keep[bad] = False
    if not keep.any():
        raise InputError(
            f"{path}: all {count} rows are invalid (first: row {bad[0] + 1}: {problems[bad[0]]})"
        )
    return BodiesFile(
        path=str(path),
        moments=moments[keep],
        names=None if names is None else [n for n, k in zip(names, keep) if k],
        rows=np.flatnonzero(keep) + 1,
        skipped=[(k + 1, f"{label(k)}: {problems[k]}") for k in bad],
    )


# a line of a multi-line name that looks like a row of moments: an unclosed
# quote closed only by a later row's quote swallowed the rows in between
_SWALLOWED_ROW = re.compile(
    rf"(?:^|,)\s*{NUMBER.pattern}\s*,\s*{NUMBER.pattern}\s*,\s*{NUMBER.pattern}\s*(?:,|$)"
)


def _check_rows(moments, names, problems):
    """Add the problems both parsers share: subnormal moments, swallowed rows.

    A moment below the smallest normal double is refused as ``--moments``
    refuses it (:func:`orbits._args.below_normal`); a name whose later lines
    look like rows of moments is refused as a misplaced quote.
    """
    for k, j in zip(*np.nonzero(below_normal(moments))):
        problems.setdefault(
            int(k), below_normal_message(f"{BODY_FILE_COLUMNS[j]} {moments[k, j]:.3g}")
        )
    for k, name in enumerate(names or ()):
        if ("\n" in name or "\r" in name) and any(
            _SWALLOWED_ROW.search(line) for line in name.splitlines()[1:]
        ):
            problems.setdefault(
                k,
                "the name spans lines that look like rows of bodies: a quote opened in "
                "it is closed only on a later line; close it where the name ends",
            )


def _invalid_moments(moments):
    """Indices of rows that :func:`orbits.bodies.validate_moments` rejects."""
    if moments.shape[0] == 0:
        return []
    ordered = np.sort(moments, axis=1)
    try:
        validate_moments(ordered)
        return []
    except OrbitsError:
        pass
    # at least one bad row: find every one (vectorised checks first, then
    # the validator row by row on what they did not explain)
    with np.errstate(invalid="ignore", over="ignore", under="ignore"):
        # the triangle test as the validator makes it: exact, at unit scale
        scale = np.frexp(np.where(np.isfinite(ordered[:, 2]), ordered[:, 2], 1.0))[1]
        unit = np.ldexp(ordered, -scale[:, None])
        flags = (
            ~np.all(np.isfinite(ordered), axis=1)
            | (ordered[:, 0] <= 0)
            | (ordered[:, 0] == ordered[:, 1])
            | (ordered[:, 1] == ordered[:, 2])
            | (flat_excess(unit) > FLAT_SLACK * unit[:, 2])
        )
    bad = set(np.flatnonzero(flags).tolist())
    rest = np.flatnonzero(~flags)
    try:
        validate_moments(ordered[rest])
    except OrbitsError:
        for k in rest:
            try:
                validate_moments(ordered[k : k + 1])
            except OrbitsError:
                bad.add(int(k))
    return sorted(bad)


def _body_error(moments):
    try:
        Body(moments)
    except OrbitsError as error:
        return str(error)
    return "invalid moments"


def bodies_from_csv(path, skip_invalid=False):
    """Bodies listed in a CSV with columns ``I1, I2, I3`` (and optionally ``name``).

    Moments may be in any order and scale on each row.  See
    :func:`read_bodies_csv` for the rules; this returns the list of
    :class:`Body`.

    Raises
    ------
    InputError
        Missing file or columns; the row number of an invalid body.
    """
    return read_bodies_csv(path, skip_invalid).bodies()
