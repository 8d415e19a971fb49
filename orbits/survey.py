"""Body-space survey: closed orbits and minimum phases over many bodies.

A survey covers the region of physical asymmetric bodies in the paper's
I1-I2 plane (``|I| = 1``), or an explicit list, and writes a directory::

    DIR/manifest.json          parameters; a rerun must match them
    DIR/bodies/part-NNNNN.parquet  one row per body (or .csv)
    DIR/orbits/part-NNNNN.parquet  the closed orbits, catalog schema
    DIR/report.json            summary and the minimum-at-the-ends test

The bodies are cut into chunks; each finished chunk is written atomically
(orbits first, bodies last, so a chunk is done exactly when its bodies part
exists).  A killed survey run again computes only the missing chunks.

Chunks run in-process on all cores (numba), or on a ``dask.distributed``
cluster (``scheduler="tcp://host:port"`` or a ``Client``): the same
function computes each chunk there and the results come back to be written
here, so both engines write identical files.
"""

import hashlib
import json
from pathlib import Path

import numpy as np
import pandas as pd

from ._version import __version__
from .atomic import FLOAT_FORMAT, atomic_path, write_text_atomic
from .bodies import as_moments, region_grid
from .core import search as _kernels
from .errors import InputError
from .phases import phase_limits
from .search import catalog_rows, phase_levels

FORMATS = ("csv", "parquet")
DEFAULT_CHUNK = 20_000
# seconds to wait for a dask scheduler before giving up
CONNECT_TIMEOUT = 10
BODY_COLUMNS = ("body", "I1", "I2", "I3", "theta_crit", "limit_theta_zero",
                "limit_theta_half_pi", "min_total_phase", "min_dtheta", "min_theta",
                "min_at_end", "orbits", "n_smallest", "n_largest", "unresolved")
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
    moments = np.ascontiguousarray(as_moments(moments), dtype=float)
    count = moments.shape[0]
    p, q, levels = phase_levels(n_max, q_max)
    capacity = 2 * levels.size + 8
    info = np.empty((count, _kernels.INFO_SIZE))
    branch = np.empty((count, capacity), dtype=np.int8)
    level = np.empty((count, capacity), dtype=np.int64)
    offset = np.empty((count, capacity))
    found = np.empty(count, dtype=np.int64)
    _kernels.search_many(moments, levels, branch, level, offset, found, info)
    rows_body, rows_level, rows_offset = _flatten(moments, levels, level, offset,
                                                  found, info)
    ids = first_id + np.arange(count)
    orbits = catalog_rows(ids[rows_body], moments[rows_body], rows_level, rows_offset,
                          p, q, levels)
    bodies = _body_rows(moments, ids, info, orbits, rows_body)
    return bodies, orbits


def _flatten(moments, levels, level, offset, found, info):
    """Per-body root arrays to flat rows, sorted by body then dtheta.

    A body whose roots overflowed its row (``found < 0``: a phase with
    many monotone pieces) is searched again with room to spare.
    """
    mask = np.arange(level.shape[1])[None, :] < np.maximum(found, 0)[:, None]
    body, rows_level, rows_offset = np.nonzero(mask)[0], level[mask], offset[mask]
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
    minimum = np.where(use_sam, sam_min, lam_min)
    where = np.where(use_sam, info[:, _kernels.INFO_MIN_AT_SAM],
                     info[:, _kernels.INFO_MIN_AT_LAM])
    end_value = np.minimum(limits.theta_zero, limits.theta_half_pi)
    at_end = ((np.abs(np.abs(where) - np.where(use_sam, theta_c,
                                               info[:, _kernels.INFO_WIDTH_LAM]))
               <= 1e-9 * np.pi)
              & (minimum >= end_value * (1.0 - _END_TOLERANCE)))
    integer = orbits["q"].to_numpy() == 1 if len(orbits) else np.zeros(0, bool)
    counts = np.bincount(body_of_row, minlength=len(ids))
    n_small = np.full(len(ids), -1, dtype=np.int64)
    n_large = np.full(len(ids), -1, dtype=np.int64)
    if integer.any():
        frame = pd.DataFrame({"b": body_of_row[integer], "n": orbits["n"].to_numpy()[integer]})
        grouped = frame.groupby("b")["n"]
        n_small[grouped.min().index] = grouped.min().to_numpy()
        n_large[grouped.max().index] = grouped.max().to_numpy()
    return pd.DataFrame({
        "body": ids,
        "I1": moments[:, 0] / norm, "I2": moments[:, 1] / norm, "I3": moments[:, 2] / norm,
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
        "unresolved": (info[:, _kernels.INFO_UNREACHED_SAM]
                       + info[:, _kernels.INFO_UNREACHED_LAM]).astype(np.int64),
    }, columns=list(BODY_COLUMNS))


# --------------------------------------------------------------- the survey
class Survey:
    """A survey's parameters, bodies and output directory.

    Build with :meth:`grid` (``N x N`` over the region's bounding box) or
    :meth:`from_bodies`; :meth:`run` computes the missing chunks.
    """

    def __init__(self, out_dir, moments, source, n_max, q_max=1, fmt="parquet",
                 chunk=DEFAULT_CHUNK):
        if fmt not in FORMATS:
            raise InputError(f"format must be one of {', '.join(FORMATS)}, got {fmt!r}")
        if fmt == "parquet":
            _require_pyarrow()
        for name, value in (("n_max", n_max), ("q_max", q_max), ("chunk", chunk)):
            if isinstance(value, bool) or int(value) != value or value < 1:
                raise InputError(f"{name} must be an integer >= 1, got {value!r}")
        self.out_dir = Path(out_dir)
        self.moments = np.ascontiguousarray(as_moments(moments), dtype=float).reshape(-1, 3)
        if self.moments.shape[0] == 0:
            raise InputError("a survey needs at least one body")
        self.n_max, self.q_max, self.format, self.chunk = int(n_max), int(q_max), fmt, int(chunk)
        digest = hashlib.sha256(self.moments.tobytes()).hexdigest()
        self.parameters = {
            "orbits_version": __version__, "bodies": source, "body_count":
            int(self.moments.shape[0]), "bodies_sha256": digest, "n_max": self.n_max,
            "q_max": self.q_max, "format": fmt, "chunk": self.chunk,
        }

    @classmethod
    def grid(cls, out_dir, resolution, n_max, **kwargs):
        """Bodies on an ``N x N`` grid over the region's bounding box."""
        if isinstance(resolution, bool) or int(resolution) != resolution or resolution < 2:
            raise InputError(f"resolution must be an integer >= 2, got {resolution!r}")
        moments = region_grid(int(resolution))
        return cls(out_dir, moments, {"grid": int(resolution)}, n_max, **kwargs)

    @classmethod
    def from_bodies(cls, out_dir, bodies, n_max, source="list", **kwargs):
        """An explicit list of bodies (Body objects or moments)."""
        moments = np.array([getattr(b, "moments", b) for b in bodies], dtype=float)
        return cls(out_dir, moments, {"file": str(source)}, n_max, **kwargs)

    @property
    def chunks(self):
        return -(-self.moments.shape[0] // self.chunk)

    def _part(self, table, index):
        return self.out_dir / table / f"part-{index:05d}.{self.format}"

    def prepare(self):
        """Create the directory and manifest, or check an existing one.

        Raises
        ------
        InputError
            The directory holds a survey with other parameters (they never
            mix: use a new directory), or cannot be written.
        """
        manifest = self.out_dir / "manifest.json"
        if manifest.exists():
            try:
                existing = json.loads(manifest.read_text())
            except ValueError:
                raise InputError(f"{manifest} is not a survey manifest") from None
            if existing != self.parameters:
                changed = sorted(k for k in set(existing) | set(self.parameters)
                                 if existing.get(k) != self.parameters.get(k))
                raise InputError(
                    f"{self.out_dir} holds a survey with different parameters "
                    f"({', '.join(changed)}); use a new directory")
        else:
            if self.out_dir.exists() and any(self.out_dir.iterdir()):
                raise InputError(f"{self.out_dir} exists and is not a survey directory")
            try:
                for sub in ("bodies", "orbits"):
                    (self.out_dir / sub).mkdir(parents=True, exist_ok=True)
            except OSError as error:
                raise InputError(f"cannot create {self.out_dir}: {error.strerror}") from None
            write_text_atomic(manifest, json.dumps(self.parameters, indent=2) + "\n")

    def clean_partial(self):
        """Remove temporary files a killed run left behind (never complete parts)."""
        for table in ("bodies", "orbits"):
            for leftover in (self.out_dir / table).glob(".part-*.part"):
                leftover.unlink(missing_ok=True)

    def missing(self):
        """Indices of the chunks not yet written."""
        return [k for k in range(self.chunks) if not self._part("bodies", k).exists()]

    def chunk_moments(self, index):
        return self.moments[index * self.chunk:(index + 1) * self.chunk]

    def write_chunk(self, index, bodies, orbits):
        """Write one chunk: orbits first, bodies last (the 'done' mark)."""
        _write_table(orbits, self._part("orbits", index), self.format)
        _write_table(bodies, self._part("bodies", index), self.format)

    def run(self, scheduler=None, progress=None):
        """Compute and write every missing chunk; then the report.

        Parameters
        ----------
        scheduler : str or distributed.Client, optional
            ``"tcp://host:port"`` of a running ``dask scheduler`` (or a
            Client): chunks run on its workers.  Default: in-process.
        progress : callable, optional
            Called with the number of bodies of each finished chunk.

        Returns
        -------
        dict
            The report (also written to ``report.json``).
        """
        self.prepare()
        self.clean_partial()
        todo = self.missing()
        if scheduler is None:
            for index in todo:
                bodies, orbits = compute_chunk(self.chunk_moments(index), self.n_max,
                                               self.q_max, index * self.chunk)
                self.write_chunk(index, bodies, orbits)
                if progress is not None:
                    progress(len(bodies))
        else:
            self._run_distributed(scheduler, todo, progress)
        return self.report()

    def _run_distributed(self, scheduler, todo, progress):
        try:
            from distributed import Client, as_completed
        except ImportError:
            raise InputError("--scheduler needs dask.distributed: "
                             "pip install 'orbits[distributed]'") from None
        own = not isinstance(scheduler, Client)
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT) if own else scheduler
        except (OSError, TimeoutError) as error:
            raise InputError(f"cannot reach the dask scheduler at {scheduler}: "
                             f"{error}") from None
        try:
            futures = {client.submit(compute_chunk, self.chunk_moments(index), self.n_max,
                                     self.q_max, index * self.chunk, pure=False): index
                       for index in todo}
            for future in as_completed(futures):
                bodies, orbits = future.result()
                self.write_chunk(futures[future], bodies, orbits)
                if progress is not None:
                    progress(len(bodies))
        finally:
            if own:
                client.close()

    def report(self):
        """Summary of a complete survey; written to ``report.json``."""
        if self.missing():
            raise InputError(f"{self.out_dir}: the survey is not complete")
        bodies = read_table(self.out_dir, "bodies")
        failed = bodies[~bodies["min_at_end"]]
        report = {
            "bodies": int(len(bodies)),
            "orbits": int(bodies["orbits"].sum()),
            "n_max": self.n_max, "q_max": self.q_max,
            "conjecture_minimum_at_the_ends": {
                "held_on_every_body": bool(failed.empty),
                "counterexamples": failed[["body", "I1", "I2", "I3", "min_total_phase",
                                           "min_theta"]].to_dict("records"),
            },
            "bodies_with_a_two_pi_orbit": int((bodies["n_smallest"] == 1).sum()),
            "min_total_phase_range": [float(bodies["min_total_phase"].min()),
                                      float(bodies["min_total_phase"].max())],
            "bodies_with_unresolved_orbits": int((bodies["unresolved"] > 0).sum()),
        }
        write_text_atomic(self.out_dir / "report.json", json.dumps(report, indent=2) + "\n")
        return report


def _require_pyarrow():
    if not _have_pyarrow():
        raise InputError("--format parquet needs pyarrow: "
                         "pip install 'orbits[parquet]'")


def _write_table(frame, path, fmt, engine=None):
    """Write one table part atomically.

    CSV goes through pyarrow's writer when it is installed (ten times
    faster than pandas here, and like it writes the shortest decimal that
    reads back to the same double); otherwise through pandas.
    """
    if engine is None:
        engine = "arrow" if _have_pyarrow() else "pandas"
    with atomic_path(path) as temporary:
        if fmt == "parquet":
            frame.to_parquet(temporary, index=False)
        elif engine == "arrow":
            from pyarrow import Table
            from pyarrow.csv import write_csv
            write_csv(Table.from_pandas(frame, preserve_index=False), temporary)
        else:
            frame.to_csv(temporary, index=False, float_format=FLOAT_FORMAT)


def _have_pyarrow():
    from importlib.util import find_spec
    return find_spec("pyarrow") is not None


def read_table(out_dir, table):
    """One table of a survey directory (``"bodies"`` or ``"orbits"``), all parts."""
    directory = Path(out_dir) / table
    parts = sorted(directory.glob("part-*.*"))
    if not parts:
        raise InputError(f"no {table} table in {out_dir}")
    reader = pd.read_parquet if parts[0].suffix == ".parquet" else pd.read_csv
    return pd.concat([reader(part) for part in parts], ignore_index=True)


def read_survey(out_dir):
    """``(bodies, orbits)`` DataFrames of a survey directory."""
    return read_table(out_dir, "bodies"), read_table(out_dir, "orbits")


def survey_grid(out_dir):
    """The Fig. 2 data (i1, i2, minimum) of a grid survey.

    Raises
    ------
    InputError
        Not a survey directory, not complete, or not a grid survey.
    """
    manifest = Path(out_dir) / "manifest.json"
    if not manifest.exists():
        raise InputError(f"{out_dir} is not a survey directory (no manifest.json)")
    parameters = json.loads(manifest.read_text())
    resolution = parameters["bodies"].get("grid")
    if resolution is None:
        raise InputError(f"{out_dir} surveys a list of bodies; Fig. 2 needs a grid survey")
    bodies = read_table(out_dir, "bodies")
    if len(bodies) != parameters["body_count"]:
        raise InputError(f"{out_dir}: the survey is not complete")
    from .bodies import REGION_BOX
    (lo1, hi1), (lo2, hi2) = REGION_BOX
    # grid cells are centred: i = lo + (k + 1/2) (hi - lo) / N
    k1 = np.rint((bodies["I1"].to_numpy() - lo1) / (hi1 - lo1) * resolution - 0.5).astype(int)
    k2 = np.rint((bodies["I2"].to_numpy() - lo2) / (hi2 - lo2) * resolution - 0.5).astype(int)
    axis1 = lo1 + (np.arange(resolution) + 0.5) * (hi1 - lo1) / resolution
    axis2 = lo2 + (np.arange(resolution) + 0.5) * (hi2 - lo2) / resolution
    i1, i2 = np.meshgrid(axis1, axis2, indexing="xy")
    minimum = np.full(i1.shape, np.nan)
    minimum[k2, k1] = bodies["min_total_phase"].to_numpy()
    return i1, i2, minimum
