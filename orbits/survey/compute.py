"""The survey's computation: one chunk of bodies to its two tables, and its cost.

:func:`compute_chunk` is a pure function of the bodies and the levels (the
same on a dask worker as here), so every engine writes the same bytes.
"""

import math

import numpy as np

from ..bodies import unit_moments
from ..core import rows as _rows
from ..core import search as _kernels
from ..errors import InputError
from ..limits import (
    MAX_SECONDS,
    about_bytes,
    about_duration,
    format_bytes,
    level_estimate,
    memory_budget,
    search_estimate,
    short_number,
)
from ..search import catalog_rows, phase_levels, search_bodies, searched
from ..threads import threads_for

# the bodies table; its float columns are those orbits.core.rows.body_columns
# computes, in its order
BODY_COLUMNS = (
    "body",
    *_rows.BODY_FLOAT_COLUMNS,
    "min_at_end",
    "orbits",
    "n_smallest",
    "n_largest",
    "unresolved",
)
# relative slack for "the numerical minimum is the end value"
_END_TOLERANCE = 1e-12
# how near (rad) the minimum's dtheta must lie to its branch's end
_END_SLACK = 1e-9 * math.pi


# the per-root columns a compact survey keeps (everything else is derived)
COMPACT_COLUMNS = ("body", "branch", "n", "q", "dtheta")
# the canonical moments (orbits.bodies.unit_moments) of each body, kept in a
# compact survey's bodies table so that the derived columns are those of
# orbits.catalog bit for bit
UNIT_COLUMNS = ("unit_I1", "unit_I2", "unit_I3")
LAYOUTS = ("compact", "all")
# columns stored as codes into these labels (orbits.core.rows.CODE_SAM, CODE_LAM)
CATEGORIES = {"branch": ("SAM", "LAM")}


# --------------------------------------------------------------- computing
class ChunkSearch:
    """The search's result for one chunk: canonical moments, levels, flat roots.

    Attributes
    ----------
    moments : ndarray (n, 3)
        Canonical moments (:func:`orbits.bodies.unit_moments`).
    p, q, levels : ndarray
        The searched levels ``2 pi p/q``.
    info : ndarray (n, INFO_SIZE)
        The search's per-body information (minima, widths, unreached).
    body, code, level, offset : ndarray
        One entry per root: body index in the chunk, branch (0 SAM, 1 LAM),
        level index, ``dtheta`` (rad); by body, then by ``dtheta``.  Made
        on first use (:func:`chunk_tables`, on the thread that builds the
        tables) from the search's per-body arrays.
    """

    def __init__(self, moments, p, q, levels, info, per_body):
        self.moments, self.p, self.q, self.levels, self.info = moments, p, q, levels, info
        self._per_body = per_body
        self._rows = None

    def _flat(self):
        if self._rows is None:
            self._rows = _flatten(self.moments, self.levels, *self._per_body, self.info)
            self._per_body = None
        return self._rows

    @property
    def body(self):
        return self._flat()[0]

    @property
    def code(self):
        return self._flat()[1]

    @property
    def level(self):
        return self._flat()[2]

    @property
    def offset(self):
        return self._flat()[3]


def search_chunk(moments, n_max, q_max=1, device="cpu"):
    """Search every body of a chunk (the parallel kernel, all cores, or the GPU).

    ``device="cuda"`` runs the search on an NVIDIA GPU
    (:func:`orbits.search.search_bodies`); the tables are built on the CPU
    either way.

    Returns
    -------
    ChunkSearch
    """
    moments = np.ascontiguousarray(unit_moments(moments)[0], dtype=float).reshape(-1, 3)
    count = moments.shape[0]
    p, q, all_levels = phase_levels(n_max, q_max)
    # levels 2 pi p/q <= 2 pi have no roots (orbits.search.searched)
    keep = np.flatnonzero(searched(p, q))
    p, q, levels = p[keep], q[keep], np.ascontiguousarray(all_levels[keep])
    capacity = 2 * levels.size + 8
    if device == "cuda":
        rows = search_bodies(moments, levels, capacity=capacity, device="cuda")
        branch, level, offset, found, info = rows
        return ChunkSearch(moments, p, q, levels, info, (branch, level, offset, found))
    info = np.empty((count, _kernels.INFO_SIZE))
    branch = np.empty((count, capacity), dtype=np.int8)
    level = np.empty((count, capacity), dtype=np.int64)
    offset = np.empty((count, capacity))
    found = np.empty(count, dtype=np.int64)
    with threads_for(count, serial_below=2):
        _kernels.search_many(moments, levels, branch, level, offset, found, info)
    return ChunkSearch(moments, p, q, levels, info, (branch, level, offset, found))


def compute_chunk(moments, n_max, q_max=1, first_id=0, columns="all"):
    """Closed orbits and minimum phases for a block of bodies.

    Parameters
    ----------
    moments : ndarray (n, 3)
        Principal moments, each row sorted or not, any scale.
    n_max, q_max : int
        As :func:`orbits.closed_orbits`.
    first_id : int
        Survey-wide id of the first body (the ``body`` column).
    columns : {"all", "compact"}
        ``"all"``: every catalog column per orbit.  ``"compact"``: only
        :data:`COMPACT_COLUMNS` per orbit, and the bodies table also keeps
        :data:`UNIT_COLUMNS` (:func:`derive_orbit_rows` makes the rest).

    Returns
    -------
    bodies, orbits : pandas.DataFrame
        ``bodies`` has the columns :data:`BODY_COLUMNS` (and with
        ``"compact"`` the unit moments); ``orbits`` the catalog schema
        (:data:`orbits.CATALOG_COLUMNS`) or :data:`COMPACT_COLUMNS`, with
        ``body`` the body's id.
    """
    return chunk_tables(search_chunk(moments, n_max, q_max), first_id, columns)


def chunk_tables(found, first_id, columns="all"):
    """The two tables of a searched chunk (:func:`search_chunk`), as DataFrames.

    :func:`chunk_columns` made into DataFrames (the branch a categorical);
    see :func:`compute_chunk` for the arguments and the result.
    """
    return tuple(as_frame(table) for table in chunk_columns(found, first_id, columns))


def chunk_columns(found, first_id, columns="all"):
    """The two tables of a searched chunk, as the survey writes them.

    Runs on one thread (the survey runs chunks side by side).  The compact
    tables are plain arrays, made without pandas: a survey command never
    loads it (its import is a tenth of a second of serial start-up).

    Parameters
    ----------
    found : ChunkSearch
    first_id : int
        Survey-wide id of the chunk's first body.
    columns : {"all", "compact"}
        As :func:`compute_chunk`.

    Returns
    -------
    bodies : dict
        Column name to 1-d array, in table order (:data:`BODY_COLUMNS`,
        then with ``"compact"`` :data:`UNIT_COLUMNS`).
    orbits : dict or pandas.DataFrame
        ``"compact"``: :data:`COMPACT_COLUMNS`, the branch as its codes
        into :data:`CATEGORIES` ``["branch"]``.  ``"all"``: the catalog
        DataFrame (:func:`orbits.search.catalog_rows`).
    """
    if columns not in LAYOUTS:
        raise InputError(f"columns must be one of {', '.join(LAYOUTS)}, got {columns!r}")
    ids = first_id + np.arange(found.moments.shape[0], dtype=np.int64)
    n, q = found.p[found.level], found.q[found.level]
    if columns == "all":
        orbits = catalog_rows(
            ids[found.body],
            found.moments[found.body],
            found.level,
            found.offset,
            found.p,
            found.q,
            found.levels,
        )
    else:
        orbits = dict(
            zip(COMPACT_COLUMNS, (ids[found.body], found.code, n, q, found.offset), strict=True)
        )
    bodies = _body_columns(found, ids, n, q)
    if columns == "compact":
        for k, name in enumerate(UNIT_COLUMNS):
            bodies[name] = found.moments[:, k]
    return bodies, orbits


def as_frame(table):
    """A table of :func:`chunk_columns` as a pandas DataFrame (a DataFrame as it is).

    Columns named in :data:`CATEGORIES` hold codes and become categoricals.
    """
    import pandas as pd

    if isinstance(table, pd.DataFrame):
        return table
    data = {
        name: pd.Categorical.from_codes(values, categories=list(CATEGORIES[name]))
        if name in CATEGORIES
        else values
        for name, values in table.items()
    }
    return pd.DataFrame(data, columns=list(data), copy=False)


def derive_orbit_rows(compact, unit, first_id, n_max, q_max):
    """Every catalog column of a compact chunk's orbits, as :func:`orbits.catalog` gives them.

    Parameters
    ----------
    compact : pandas.DataFrame
        :data:`COMPACT_COLUMNS` of one chunk, by body then ``dtheta``.
    unit : ndarray (n, 3)
        The chunk's canonical moments (:data:`UNIT_COLUMNS`), body
        ``first_id + k`` in row k.
    n_max, q_max : int
        The survey's (each row's level must be one of its levels).

    Returns
    -------
    pandas.DataFrame
        The catalog schema, equal bit for bit to ``orbits.catalog`` of each
        body (with ``body`` the id): the same kernels on the same canonical
        moments and the same ``dtheta``.

    Raises
    ------
    InputError
        A row that is not an orbit of its body (not a level of the survey,
        another branch than its ``dtheta`` says, or a missed level).
    """
    body = compact["body"].to_numpy()
    n = compact["n"].to_numpy().astype(np.int64)
    q = compact["q"].to_numpy().astype(np.int64)
    offset = compact["dtheta"].to_numpy().astype(float)
    p_all, q_all, values = phase_levels(n_max, q_max)
    # each row's level: the index of (n, q) among the survey's levels
    keys = p_all * (q_max + 1) + q_all
    order = np.argsort(keys, kind="stable")
    where = np.searchsorted(keys[order], n * (q_max + 1) + np.clip(q, 0, q_max))
    level = order[np.minimum(where, len(order) - 1)]
    if len(level) and (
        (p_all[level] != n).any()
        or (q_all[level] != q).any()
        or not searched(n, q).all()
        or (body - first_id).min() < 0
        or (body - first_id).max() >= len(unit)
    ):
        raise InputError("orbit rows that are not orbits of the survey's levels and bodies")
    try:
        frame = catalog_rows(body, unit[body - first_id], level, offset, p_all, q_all, values)
    except RuntimeError as error:  # a root that misses its level: damage
        raise InputError(f"an orbit row misses its level ({error})") from None
    stored = compact["branch"].astype(str).to_numpy()
    if not np.array_equal(stored, frame["branch"].to_numpy()):
        raise InputError("an orbit row's branch is not the branch of its dtheta")
    return frame


def _flatten(moments, levels, branch, level, offset, found, info):
    """Per-body root arrays to flat rows, sorted by body then dtheta.

    A body whose roots overflowed its row (``found < 0``: a phase with
    many monotone pieces) is searched again with room to spare.
    """
    rows = _rows.flat_rows(branch, level, offset, found)
    if not (found < 0).any():
        return rows  # already by body, then dtheta
    body, code, rows_level, rows_offset = rows
    for b in np.flatnonzero(found < 0):
        size = 8 * level.shape[1]
        extra = (np.empty(size, np.int8), np.empty(size, np.int64), np.empty(size))
        n = _kernels.search_body(*moments[b], levels, *extra, info[b])
        body = np.concatenate([body, np.full(n, b)])
        code = np.concatenate(
            [code, np.where(extra[0][:n] > 0, _rows.CODE_SAM, _rows.CODE_LAM).astype(np.int8)]
        )
        rows_level = np.concatenate([rows_level, extra[1][:n]])
        rows_offset = np.concatenate([rows_offset, extra[2][:n]])
    order = np.lexsort((rows_offset, body))
    return body[order], code[order], rows_level[order], rows_offset[order]


def _body_columns(found, ids, n, q):
    """The bodies table of a searched chunk: one compiled pass
    (:func:`orbits.core.rows.body_columns`) and the per-body counts."""
    floats, at_end, unresolved = _rows.body_columns(
        found.moments, found.info, _END_SLACK, _END_TOLERANCE
    )
    counts, n_small, n_large = _rows.body_counts(found.body, n, q, len(ids))
    columns = {"body": ids}
    columns.update(zip(_rows.BODY_FLOAT_COLUMNS, floats, strict=True))
    columns.update(
        min_at_end=at_end,
        orbits=counts,
        n_smallest=n_small,
        n_largest=n_large,
        unresolved=unresolved,
    )
    return columns


# --------------------------------------------------------------- bounds
# measured here (Newton search, Parquet): 10,005,794 bodies with n_max = 10 in
# 232 s on 2 cores, i.e. 2.3e-5 s per body with about 16 levels
_SECONDS_PER_BODY = 2e-5
_SECONDS_PER_BODY_LEVEL = 2e-7
# each chunk writes two parts (fsync'ed) and the whole manifest again, whose
# ledger grows by one entry a chunk: `--resolution 200 --n-max 30` (15,402
# bodies) took 8.6 s with --chunk 20 (771 chunks) and 102.6 s with --chunk 5
# (3,081 chunks) on the 2-core VM (2026-11-28): about 2.2 ms a chunk plus
# 20 us per ledger entry rewritten
_SECONDS_PER_CHUNK = 2.2e-3
_SECONDS_PER_LEDGER_ENTRY = 2e-5
_BYTES_PER_ROW = 600  # an orbit row: kernel arrays, DataFrame, CSV text
GRID_INSIDE = 0.39  # fraction of the bounding box inside the region


def survey_estimate(bodies, n_max, q_max, chunk):
    """Rough peak memory (bytes) and total time (s) of a survey.

    A chunk holds up to two orbits per level and body; the memory is two
    chunks' rows (one being written while the next is computed).  The time
    counts each chunk's files and its rewrite of the manifest, whose ledger
    grows with the chunks (so a small ``chunk`` costs time quadratically).
    """
    level_memory, _ = search_estimate(n_max, q_max, bodies=0)
    _, levels = level_estimate(n_max, q_max)
    per_chunk = min(chunk, bodies)
    # zero bodies add nothing (not inf * 0 = NaN when n_max overflows a double)
    rows = 2 * per_chunk * (2.0 * levels * _BYTES_PER_ROW + 34.0 * levels) if per_chunk else 0.0
    memory = level_memory + rows
    seconds = bodies * (_SECONDS_PER_BODY + levels * _SECONDS_PER_BODY_LEVEL) if bodies else 0.0
    chunks = -(-bodies // chunk) if bodies else 0
    seconds += chunks * _SECONDS_PER_CHUNK + 0.5 * chunks * chunks * _SECONDS_PER_LEDGER_ENTRY
    return memory, seconds


def check_survey_bounds(bodies, n_max, q_max, chunk):
    """Refuse a survey whose memory or time would exceed the machine.

    Raises
    ------
    InputError
        With the estimate and the largest ``chunk`` that would fit.
    """
    memory, seconds = survey_estimate(bodies, n_max, q_max, chunk)
    budget = memory_budget()
    if not memory <= budget:  # also a NaN estimate (inf * 0 for a huge n_max)
        one, _ = survey_estimate(1, n_max, q_max, 1)
        base, _ = survey_estimate(0, n_max, q_max, 0)
        room = (budget - base) / max(one - base, 1.0)
        fits = int(room) if math.isfinite(room) and room >= 1.0 else 0
        advice = f"use --chunk {fits} or less" if fits >= 1 else "lower --n-max or --q-max"
        raise InputError(
            f"this survey (n_max={short_number(n_max)}, q_max={short_number(q_max)}, "
            f"chunk={chunk}) "
            f"would need {about_bytes(memory)} of memory per chunk, more "
            f"than the {format_bytes(budget)} allowed (half of this machine's); "
            f"{advice}"
        )
    if not seconds <= MAX_SECONDS:
        raise InputError(
            f"this survey ({bodies} bodies, n_max={short_number(n_max)}, "
            f"q_max={short_number(q_max)}) "
            f"would take {about_duration(seconds)}; use fewer bodies, "
            f"a lower --n-max or a larger --chunk (now {chunk})"
        )
    return memory, seconds
