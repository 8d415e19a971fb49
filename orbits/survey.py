"""Body-space survey: closed orbits and minimum phases over many bodies.

A survey covers the region of physical asymmetric bodies in the paper's
I1-I2 plane (``|I| = 1``), or an explicit list, and writes a directory::

    DIR/manifest.json          parameters (a rerun must match them) and ledger
    DIR/bodies/part-NNNNN.parquet  one row per body (or .csv)
    DIR/orbits/part-NNNNN.parquet  the closed orbits, catalog schema
    DIR/report.json            summary and the minimum-at-the-ends test

The bodies are cut into chunks; each finished chunk is written atomically
(orbits, then bodies), and then recorded in the manifest's ledger (file
names, row counts, body-id range, SHA-256 of each part).  A chunk is done
exactly when its ledger entry matches its files: a rerun checks every part,
recomputes the missing or damaged ones and never reads a file that is not
in the ledger.  One run at a time holds the directory (``fcntl`` lock).

Chunks run in-process on all cores (numba), or on a ``dask.distributed``
cluster (``scheduler="tcp://host:port"`` or a ``Client``): the same
function computes each chunk there and the results come back to be written
here, so both engines write identical files.
"""

import hashlib
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd

from ._args import integer, path_argument, real_array
from ._version import __version__
from .atomic import (
    FLOAT_FORMAT,
    atomic_path,
    read_bytes_nofollow,
    refuse_link,
    write_text_atomic,
)
from .bodies import as_moments, region_grid, unit_moments
from .cells import neutralize, unneutralize
from .core import search as _kernels
from .errors import ArgumentTypeError, InputError
from .limits import (
    MAX_SECONDS,
    about_bytes,
    about_duration,
    check_resolution,
    format_bytes,
    level_estimate,
    memory_budget,
    search_estimate,
    short_number,
)
from .phases import phase_limits
from .search import catalog_rows, phase_levels, searched

FORMATS = ("csv", "parquet")
DEFAULT_CHUNK = 20_000
# seconds to wait for a dask scheduler before giving up
CONNECT_TIMEOUT = 10
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


# --------------------------------------------------------------- the survey
MANIFEST = "manifest.json"
REPORT = "report.json"
LOCK = ".lock"
# 3: the manifest carries its own SHA-256; 2 (read, not resumed): without
SURVEY_FORMAT = 3
READABLE_FORMATS = (2, 3)
TABLES = ("bodies", "orbits")


class Survey:
    """A survey's parameters, bodies and output directory.

    Build with :meth:`grid` (``N x N`` over the region's bounding box) or
    :meth:`from_bodies`; :meth:`run` computes the missing chunks.

    The directory proves itself: ``manifest.json`` keeps, besides the
    parameters, a ledger of every finished part (file, row count, body-id
    range, SHA-256).  A part counts as done only when its ledger entry
    matches the file; a rerun recomputes the others, and files not in the
    ledger (e.g. ``part-00001.csv.bak``) are never read.  One run at a time
    writes a directory (an exclusive ``fcntl`` lock on ``DIR/.lock``).
    """

    def __init__(
        self,
        out_dir,
        moments,
        source,
        n_max,
        q_max=1,
        fmt="parquet",
        chunk=DEFAULT_CHUNK,
        names=None,
        skipped=(),
    ):
        if fmt not in FORMATS:
            raise InputError(f"format must be one of {', '.join(FORMATS)}, got {fmt!r}")
        if fmt == "parquet":
            _require_pyarrow()
        n_max, q_max, chunk = (
            integer(name, value)
            for name, value in (("n_max", n_max), ("q_max", q_max), ("chunk", chunk))
        )
        self.out_dir = Path(path_argument("out_dir", out_dir))
        self.moments = np.ascontiguousarray(as_moments(moments), dtype=float).reshape(-1, 3)
        if self.moments.shape[0] == 0:
            raise InputError("a survey needs at least one body")
        self.n_max, self.q_max, self.format, self.chunk = int(n_max), int(q_max), fmt, int(chunk)
        check_survey_bounds(self.moments.shape[0], self.n_max, self.q_max, self.chunk)
        if names is not None:
            names = [str(name) for name in names]
            if len(names) != self.moments.shape[0]:
                raise InputError(f"{len(names)} names for {self.moments.shape[0]} bodies")
        self.names = names
        self.source = source
        self.skipped = list(skipped)
        # what the survey *means*: the bodies by content, not by path
        self.parameters = {
            "orbits_version": __version__,
            "bodies": {"grid": int(source["grid"])} if "grid" in source else "list",
            "body_count": int(self.moments.shape[0]),
            "bodies_sha256": hashlib.sha256(self.moments.tobytes()).hexdigest(),
            # JSON of the list: unambiguous (["a\nb", "c"] is not ["a", "b\nc"])
            "names_sha256": None
            if names is None
            else hashlib.sha256(json.dumps(names).encode("ascii")).hexdigest(),
            "n_max": self.n_max,
            "q_max": self.q_max,
            "format": fmt,
            "chunk": self.chunk,
        }

    @classmethod
    def grid(cls, out_dir, resolution, n_max, **kwargs):
        """Bodies on an ``N x N`` grid over the region's bounding box."""
        resolution = check_resolution(resolution)
        moments = region_grid(resolution)
        return cls(out_dir, moments, {"grid": resolution}, n_max, **kwargs)

    @classmethod
    def from_bodies(cls, out_dir, bodies, n_max, source="list", **kwargs):
        """An explicit list of bodies (Body objects or moments).

        Names of :class:`~orbits.Body` objects are kept (a ``name`` column
        in the bodies table) unless ``names`` is given.
        """
        if isinstance(bodies, (str, bytes)) or not hasattr(bodies, "__iter__"):
            raise ArgumentTypeError(
                f"bodies must be an iterable of Body objects or "
                f"moments, got {type(bodies).__name__}"
            )
        bodies = list(bodies)
        if not bodies:
            raise InputError("a survey needs at least one body")
        moments = real_array("bodies", [getattr(b, "moments", b) for b in bodies], InputError)
        if (
            "names" not in kwargs
            and bodies
            and all(getattr(b, "name", None) is not None for b in bodies)
        ):
            kwargs["names"] = [b.name for b in bodies]
        return cls(out_dir, moments, {"file": str(source)}, n_max, **kwargs)

    @property
    def chunks(self):
        return -(-self.moments.shape[0] // self.chunk)

    def _part(self, table, index):
        return self.out_dir / table / f"part-{index:05d}.{self.format}"

    # ------------------------------------------------------------ directory
    def _refuse_foreign_directory(self):
        import re

        if self.out_dir.exists() and not self.out_dir.is_dir():
            raise InputError(f"{self.out_dir} exists and is not a directory")
        if not self.out_dir.is_dir():
            return
        refuse_links(self.out_dir)
        if (self.out_dir / MANIFEST).exists():
            return
        if _has_parts(self.out_dir):
            raise InputError(_NO_MANIFEST.format(directory=self.out_dir))
        # a survey being created (by another run, or one killed) has only these;
        # the manifest too, since another run may write it between the check
        # above and this listing (a report without a manifest is damage)
        ours = re.compile(
            rf"{re.escape(LOCK)}|bodies|orbits|manifest\.json|\.manifest\.json\..*\.part"
        )
        if any(not ours.fullmatch(p.name) for p in self.out_dir.iterdir()):
            raise InputError(f"{self.out_dir} exists and is not a survey directory")

    def prepare(self):
        """Create the directory and manifest, or check an existing one.

        Call under :meth:`lock` (``run`` does).

        Raises
        ------
        InputError
            The directory holds a survey with other parameters (they never
            mix: use a new directory), or cannot be written.
        """
        self._refuse_foreign_directory()
        manifest = self.out_dir / MANIFEST
        existing = load_manifest(self.out_dir) if manifest.exists() else None
        if existing is not None:
            self._compare(existing)
        # a deleted table folder is made again (its chunks are recomputed)
        try:
            self.out_dir.mkdir(parents=True, exist_ok=True)
            for sub in TABLES:
                refuse_link(self.out_dir / sub)
                (self.out_dir / sub).mkdir(exist_ok=True)
        except OSError as error:
            raise InputError(f"cannot create {self.out_dir}: {error.strerror}") from None
        if existing is not None:
            self._ledger = existing["parts"]
        else:
            self._ledger = {}
            self._write_manifest()

    def _write_manifest(self):
        document = {
            "orbits_survey": SURVEY_FORMAT,
            "parameters": self.parameters,
            "source": self.source,
            "skipped_rows": self.skipped,
            "parts": self._ledger,
        }
        document["sha256"] = manifest_checksum(document)
        write_text_atomic(
            self.out_dir / MANIFEST, json.dumps(document, indent=1) + "\n", follow_links=False
        )

    def lock(self):
        """The directory's exclusive lock (a context manager).

        Raises
        ------
        InputError
            Another run holds it.
        """
        return _DirectoryLock(self.out_dir)

    def clean_partial(self):
        """Remove temporary files of killed runs (never parts, never a live run's)."""
        from .atomic import remove_stale_temporaries

        for table in TABLES:
            remove_stale_temporaries(self.out_dir / table, r"part-\d+\.\w+", regex=True)
        remove_stale_temporaries(self.out_dir, MANIFEST)
        remove_stale_temporaries(self.out_dir, REPORT)

    def verify(self):
        """Check every ledger entry against its files; drop the bad ones.

        Returns
        -------
        damaged : list of str
            Parts whose files were missing or did not match the ledger
            (they are removed from the ledger and will be recomputed).
        """
        damaged = []
        for key in sorted(self._ledger, key=int):
            problem = _check_part(self.out_dir, key, self._ledger[key], self.parameters)
            if problem:
                damaged.append(f"chunk {int(key)}: {problem}")
                del self._ledger[key]
        return damaged

    def missing(self):
        """Indices of the chunks not (verifiably) written."""
        ledger = getattr(self, "_ledger", None)
        if ledger is None:
            ledger = (
                load_manifest(self.out_dir)["parts"] if (self.out_dir / MANIFEST).exists() else {}
            )
        return [k for k in range(self.chunks) if str(k) not in ledger]

    def chunk_moments(self, index):
        return self.moments[index * self.chunk : (index + 1) * self.chunk]

    def write_chunk(self, index, bodies, orbits):
        """Write one chunk (orbits, then bodies), then its ledger entry."""
        if self.names is not None:
            bodies.insert(
                1, "name", self.names[index * self.chunk : index * self.chunk + len(bodies)]
            )
        entry = {
            "first_body": int(index * self.chunk),
            "last_body": int(index * self.chunk + len(bodies) - 1),
        }
        for table, frame in (("orbits", orbits), ("bodies", bodies)):
            path = self._part(table, index)
            _write_table(frame, path, self.format, follow_links=False)
            entry[table] = {
                "file": f"{table}/{path.name}",
                "rows": int(len(frame)),
                "sha256": _sha256(path),
            }
        self._ledger[str(index)] = entry
        self._write_manifest()

    def run(self, scheduler=None, progress=None, notify=None, status=None):
        """Compute and write every missing chunk; then the report.

        Parameters
        ----------
        scheduler : str or distributed.Client, optional
            ``"tcp://host:port"`` of a running ``dask scheduler`` (or a
            Client): chunks run on its workers.  Default: in-process.
        progress : callable, optional
            Called with the number of bodies of each finished chunk.
        notify : callable, optional
            Called with one-line messages (e.g. how many damaged parts are
            recomputed).
        status : callable, optional
            Called with transient one-line messages (waiting for the
            scheduler), for a terminal.

        Returns
        -------
        dict
            The report (also written to ``report.json``), built from the
            verified parts only.

        Raises
        ------
        InputError
            Another run holds the directory, it holds another survey, or
            the scheduler is unusable.
        """
        if scheduler is not None:
            _check_scheduler(scheduler)
        # refusals first, touching nothing: a foreign directory, another
        # survey's parameters, then an unusable scheduler
        self._refuse_foreign_directory()
        self._refuse_other_parameters()
        client = None
        if scheduler is not None:
            client = self._connect(scheduler, status)
        try:
            return self._run_locked(client, progress, notify)
        finally:
            if client is not None and client is not scheduler:
                client.close()

    def _refuse_other_parameters(self):
        if (self.out_dir / MANIFEST).exists():
            self._compare(load_manifest(self.out_dir))

    def _compare(self, existing):
        if existing["orbits_survey"] != SURVEY_FORMAT:
            raise InputError(
                f"{self.out_dir} holds a survey of an older orbits format "
                f"({existing['orbits_survey']}); it can be read but not resumed: "
                "use a new directory"
            )
        if existing["parameters"] != self.parameters:
            old, new = existing["parameters"], self.parameters
            changed = sorted(k for k in set(old) | set(new) if old.get(k) != new.get(k))
            raise InputError(
                f"{self.out_dir} holds a survey with different parameters "
                f"({', '.join(changed)}); use a new directory"
            )

    def _run_locked(self, client, progress, notify):
        try:
            self.out_dir.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise InputError(f"cannot create {self.out_dir}: {error.strerror}") from None
        with self.lock():
            self.prepare()
            self.clean_partial()
            damaged = self.verify()
            if damaged:
                self._write_manifest()
                if notify is not None:
                    notify(
                        f"{len(damaged)} part(s) missing or damaged, recomputing: "
                        + "; ".join(damaged[:3])
                        + (" ..." if len(damaged) > 3 else "")
                    )
            todo = self.missing()
            self.last_todo = todo
            if client is None:
                self._run_local(todo, progress)
            else:
                self._run_distributed(client, todo, progress)
            # every ledger entry was verified or written (and hashed) under
            # this lock: no need to hash all parts again
            return self._report(verified=True)

    def _run_local(self, todo, progress):
        """Compute the chunks in order; write each while the next is computed.

        One writer thread takes the finished chunks in order (files, SHA-256,
        fsync and the ledger release the GIL), so the ledger grows exactly
        as in a serial run.  At most one chunk waits to be written; on an
        error or an interrupt it is still written (it is computed) before
        the lock is released: a chunk is in the ledger with both its parts,
        or not at all.
        """
        from concurrent.futures import ThreadPoolExecutor

        writer = ThreadPoolExecutor(max_workers=1, thread_name_prefix="orbits-writer")
        previous = None  # the chunk being written
        try:
            for index in todo:
                bodies, orbits = compute_chunk(
                    self.chunk_moments(index), self.n_max, self.q_max, index * self.chunk
                )
                self._wait_for(previous, progress)  # on disk before the next is queued
                previous = writer.submit(self._write_and_count, index, bodies, orbits)
            self._wait_for(previous, progress)
        finally:
            # at most one chunk is queued: it is computed, so finish it
            writer.shutdown(wait=True)

    def _write_and_count(self, index, bodies, orbits):
        self.write_chunk(index, bodies, orbits)
        return len(bodies)

    @staticmethod
    def _wait_for(future, progress):
        """Wait for a queued write (re-raising its error); report its bodies."""
        if future is None:
            return
        written = future.result()
        if progress is not None:
            progress(written)

    @staticmethod
    def _connect(scheduler, status=None):
        """A Client with at least one worker, within :data:`CONNECT_TIMEOUT` s each.

        Raises
        ------
        InputError
            No dask.distributed, no scheduler at the address, or no worker
            joined within the timeout (the message states it).
        """
        try:
            from distributed import Client
        except ImportError:
            raise InputError(
                "--scheduler needs dask.distributed: pip install 'orbits[distributed]'"
            ) from None
        if isinstance(scheduler, Client):
            client, own = scheduler, False
        else:
            if status is not None:
                status(
                    f"connecting to the dask scheduler at {scheduler} "
                    f"(timeout {CONNECT_TIMEOUT} s)..."
                )
            try:
                client, own = Client(scheduler, timeout=CONNECT_TIMEOUT), True
            except Exception as error:  # noqa: BLE001 - any failure to connect
                raise InputError(
                    f"cannot reach the dask scheduler at {scheduler} "
                    f"within {CONNECT_TIMEOUT} s: {_one_line(error)}"
                ) from None
        try:
            if status is not None and not client.scheduler_info().get("workers"):
                status(f"waiting up to {CONNECT_TIMEOUT} s for a dask worker...")
            client.wait_for_workers(1, timeout=CONNECT_TIMEOUT)
        except Exception:  # noqa: BLE001 - dask raises TimeoutError
            if own:
                client.close()
            raise InputError(
                f"the dask scheduler at {scheduler} has no workers "
                f"(waited {CONNECT_TIMEOUT} s); start one with "
                f"'dask worker ADDRESS'"
            ) from None
        return client

    def _run_distributed(self, client, todo, progress):
        from distributed import as_completed

        futures = {
            client.submit(
                compute_chunk,
                self.chunk_moments(index),
                self.n_max,
                self.q_max,
                index * self.chunk,
                pure=False,
            ): index
            for index in todo
        }
        for future in as_completed(futures):
            bodies, orbits = future.result()
            self.write_chunk(futures[future], bodies, orbits)
            if progress is not None:
                progress(len(bodies))

    def report(self):
        """Summary of a complete survey from its verified parts; written to ``report.json``."""
        return self._report(verified=False)

    def _report(self, verified):
        if verified:
            if self.missing():
                raise InputError(f"{self.out_dir} is incomplete ({len(self.missing())} chunks)")
            bodies = read_table(self.out_dir, "bodies", verify=False)
        else:
            bodies = read_table(self.out_dir, "bodies")
        failed = bodies[~bodies["min_at_end"].astype(bool)]
        report = {
            "bodies": int(len(bodies)),
            "orbits": int(bodies["orbits"].sum()),
            "n_max": self.n_max,
            "q_max": self.q_max,
            "conjecture_minimum_at_the_ends": {
                "held_on_every_body": bool(failed.empty),
                "counterexamples": failed[
                    ["body", "I1", "I2", "I3", "min_total_phase", "min_theta"]
                ].to_dict("records"),
            },
            "bodies_with_a_two_pi_orbit": int((bodies["n_smallest"] == 1).sum()),
            "min_total_phase_range": [
                float(bodies["min_total_phase"].min()),
                float(bodies["min_total_phase"].max()),
            ],
            "bodies_with_unresolved_orbits": int((bodies["unresolved"] > 0).sum()),
            "skipped_rows": len(self.skipped),
        }
        write_text_atomic(
            self.out_dir / REPORT, json.dumps(report, indent=2) + "\n", follow_links=False
        )
        return report


class _DirectoryLock:
    """An exclusive ``fcntl.flock`` on ``DIR/.lock``, released on exit (or death)."""

    def __init__(self, directory):
        self.path = Path(directory) / LOCK

    def __enter__(self):
        import errno
        import fcntl
        import os
        import stat

        try:
            # never through a link planted as .lock (it would lock, and
            # write the pid into, a file outside the directory)
            descriptor = os.open(
                self.path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o666
            )
        except OSError as error:
            if error.errno == errno.ELOOP:
                refuse_link(self.path)
            raise InputError(f"cannot lock {self.path.parent}: {error.strerror}") from None
        self.handle = os.fdopen(descriptor, "r+")
        if not stat.S_ISREG(os.fstat(descriptor).st_mode):
            self.handle.close()
            raise InputError(f"cannot lock {self.path.parent}: {self.path} is not a regular file")
        try:
            fcntl.flock(self.handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            self.handle.seek(0)
            owner = self.handle.read().strip() or "unknown"
            self.handle.close()
            raise InputError(
                f"{self.path.parent} is being written by another orbits run "
                f"(pid {owner}); wait for it to finish or use another "
                "directory"
            ) from None
        self.handle.seek(0)
        self.handle.truncate()
        self.handle.write(f"{os.getpid()}\n")
        self.handle.flush()
        return self

    def __exit__(self, *exc):
        self.handle.close()  # closing releases the lock
        return False


def _one_line(error):
    return " ".join(str(error).split()) or type(error).__name__


def _check_scheduler(scheduler):
    """Refuse an address that cannot be a dask scheduler before connecting."""
    import re

    if not isinstance(scheduler, str):
        return
    match = re.fullmatch(
        r"(?:(?:tcp|tls|ucx|inproc|ws|wss)://)?[\w.\-\[\]:]+:(\d{1,5})", scheduler
    )
    if not match or not 0 < int(match.group(1)) < 65536:
        raise InputError(
            f"--scheduler {scheduler!r} is not a dask scheduler address "
            "(expected tcp://HOST:PORT, port 1-65535)"
        )


def _sha256(path):
    """SHA-256 of a regular file, never through a symbolic link."""
    import errno
    import os

    digest = hashlib.sha256()
    try:
        descriptor = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_CLOEXEC | os.O_NONBLOCK)
    except OSError as error:
        if error.errno == errno.ELOOP:
            refuse_link(path)
        raise
    with os.fdopen(descriptor, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def manifest_checksum(document):
    """SHA-256 of a manifest's canonical JSON (every key but ``sha256``).

    Canonical: keys sorted, no spaces, ASCII only, so that the same document
    always hashes the same however it was indented.
    """
    body = {key: value for key, value in document.items() if key != "sha256"}
    text = json.dumps(body, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


def chunk_bounds(parameters, index):
    """``(first, last)`` body ids of chunk ``index`` of a survey's parameters."""
    first = index * parameters["chunk"]
    return first, min(first + parameters["chunk"], parameters["body_count"]) - 1


def part_name(table, index, fmt):
    """The ledger's file name of a chunk's part, e.g. ``bodies/part-00003.csv``."""
    return f"{table}/part-{index:05d}.{fmt}"


def _entry_problem(key, entry, parameters):
    """What binds an entry to its chunk and the parameters, broken ('' if not)."""
    chunks = -(-parameters["body_count"] // parameters["chunk"])
    if not (isinstance(key, str) and key.isdigit() and key == str(int(key))):
        return "malformed ledger key"
    index = int(key)
    if index >= chunks:
        return f"not a chunk of this survey (it has {chunks})"
    first, last = chunk_bounds(parameters, index)
    if entry.get("first_body") != first or entry.get("last_body") != last:
        return f"body ids {entry.get('first_body')}..{entry.get('last_body')} are not the chunk's"
    for table in TABLES:
        item = entry[table]
        name = part_name(table, index, parameters["format"])
        # only the chunk's own part: a ledger never points at another chunk
        # or outside DIR/TABLE/
        if item["file"] != name:
            return f"ledger names {item['file']!r}, not the chunk's {name}"
        rows = item["rows"]
        if not isinstance(rows, int) or isinstance(rows, bool) or rows < 0:
            return f"{name}: bad row count {rows!r}"
        if table == "bodies" and rows != last - first + 1:
            return f"{name}: {rows} rows for {last - first + 1} bodies"
        if not isinstance(item["sha256"], str):
            return f"{name}: bad SHA-256"
    return ""


def _check_part(out_dir, key, entry, parameters):
    """The first problem of a ledger entry or its files, or '' if they match."""
    import os
    import stat

    try:
        problem = _entry_problem(key, entry, parameters)
        if problem:
            return problem
        for table in TABLES:
            item = entry[table]
            path = Path(out_dir) / item["file"]
            try:
                mode = os.lstat(path).st_mode
            except FileNotFoundError:
                return f"{item['file']} is missing"
            if stat.S_ISLNK(mode):
                return f"{item['file']} is a symbolic link (never followed)"
            if not stat.S_ISREG(mode):
                return f"{item['file']} is not a regular file"
            if _sha256(path) != item["sha256"]:
                return f"{item['file']} does not match its SHA-256 (changed or truncated)"
    except (KeyError, TypeError, AttributeError):
        return "malformed ledger entry"
    except InputError as error:
        return str(error)
    except OSError as error:
        return f"cannot read it: {error.strerror}"
    return ""


_NO_MANIFEST = (
    "{directory} holds survey parts but no manifest.json (deleted?); without "
    "its ledger they cannot be verified: rerun the survey into a new directory"
)


def _has_parts(out_dir):
    """Whether a directory without a manifest holds a survey's files."""
    import re

    if (Path(out_dir) / REPORT).exists():
        return True
    part = re.compile(r"part-\d{5,}\.(?:csv|parquet)")
    for table in TABLES:
        folder = Path(out_dir) / table
        if folder.is_dir() and not folder.is_symlink():
            if any(part.fullmatch(p.name) for p in folder.iterdir()):
                return True
    return False


def refuse_links(out_dir):
    """Refuse a survey directory with a symbolic link where orbits reads or writes.

    The manifest, lock, report, the table folders and every entry inside
    them: none is ever followed.

    Raises
    ------
    InputError
        One line naming the link.
    """
    import os

    out_dir = Path(out_dir)
    for name in (LOCK, MANIFEST, REPORT, *TABLES):
        refuse_link(out_dir / name)
    for table in TABLES:
        try:
            entries = list(os.scandir(out_dir / table))
        except OSError:
            continue
        for entry in entries:
            if entry.is_symlink():
                refuse_link(entry.path)


def load_manifest(out_dir):
    """The parsed ``manifest.json`` of a survey directory.

    Raises
    ------
    InputError
        No manifest, not JSON, or not a survey manifest of this version.
    """
    out_dir = path_argument("out_dir", out_dir)
    manifest = Path(out_dir) / MANIFEST
    if not Path(out_dir).is_dir():
        raise InputError(f"{out_dir} is not a directory")
    refuse_links(out_dir)
    try:
        document = json.loads(read_bytes_nofollow(manifest).decode("utf-8"))
    except FileNotFoundError:
        if _has_parts(out_dir):
            raise InputError(_NO_MANIFEST.format(directory=out_dir)) from None
        raise InputError(f"{out_dir} is not a survey directory (no {MANIFEST})") from None
    except (ValueError, UnicodeDecodeError):
        raise InputError(f"{manifest} is damaged (not valid JSON)") from None
    except OSError as error:
        raise InputError(f"cannot read {manifest}: {error.strerror}") from None
    version = document.get("orbits_survey") if isinstance(document, dict) else None
    if version not in READABLE_FORMATS or isinstance(version, bool):
        raise InputError(
            f"{manifest} is not a survey manifest of this orbits version "
            "(no ledger); rerun the survey into a new directory"
        )
    if version >= 3 and document.get("sha256") != manifest_checksum(document):
        raise InputError(
            f"{manifest} does not match its own SHA-256 (edited by hand or "
            "damaged): its ledger cannot be trusted; rerun the survey into a "
            "new directory"
        )
    parameters = document.get("parameters")
    parts = document.get("parts")
    required = ("bodies", "body_count", "n_max", "q_max", "format", "chunk")
    if (
        not isinstance(parameters, dict)
        or not isinstance(parts, dict)
        or any(key not in parameters for key in required)
        or parameters["format"] not in FORMATS
        or not all(
            isinstance(parameters[k], int) and parameters[k] >= 1
            for k in ("body_count", "n_max", "q_max", "chunk")
        )
    ):
        raise InputError(f"{manifest} is incomplete or damaged")
    if not all(str(key).isdigit() and isinstance(entry, dict) for key, entry in parts.items()):
        raise InputError(f"{manifest} has a damaged ledger")
    return document


def check_survey(out_dir):
    """Verify a survey directory without computing anything.

    Returns
    -------
    dict
        ``chunks`` (expected), ``verified`` (count), ``damaged`` and
        ``missing`` (lists of one-line descriptions), ``complete`` (bool).

    Raises
    ------
    InputError
        Not a survey directory, or its manifest is damaged.
    """
    document = load_manifest(out_dir)
    parameters, ledger = document["parameters"], document["parts"]
    chunks = -(-parameters["body_count"] // parameters["chunk"])
    damaged, verified = [], 0
    for key in sorted(ledger, key=lambda k: int(k) if str(k).isdigit() else -1):
        problem = _check_part(out_dir, key, ledger[key], parameters)
        if problem:
            damaged.append(f"chunk {key}: {problem}")
        else:
            verified += 1
    missing = [f"chunk {k}" for k in range(chunks) if str(k) not in ledger]
    return {
        "chunks": chunks,
        "verified": verified,
        "damaged": damaged,
        "missing": missing,
        "complete": not damaged and not missing,
    }


def _require_pyarrow():
    if not _have_pyarrow():
        raise InputError("--format parquet needs pyarrow: pip install 'orbits[parquet]'")


def _write_table(frame, path, fmt, engine=None, follow_links=True):
    """Write one table part atomically.

    CSV goes through pyarrow's writer when it is installed (ten times
    faster than pandas here, and like it writes the shortest decimal that
    reads back to the same double); otherwise through pandas.  Names are
    neutralised against spreadsheet formulas (:func:`orbits.cells.neutralize`).
    """
    if engine is None:
        engine = "arrow" if _have_pyarrow() else "pandas"
    if fmt == "csv" and "name" in frame.columns:
        frame = frame.assign(name=[neutralize(str(v)) for v in frame["name"]])
    with atomic_path(path, follow_links) as temporary:
        if fmt == "parquet":
            # dictionary pages only for text columns: on doubles they never
            # pay off and cost pyarrow ~4x the write time
            text = [name for name in frame.columns if frame[name].dtype.kind not in "biuf"]
            frame.to_parquet(temporary, index=False, use_dictionary=text)
        elif engine == "arrow":
            from pyarrow import Table
            from pyarrow.csv import write_csv

            write_csv(Table.from_pandas(frame, preserve_index=False), temporary)
        else:
            frame.to_csv(temporary, index=False, float_format=FLOAT_FORMAT)


def _have_pyarrow():
    from importlib.util import find_spec

    return find_spec("pyarrow") is not None


def _csv_dtypes():
    from .search import CATALOG_COLUMNS

    types = {name: np.float64 for name in BODY_COLUMNS + CATALOG_COLUMNS}
    types.update(
        {
            name: np.int64
            for name in ("body", "orbits", "n_smallest", "n_largest", "unresolved", "n", "q")
        }
    )
    types.update(name=str, branch=str, closes_after=str, min_at_end=object)
    return types


_CSV_DTYPES = _csv_dtypes()


def _read_part(path):
    import io

    from .atomic import csv_float_options

    data = io.BytesIO(read_bytes_nofollow(path))  # never through a link
    if path.suffix == ".parquet":
        return pd.read_parquet(data)
    # Types by schema, not by inference: a part whose float column holds only
    # "-0" or "0" would otherwise come back as integers (losing the sign).
    frame = pd.read_csv(data, dtype=_CSV_DTYPES, keep_default_na=False, **csv_float_options())
    if "name" in frame.columns:
        frame["name"] = frame["name"].map(unneutralize).astype(frame["name"].dtype)
    if "min_at_end" in frame.columns and frame["min_at_end"].dtype == object:
        frame["min_at_end"] = frame["min_at_end"].map(
            {"true": True, "false": False, "True": True, "False": False}
        )
    return frame


def read_table(out_dir, table, verify=True):
    """One table of a survey directory (``"bodies"`` or ``"orbits"``), all parts.

    Only the parts in the manifest's ledger are read, in order; other files
    in the directory are ignored.

    Raises
    ------
    InputError
        Not a survey directory, incomplete, or (with ``verify``) a part that
        is missing or does not match its SHA-256.
    """
    if table not in ("bodies", "orbits"):
        raise InputError(f"table must be 'bodies' or 'orbits', got {table!r}")
    document = load_manifest(out_dir)
    status = check_survey(out_dir) if verify else None
    if status is not None and not status["complete"]:
        problems = status["damaged"] + [f"{m} missing" for m in status["missing"]]
        raise InputError(
            f"{out_dir} is damaged or incomplete ({len(problems)} "
            f"problem(s), first: {problems[0]}); rerun the survey command "
            "to recompute, or check it with 'orbits survey --check'"
        )
    ledger, parameters = document["parts"], document["parameters"]
    frames = []
    for key in sorted(ledger, key=int):
        problem = _entry_problem(key, ledger[key], parameters)
        if problem:
            raise InputError(f"{out_dir}: chunk {key}: {problem}")
        try:
            frame = _read_part(Path(out_dir) / ledger[key][table]["file"])
            problem = _rows_problem(frame, table, ledger[key], parameters)
            if problem:
                raise InputError(f"{out_dir}: chunk {key} of {table}: {problem}")
            frames.append(frame)
        except InputError:
            raise
        except (OSError, ValueError, KeyError) as error:
            raise InputError(
                f"{out_dir}: cannot read chunk {key} of {table}: {_one_line(error)}"
            ) from None
        except Exception as error:  # noqa: BLE001 - pyarrow's own errors
            raise InputError(
                f"{out_dir}: chunk {key} of {table} is damaged: {_one_line(error)}"
            ) from None
    if not frames:
        raise InputError(f"no {table} table in {out_dir}")
    return pd.concat(frames, ignore_index=True)


def _rows_problem(frame, table, entry, parameters):
    """A part's rows against its ledger entry: count and body ids ('' if they agree)."""
    if len(frame) != entry[table]["rows"]:
        return f"{len(frame)} rows, the ledger says {entry[table]['rows']}"
    if "body" not in frame.columns:
        return "no body column"
    body = frame["body"].to_numpy()
    first, last = entry["first_body"], entry["last_body"]
    if table == "bodies":
        if not np.array_equal(body, np.arange(first, last + 1)):
            return f"its body ids are not the chunk's {first}..{last}"
    elif len(body) and (body.min() < first or body.max() > last or (np.diff(body) < 0).any()):
        return f"its orbits are not of the chunk's bodies {first}..{last}"
    return ""


def read_survey(out_dir, verify=True):
    """``(bodies, orbits)`` DataFrames of a complete, verified survey directory.

    Raises
    ------
    InputError
        Not a survey directory, incomplete, or damaged (a part missing,
        changed or truncated: each is checked against the ledger's SHA-256).
    """
    bodies = read_table(out_dir, "bodies", verify)
    table = read_table(out_dir, "orbits", verify)
    if len(table) != int(bodies["orbits"].sum()):
        raise InputError(
            f"{out_dir}: {len(table)} orbit rows, but the bodies table counts "
            f"{int(bodies['orbits'].sum())}; rerun the survey into a new directory"
        )
    return bodies, table


def survey_grid(out_dir):
    """The Fig. 2 data (i1, i2, minimum) of a grid survey.

    Raises
    ------
    InputError
        Not a survey directory, damaged, not complete, or not a grid survey.
    """
    parameters = load_manifest(out_dir)["parameters"]
    grid = parameters["bodies"]
    resolution = grid.get("grid") if isinstance(grid, dict) else None
    if not isinstance(resolution, int) or resolution < 2:
        raise InputError(f"{out_dir} surveys a list of bodies; Fig. 2 needs a grid survey")
    bodies = read_table(out_dir, "bodies")
    if len(bodies) != parameters["body_count"]:
        raise InputError(f"{out_dir}: the survey is not complete")
    from .bodies import REGION_BOX

    (lo1, hi1), (lo2, hi2) = REGION_BOX
    # grid cells are centred: i = lo + (k + 1/2) (hi - lo) / N
    k1 = np.rint((bodies["I1"].to_numpy() - lo1) / (hi1 - lo1) * resolution - 0.5).astype(int)
    k2 = np.rint((bodies["I2"].to_numpy() - lo2) / (hi2 - lo2) * resolution - 0.5).astype(int)
    if k1.min() < 0 or k2.min() < 0 or k1.max() >= resolution or k2.max() >= resolution:
        raise InputError(f"{out_dir}: bodies outside the grid of the manifest")
    axis1 = lo1 + (np.arange(resolution) + 0.5) * (hi1 - lo1) / resolution
    axis2 = lo2 + (np.arange(resolution) + 0.5) * (hi2 - lo2) / resolution
    i1, i2 = np.meshgrid(axis1, axis2, indexing="xy")
    minimum = np.full(i1.shape, np.nan)
    minimum[k2, k1] = bodies["min_total_phase"].to_numpy()
    return i1, i2, minimum
