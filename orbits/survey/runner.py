"""The survey: its parameters and bodies, and the run that fills its directory.

:class:`Survey` computes the missing chunks (:mod:`orbits.survey.compute`)
in-process or on a ``dask.distributed`` cluster, writes each chunk's parts
(:mod:`orbits.survey.tables`) and records it in the ledger
(:mod:`orbits.survey.ledger`), then writes the report
(:mod:`orbits.survey.report`).
"""

import hashlib
import json
import threading
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from .._args import integer, listlike, path_argument, real_array, utf8_text
from .._version import __version__, source_fingerprint
from ..atomic import make_directories, refuse_link, remove_directories
from ..bodies import as_moments, region_grid
from ..device import check_device, cuda_kernels
from ..errors import ArgumentTypeError, InputError, OrbitsError
from ..limits import check_resolution
from ..startup import release_collector
from . import compute
from .compute import LAYOUTS, check_survey_bounds
from .ledger import FORMATS, Ledger, one_line, part_name
from .report import bodies_summary, survey_report
from .tables import require_pyarrow, write_part

DEFAULT_CHUNK = 20_000
# seconds to wait for a dask scheduler before giving up
CONNECT_TIMEOUT = 10


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
        columns="compact",
        device="cpu",
    ):
        # the search's device: results agree between devices (the last bits
        # of dtheta may differ on a GPU), so it is no parameter of the survey
        self.device = check_device(device)
        if self.device == "cuda":
            cuda_kernels()  # DeviceError now, before anything is written
        if fmt not in FORMATS:
            raise InputError(f"format must be one of {', '.join(FORMATS)}, got {fmt!r}")
        if columns not in LAYOUTS:
            raise InputError(f"columns must be one of {', '.join(LAYOUTS)}, got {columns!r}")
        self.columns = columns
        if fmt == "parquet":
            require_pyarrow()
        n_max, q_max, chunk = (
            integer(name, value)
            for name, value in (("n_max", n_max), ("q_max", q_max), ("chunk", chunk))
        )
        self.out_dir = Path(path_argument("out_dir", out_dir))
        # the directory itself is never reached through a link either (a
        # link to another survey would resume, or overwrite, that one)
        refuse_link(self.out_dir)
        self.moments = np.ascontiguousarray(as_moments(moments), dtype=float).reshape(-1, 3)
        if self.moments.shape[0] == 0:
            raise InputError("a survey needs at least one body")
        self.n_max, self.q_max, self.format, self.chunk = int(n_max), int(q_max), fmt, int(chunk)
        check_survey_bounds(self.moments.shape[0], self.n_max, self.q_max, self.chunk)
        if names is not None:
            names = [utf8_text("name", str(name)) for name in names]
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
            # the layout: "compact" keeps per orbit only what cannot be
            # recomputed cheaply; read_survey derives the other columns
            "columns": columns,
        }
        if self.device == "cuda":
            # the search kernel compiled and run on the first body now: a
            # numba-cuda that cannot compile here is a DeviceError before
            # the directory is made, not after (the compile is needed anyway)
            compute.search_chunk(self.moments[:1], self.n_max, self.q_max, device="cuda")
        self.ledger = Ledger(self.out_dir, self.parameters, source, skipped)
        self._record_lock = threading.Lock()
        # bodies_summary of each chunk written by the current run
        self._summaries = {}

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
        in the bodies table, empty for items without one) unless ``names``
        is given.
        """
        if not listlike(bodies):
            raise ArgumentTypeError(
                f"bodies must be an iterable of Body objects or "
                f"moments, got {type(bodies).__name__}"
            )
        bodies = list(bodies)
        if not bodies:
            raise InputError("a survey needs at least one body")
        moments = real_array("bodies", [getattr(b, "moments", b) for b in bodies], InputError)
        # one named Body among unnamed items kept no name at all, silently
        given = [getattr(b, "name", None) for b in bodies]
        if "names" not in kwargs and any(name is not None and name != "" for name in given):
            kwargs["names"] = ["" if name is None else name for name in given]
        return cls(out_dir, moments, {"file": str(source)}, n_max, **kwargs)

    @property
    def chunks(self):
        return -(-self.moments.shape[0] // self.chunk)

    def prepare(self):
        """Create the directory and manifest, or check an existing one (see :class:`Ledger`)."""
        self.ledger.prepare()

    def lock(self):
        """The directory's exclusive lock (a context manager)."""
        return self.ledger.lock()

    def verify(self):
        """Check every ledger entry; drop and return the bad ones (see :class:`Ledger`)."""
        return self.ledger.verify()

    def missing(self):
        """Indices of the chunks not (verifiably) written."""
        return self.ledger.missing()

    def chunk_moments(self, index):
        return self.moments[index * self.chunk : (index + 1) * self.chunk]

    def write_chunk(self, index, bodies, orbits):
        """Write one chunk (orbits, then bodies), then its ledger entry.

        ``bodies`` and ``orbits`` as :func:`compute.chunk_columns` makes
        them (dicts of arrays), or DataFrames (:func:`compute.chunk_tables`).
        """
        count = len(bodies["body"])
        if self.names is not None:
            names = self.names[index * self.chunk : index * self.chunk + count]
            if isinstance(bodies, Mapping):
                bodies = {"body": bodies["body"], "name": names, **bodies}
            else:  # a DataFrame
                bodies = bodies.copy()
                bodies.insert(1, "name", names)
        entry = {
            "first_body": int(index * self.chunk),
            "last_body": int(index * self.chunk + count - 1),
        }
        for table, frame in (("orbits", orbits), ("bodies", bodies)):
            name = part_name(table, index, self.format)
            entry[table] = {
                "file": name,
                "rows": int(len(frame["body"])),
                # of the bytes written, hashed before they went to disk
                "sha256": write_part(frame, self.out_dir / name, self.format, root=self.out_dir),
            }
        summary = bodies_summary(bodies)  # for the report: no reading back
        with self._record_lock:  # chunks finish on several threads
            self.ledger.record(index, entry)
            self._summaries[index] = summary
        # a command's start-up ends with its first chunk on disk: pyarrow
        # and the table kernels are loaded by then (a no-op unless the
        # command line held the collector, and after the first chunk)
        release_collector()

    def run(self, scheduler=None, progress=None, notify=None, status=None):
        """Compute and write every missing chunk; then the report.

        Parameters
        ----------
        scheduler : str, distributed.Client or a dask cluster, optional
            ``"tcp://host:port"`` of a running ``dask scheduler``, a Client,
            or a cluster object (``distributed.LocalCluster``): chunks run
            on its workers.  Default: in-process.
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
            if self.device == "cuda":
                raise InputError(
                    "device='cuda' searches on this machine's GPU; a dask scheduler's "
                    "workers search on their CPUs: use one or the other"
                )
        # refusals first, touching nothing: a foreign directory, another
        # survey's parameters, then an unusable scheduler
        self.ledger.refuse_foreign_directory()
        self.ledger.refuse_other_parameters()
        client = None
        if scheduler is not None:
            client = self._connect(scheduler, status)
        try:
            return self._run_locked(client, progress, notify)
        finally:
            if client is not None and client is not scheduler:
                client.close()

    def _run_locked(self, client, progress, notify):
        made = []
        try:
            make_directories(self.out_dir, made)
            # "new/.." did not exist before: what it names now is checked again
            self.ledger.refuse_foreign_directory()
        except OSError as error:
            remove_directories(made)
            raise InputError(f"cannot create {self.out_dir}: {error.strerror}") from None
        except BaseException:
            remove_directories(made)
            raise
        with self.lock():
            self._summaries = {}
            self.prepare()
            self.ledger.clean_partial()
            damaged = self.verify()
            if damaged:
                self.ledger.write_manifest()
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
            if self.missing():
                raise InputError(f"{self.out_dir} is incomplete ({len(self.missing())} chunks)")
            # a run with nothing left to compute reads the parts for its
            # report: not with the start-up's collector hold
            release_collector()
            return survey_report(
                self.out_dir,
                self.n_max,
                self.q_max,
                len(self.skipped),
                verify=False,
                summaries=self._summaries,
            )

    def _run_local(self, todo, progress):
        """Search the chunks in order; make, write and record their tables side by side.

        This thread runs the search of one chunk after another (the parallel
        kernel, on all cores).  Each searched chunk goes to a pool of
        :func:`table_workers` threads that build its tables (compiled
        kernels that release the GIL), write both parts, hash them and then
        record the chunk in the ledger (one at a time, under a lock).  At
        most that many searched chunks wait; on an error or an interrupt
        the ones already searched are still written before the lock on the
        directory is released: a chunk is in the ledger with both its
        parts, or not at all.
        """
        from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

        workers, pool, pending = None, None, set()
        try:
            for index in todo:
                found = compute.search_chunk(
                    self.chunk_moments(index), self.n_max, self.q_max, device=self.device
                )
                if workers is None:  # numba's threading layer is known after a search
                    workers = table_workers(self.n_max, self.q_max, self.chunk)
                    if workers:
                        pool = ThreadPoolExecutor(workers, thread_name_prefix="orbits-chunk")
                if not workers:  # kernels may not run side by side: one chunk at a time
                    self._collect([_Done(self._finish_chunk(index, found))], progress)
                    continue
                while len(pending) >= workers:
                    done, pending = wait(pending, return_when=FIRST_COMPLETED)
                    self._collect(done, progress)
                pending.add(pool.submit(self._finish_chunk, index, found))
            while pending:
                done, pending = wait(pending, return_when=FIRST_COMPLETED)
                self._collect(done, progress)
        finally:
            # every chunk handed to the pool is searched: finish it
            if pool is not None:
                pool.shutdown(wait=True)

    def _finish_chunk(self, index, found):
        bodies, orbits = compute.chunk_columns(found, index * self.chunk, self.columns)
        self.write_chunk(index, bodies, orbits)
        return len(bodies["body"])

    @staticmethod
    def _collect(done, progress):
        """Re-raise a finished chunk's error; report its bodies."""
        for future in done:
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
            client, own = _client_within(Client, scheduler, CONNECT_TIMEOUT), True
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
        """Chunks on the workers, written here as they finish.

        Every worker must run this process's orbits (version and sources,
        checked per chunk, so also on workers that join later).  A chunk
        lost on the cluster (a worker killed again and again, the scheduler
        gone) ends the run with one InputError; the chunks written so far
        stay in the ledger and a rerun resumes.
        """
        from distributed import as_completed

        expected = (__version__, source_fingerprint())
        futures = {
            client.submit(
                _chunk_on_worker,
                expected,
                self.chunk_moments(index),
                self.n_max,
                self.q_max,
                index * self.chunk,
                self.columns,
                pure=False,
            ): index
            for index in todo
        }
        completed, index = as_completed(futures), None
        while True:
            try:
                future = next(completed)
                index = futures[future]
                bodies, orbits = future.result()
            except StopIteration:
                break
            except OrbitsError:
                raise
            except Exception as error:  # noqa: BLE001 - dask's and the network's
                where = f"chunk {index}" if index is not None else "a chunk"
                raise InputError(
                    f"{where} was lost on the dask cluster ({type(error).__name__}: "
                    f"{one_line(error)}); the chunks written so far are kept: rerun the "
                    "same command to resume (a worker that dies again and again may be "
                    "out of memory: try a smaller --chunk)"
                ) from None
            self.write_chunk(index, bodies, orbits)
            if progress is not None:
                progress(len(bodies["body"]))

    def report(self):
        """Summary of a complete survey from its verified parts; written to ``report.json``."""
        return survey_report(self.out_dir, self.n_max, self.q_max, len(self.skipped))


# "tcp://HOST:8786 by default; 8787 is its dashboard": what the errors say
_SCHEDULER_HINT = (
    "is it a dask scheduler's address (tcp://HOST:8786 by default; 8787 is its dashboard)?"
)


def _client_within(client_class, address, timeout):
    """``Client(address)``, or one InputError within about ``1.5 timeout + 1`` s.

    dask's own ``timeout`` bounds reaching the port, not the handshake: a
    port that accepts and never answers (a silent listener, or an HTTP
    server such as the dashboard on 8787) hung ``orbits survey
    --scheduler`` for good (an audit: still waiting after 623 s).  So the
    client is made on a daemon thread and given up after the wait; one
    that connects after all is closed there.  An answer in another
    protocol (junk bytes read as a frame: "Unable to allocate 3.07 EiB")
    is said to be one, not a timeout.  A port that never answers keeps the
    abandoned thread (and dask's connection) until the peer closes: Python
    cannot stop a thread.
    """
    lock, box = threading.Lock(), {}

    def connect():
        try:
            client = client_class(address, timeout=timeout)
        except BaseException as error:  # noqa: BLE001 - reported by the caller
            with lock:
                box["error"] = error
            return
        with lock:
            if box.get("abandoned"):
                client.close()
            else:
                box["client"] = client

    thread = threading.Thread(target=connect, name="orbits-dask-connect", daemon=True)
    thread.start()
    try:
        thread.join(1.5 * timeout + 1.0)
    except BaseException:  # KeyboardInterrupt: a client that connects later is closed
        with lock:
            box["abandoned"] = True
            late = box.pop("client", None)
        if late is not None:
            late.close()
        raise
    with lock:
        if "client" in box:
            return box["client"]
        error = box.get("error")
        if error is None:
            box["abandoned"] = True
            raise InputError(
                f"the dask scheduler at {address} did not answer within {timeout} s "
                f"(a port that accepts but does not answer); {_SCHEDULER_HINT}"
            )
    if isinstance(error, (OSError, TimeoutError)):
        raise InputError(
            f"cannot reach the dask scheduler at {address} within {timeout} s: {one_line(error)}"
        ) from None
    raise InputError(
        f"the server at {address} does not answer as a dask scheduler "
        f"({type(error).__name__}: {one_line(error)}); {_SCHEDULER_HINT}"
    ) from None


# the first chunk on a worker process runs alone: its lazy imports (pandas,
# pyarrow, the kernels) taken by two worker threads at once met numpy.ma
# partially initialised ("has no attribute 'MaskedArray'") on fresh workers
# with --nthreads 2 (an audit, 2 of 3 starts)
_FIRST_CHUNK = threading.Lock()
_first_chunk_done = False


def _chunk_on_worker(expected, moments, n_max, q_max, first_id, columns):
    """A chunk's tables on a dask worker that runs the client's orbits.

    The search and :func:`compute.chunk_columns`, as a local run makes
    them (so the parts' bytes are the same).

    ``expected``: the client's ``(version, source fingerprint)``; a worker
    with other code would write other numbers under the client's version.
    """
    found = (__version__, source_fingerprint())
    if found != expected:
        raise InputError(
            f"a dask worker runs orbits {found[0]} (sources {found[1][:12] or 'unknown'}), "
            f"not this run's {expected[0]} (sources {expected[1][:12] or 'unknown'}): "
            "install the same orbits on the workers as here"
        )

    def tables():
        return compute.chunk_columns(
            compute.search_chunk(moments, n_max, q_max), first_id, columns
        )

    global _first_chunk_done
    if not _first_chunk_done:
        with _FIRST_CHUNK:  # the first chunk alone on a worker (its kernels load once)
            if not _first_chunk_done:
                first = tables()
                _first_chunk_done = True
                return first
    return tables()


class _Done:
    """A finished result in the shape of a future (the serial path)."""

    def __init__(self, value):
        self.value = value

    def result(self):
        return self.value


def table_workers(n_max, q_max, chunk):
    """Threads that build and write chunks side by side (0: one chunk at a time).

    One per numba thread (:func:`orbits.threads.get_num_threads`), fewer
    when that many chunks in flight would exceed the memory budget; 0 when
    numba's threading layer cannot run kernels from several threads at once
    (``workqueue``).
    """
    import numba

    from ..limits import memory_budget
    from ..threads import get_num_threads

    try:
        layer = numba.threading_layer()
    except ValueError:  # no parallel kernel has run yet (a survey on the GPU)
        from ..core.tasks import start_threads

        try:
            start_threads(np.zeros(1))
            layer = numba.threading_layer()
        except ValueError:  # no layer can be loaded (or the JIT is off)
            return 0
    if layer not in ("omp", "tbb"):
        return 0
    # survey_estimate counts two chunks in flight
    per_chunk = max(compute.survey_estimate(chunk, n_max, q_max, chunk)[0] / 2.0, 1.0)
    fits = int(memory_budget() // per_chunk) - 1
    return max(1, min(get_num_threads(), fits))


def _check_scheduler(scheduler):
    """Refuse an address that cannot be a dask scheduler before connecting."""
    import re

    if not isinstance(scheduler, str):
        try:
            from distributed import Client
            from distributed.deploy import Cluster

            kinds = (Client, Cluster)
        except ImportError:
            kinds = ()
        if not isinstance(scheduler, kinds):
            raise ArgumentTypeError(
                "scheduler must be a dask scheduler's address ('tcp://HOST:PORT'), a "
                f"distributed.Client or a cluster, got {type(scheduler).__name__}"
            )
        return
    match = re.fullmatch(
        r"(?:(?:tcp|tls|ucx|inproc|ws|wss)://)?[\w.\-\[\]:]+:(\d{1,5})", scheduler
    )
    if not match or not 0 < int(match.group(1)) < 65536:
        raise InputError(
            f"--scheduler {scheduler!r} is not a dask scheduler address "
            "(expected tcp://HOST:PORT, port 1-65535)"
        )
