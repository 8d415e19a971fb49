"""The survey's computation: one chunk of bodies to its two tables, and its cost.

:func:`compute_chunk` is a pure function of the bodies and the levels (the
same on a dask worker as here), so every engine writes the same bytes.
"""

import math

import numpy as np
import pandas as pd

from ..bodies import unit_moments
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
from ..phases import phase_limits
from ..search import catalog_rows, phase_levels, searched

BODY_COLUMNS = (
    "body",
    "I1",
    "I2",
    "I3",
    "theta_crit",
    "limit_theta_zero",
    "limit_theta_half_pi",
    "min_total_phase",
    "min_dtheta",
    "min_theta",
    "min_at_end",
    "orbits",
    "n_smallest",
    "n_largest",
    "unresolved",
)
# relative slack for "the numerical minimum is the end value"
_END_TOLERANCE = 1e-12


# --------------------------------------------------------------- computing
def compute_chunk(moments, n_max, q_max=1, first_id=0):
    """Closed orbits and minimum phases for a block of bodies.

    Parameters
    ----------
    moments : ndarray (n, 3)
        Principal moments, each row sorted or not, any scale.
    n_max, q_max : int
        As :func:`orbits.closed_orbits`.
    first_id : int
        Survey-wide id of the first body (the ``body`` column).

    Returns
    -------
    bodies, orbits : pandas.DataFrame
        ``bodies`` has the columns :data:`BODY_COLUMNS`; ``orbits`` the
        catalog schema (:data:`orbits.CATALOG_COLUMNS`) with ``body`` the
        body's id.
    """
    moments = np.ascontiguousarray(unit_moments(moments)[0], dtype=float).reshape(-1, 3)
    count = moments.shape[0]
    p, q, all_levels = phase_levels(n_max, q_max)
    # levels 2 pi p/q <= 2 pi have no roots (orbits.search.searched)
    keep = np.flatnonzero(searched(p, q))
    p, q, levels = p[keep], q[keep], np.ascontiguousarray(all_levels[keep])
    capacity = 2 * levels.size + 8
    info = np.empty((count, _kernels.INFO_SIZE))
    branch = np.empty((count, capacity), dtype=np.int8)
    level = np.empty((count, capacity), dtype=np.int64)
    offset = np.empty((count, capacity))
    found = np.empty(count, dtype=np.int64)
    _kernels.search_many(moments, levels, branch, level, offset, found, info)
    rows_body, rows_level, rows_offset = _flatten(moments, levels, level, offset, found, info)
    ids = first_id + np.arange(count)
    orbits = catalog_rows(
        ids[rows_body], moments[rows_body], rows_level, rows_offset, p, q, levels
    )
    bodies = _body_rows(moments, ids, info, orbits, rows_body)
    return bodies, orbits


def _flatten(moments, levels, level, offset, found, info):
    """Per-body root arrays to flat rows, sorted by body then dtheta.

    A body whose roots overflowed its row (``found < 0``: a phase with
    many monotone pieces) is searched again with room to spare.
    """
    body, rows_level, rows_offset = _kernels.flatten_roots(level, offset, found)
    if not (found < 0).any():
        return body, rows_level, rows_offset  # already by body, then dtheta
    for b in np.flatnonzero(found < 0):
        size = 8 * level.shape[1]
        extra = (np.empty(size, np.int8), np.empty(size, np.int64), np.empty(size))
        n = _kernels.search_body(*moments[b], levels, *extra, info[b])
        body = np.concatenate([body, np.full(n, b)])
        rows_level = np.concatenate([rows_level, extra[1][:n]])
        rows_offset = np.concatenate([rows_offset, extra[2][:n]])
    order = np.lexsort((rows_offset, body))
    return body[order], rows_level[order], rows_offset[order]


def _body_rows(moments, ids, info, orbits, body_of_row):
    norm = np.linalg.norm(moments, axis=1)
    limits = phase_limits(moments)
    theta_c = info[:, _kernels.INFO_WIDTH_SAM]
    sam_min = info[:, _kernels.INFO_MIN_SAM]
    lam_min = info[:, _kernels.INFO_MIN_LAM]
    use_sam = sam_min <= lam_min
    # >= 2 pi for every body (orbits.search._at_least_two_pi)
    minimum = np.maximum(np.where(use_sam, sam_min, lam_min), 2.0 * np.pi)
    where = np.where(use_sam, info[:, _kernels.INFO_MIN_AT_SAM], info[:, _kernels.INFO_MIN_AT_LAM])
    end_value = np.minimum(limits.theta_zero, limits.theta_half_pi)
    at_end = (
        np.abs(np.abs(where) - np.where(use_sam, theta_c, info[:, _kernels.INFO_WIDTH_LAM]))
        <= 1e-9 * np.pi
    ) & (minimum >= end_value * (1.0 - _END_TOLERANCE))
    integer = orbits["q"].to_numpy() == 1 if len(orbits) else np.zeros(0, bool)
    counts = np.bincount(body_of_row, minlength=len(ids))
    n_small = np.full(len(ids), -1, dtype=np.int64)
    n_large = np.full(len(ids), -1, dtype=np.int64)
    if integer.any():
        frame = pd.DataFrame({"b": body_of_row[integer], "n": orbits["n"].to_numpy()[integer]})
        grouped = frame.groupby("b")["n"]
        n_small[grouped.min().index] = grouped.min().to_numpy()
        n_large[grouped.max().index] = grouped.max().to_numpy()
    return pd.DataFrame(
        {
            "body": ids,
            "I1": moments[:, 0] / norm,
            "I2": moments[:, 1] / norm,
            "I3": moments[:, 2] / norm,
            "theta_crit": theta_c,
            "limit_theta_zero": limits.theta_zero,
            "limit_theta_half_pi": limits.theta_half_pi,
            "min_total_phase": minimum,
            "min_dtheta": where,
            "min_theta": theta_c + where,
            "min_at_end": at_end,
            "orbits": counts,
            "n_smallest": n_small,
            "n_largest": n_large,
            "unresolved": (
                info[:, _kernels.INFO_UNREACHED_SAM] + info[:, _kernels.INFO_UNREACHED_LAM]
            ).astype(np.int64),
        },
        columns=list(BODY_COLUMNS),
        copy=False,  # one block per column: no consolidating copy
    )


# --------------------------------------------------------------- bounds
# measured here (Newton search, Parquet): 10,005,794 bodies with n_max = 10 in
# 232 s on 2 cores, i.e. 2.3e-5 s per body with about 16 levels
_SECONDS_PER_BODY = 2e-5
_SECONDS_PER_BODY_LEVEL = 2e-7
_BYTES_PER_ROW = 600  # an orbit row: kernel arrays, DataFrame, CSV text
GRID_INSIDE = 0.39  # fraction of the bounding box inside the region


def survey_estimate(bodies, n_max, q_max, chunk):
    """Rough peak memory (bytes) and total time (s) of a survey.

    A chunk holds up to two orbits per level and body; the memory is two
    chunks' rows (one being written while the next is computed).
    """
    level_memory, _ = search_estimate(n_max, q_max, bodies=0)
    _, levels = level_estimate(n_max, q_max)
    per_chunk = min(chunk, bodies)
    # zero bodies add nothing (not inf * 0 = NaN when n_max overflows a double)
    rows = 2 * per_chunk * (2.0 * levels * _BYTES_PER_ROW + 34.0 * levels) if per_chunk else 0.0
    memory = level_memory + rows
    seconds = bodies * (_SECONDS_PER_BODY + levels * _SECONDS_PER_BODY_LEVEL) if bodies else 0.0
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
            f"would take {about_duration(seconds)}; use fewer bodies or "
            "a lower --n-max"
        )
    return memory, seconds
