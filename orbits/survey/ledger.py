"""The survey's ledger: manifest, lock and verification of a survey directory.

``DIR/manifest.json`` holds the survey's parameters and a ledger of every
finished chunk (its two part files, row counts, body-id range and the
SHA-256 of each part); the manifest carries the SHA-256 of its own canonical
JSON, so a hand edit is damage.  Every entry is bound to its chunk: the file
names are the chunk's own, the body ids the chunk's range.  A chunk is done
exactly when its entry matches its files.  No symbolic link inside a survey
directory is ever followed.  One run at a time holds a directory (an
exclusive ``fcntl`` lock on ``DIR/.lock``).
"""

import hashlib
import json
from pathlib import Path

from .._args import path_argument
from ..atomic import (
    open_nofollow,
    read_bytes_nofollow,
    refuse_link,
    remove_stale_temporaries,
    write_bytes_under,
)
from ..errors import InputError

FORMATS = ("csv", "parquet")
MANIFEST = "manifest.json"
REPORT = "report.json"
LOCK = ".lock"
# 3: the manifest carries its own SHA-256; 2 (read, not resumed): without
SURVEY_FORMAT = 3
READABLE_FORMATS = (2, 3)
TABLES = ("bodies", "orbits")


def sha256_file(path):
    """SHA-256 of a regular file, never through a symbolic link.

    Opened by :func:`orbits.atomic.open_nofollow` (a link or a non-regular
    file raises :class:`~orbits.errors.InputError`).
    """
    return _digest(path)[0]


def _digest(path):
    """``(SHA-256, newlines, quoted)`` of a regular file read once (see :func:`sha256_file`)."""
    digest = hashlib.sha256()
    newlines, quoted = 0, False
    with open_nofollow(path) as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
            newlines += block.count(b"\n")
            quoted = quoted or b'"' in block
    return digest.hexdigest(), newlines, quoted


def is_chunk_key(key):
    """A ledger key: a chunk index in ASCII decimal digits (``"²"`` is a digit, not decimal)."""
    return isinstance(key, str) and key.isascii() and key.isdecimal()


def _part_rows(path, fmt, newlines, quoted):
    """Rows of a part: Parquet's metadata; a CSV's records after the header.

    A CSV without a quote has one record per line; with quotes (a name
    holding a line break) the records are counted by the csv module.
    """
    if fmt == "parquet":
        import pyarrow.parquet as pq

        with open_nofollow(path) as handle:
            return pq.ParquetFile(handle).metadata.num_rows
    if not quoted:
        return newlines - 1
    import csv
    import io

    # the wrapper owns the handle: closing it closes both (a wrapper left to
    # the collector warned ResourceWarning once per part)
    with io.TextIOWrapper(open_nofollow(path), "utf-8", newline="") as text:
        return sum(1 for _ in csv.reader(text)) - 1


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


def chunk_count(parameters):
    """How many chunks the survey of a manifest's ``parameters`` has."""
    return -(-parameters["body_count"] // parameters["chunk"])


def entry_problem(key, entry, parameters):
    """What binds an entry to its chunk and the parameters, broken ('' if not)."""
    chunks = chunk_count(parameters)
    if not (is_chunk_key(key) and key == str(int(key))):
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
        problem = entry_problem(key, entry, parameters)
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
            digest, newlines, quoted = _digest(path)
            if digest != item["sha256"]:
                return f"{item['file']} does not match its SHA-256 (changed or truncated)"
            # the count is the ledger's word too: read_survey holds the
            # part to it, so a check must (a forged count is a damaged chunk)
            rows = _part_rows(path, parameters["format"], newlines, quoted)
            if rows != item["rows"]:
                return f"{item['file']} has {rows} rows, the ledger says {item['rows']}"
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


def has_parts(out_dir):
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
        if has_parts(out_dir):
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
    # a format-2 manifest (before checksums and layouts) has neither key: one
    # that has them was edited down to 2, which would switch the check off
    if version < 3 and ("sha256" in document or "columns" in (document.get("parameters") or {})):
        raise InputError(
            f"{manifest} says format {version} but carries a later format's keys "
            "(edited by hand or damaged): its ledger cannot be trusted; rerun the "
            "survey into a new directory"
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
        or parameters.get("columns", "all") not in ("compact", "all")
        or (document["orbits_survey"] >= 3 and "columns" not in parameters)
        or not all(
            isinstance(parameters[k], int) and parameters[k] >= 1
            for k in ("body_count", "n_max", "q_max", "chunk")
        )
    ):
        raise InputError(f"{manifest} is incomplete or damaged")
    if not all(is_chunk_key(key) and isinstance(entry, dict) for key, entry in parts.items()):
        raise InputError(f"{manifest} has a damaged ledger")
    return document


def missing_chunks(document):
    """``["chunk K", ...]``: the chunks a manifest's ledger has no entry for."""
    ledger, chunks = document["parts"], chunk_count(document["parameters"])
    return [f"chunk {k}" for k in range(chunks) if str(k) not in ledger]


def check_parts(out_dir):
    """Verify the parts of a survey directory against its ledger (not ``report.json``).

    :func:`orbits.survey.check_survey` adds the check of the report.

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
    chunks = chunk_count(parameters)
    damaged, verified = [], 0
    for key in sorted(ledger, key=int):  # keys checked by load_manifest
        problem = _check_part(out_dir, key, ledger[key], parameters)
        if problem:
            damaged.append(f"chunk {key}: {problem}")
        else:
            verified += 1
    missing = missing_chunks(document)
    return {
        "chunks": chunks,
        "verified": verified,
        "damaged": damaged,
        "missing": missing,
        "complete": not damaged and not missing,
    }


def _held(path, handle):
    """The error for a lock file ``path`` another run holds (its pid read from ``handle``)."""
    handle.seek(0)
    owner = handle.read().strip() or "unknown"
    return InputError(
        f"{path.parent} is being written by another orbits run "
        f"(pid {owner}); wait for it to finish or use another "
        "directory"
    )


def _not_regular(path):
    """The error for a lock file ``path`` that is not a regular file (a FIFO, a directory)."""
    return InputError(f"cannot lock {path.parent}: {path} is not a regular file")


def check_unlocked(directory):
    """Refuse at once a directory another run holds (see :class:`_DirectoryLock`).

    Takes and drops a shared lock on ``DIR/.lock`` if it exists, creating
    nothing; the run itself locks again.  Lets the command say "being
    written by another run" before it announces an estimate.

    Raises
    ------
    InputError
        Another run holds the lock.
    """
    import fcntl
    import os
    import stat

    path = Path(directory) / LOCK
    try:
        # O_NONBLOCK: a FIFO planted as .lock would block the open
        flags = os.O_RDONLY | os.O_NOFOLLOW | os.O_CLOEXEC | os.O_NONBLOCK
        descriptor = os.open(path, flags)
    except OSError:
        return  # no lock file (or a link, refused when the run locks)
    if not stat.S_ISREG(os.fstat(descriptor).st_mode):
        os.close(descriptor)
        raise _not_regular(path)
    with os.fdopen(descriptor, "r") as handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            raise _held(path, handle) from None
        except OSError:
            return  # a lock file flock does not take: the run reports it


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
                self.path,
                os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC | os.O_NONBLOCK,
                0o666,
            )
        except OSError as error:
            if error.errno == errno.ELOOP:
                refuse_link(self.path)
            if error.errno == errno.EISDIR:
                raise _not_regular(self.path) from None
            raise InputError(f"cannot lock {self.path.parent}: {error.strerror}") from None
        if not stat.S_ISREG(os.fstat(descriptor).st_mode):
            os.close(descriptor)
            raise _not_regular(self.path)
        self.handle = os.fdopen(descriptor, "r+")
        try:
            fcntl.flock(self.handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            error = _held(self.path, self.handle)
            self.handle.close()
            raise error from None
        try:
            self.handle.seek(0)
            self.handle.truncate()
            self.handle.write(f"{os.getpid()}\n")
            self.handle.flush()
        except OSError as error:  # a file size limit, a full disk
            try:
                self.handle.close()  # flushes the unwritten pid again, and fails again
            except OSError:
                pass
            raise InputError(f"cannot write {self.path}: {error.strerror or error}") from None
        return self

    def __exit__(self, *exc):
        self.handle.close()  # closing releases the lock
        return False


def one_line(error):
    return " ".join(str(error).split()) or type(error).__name__


class Ledger:
    """The manifest and ledger of one survey directory, as a run keeps them.

    Parameters
    ----------
    out_dir : path
    parameters : dict
        What the survey means (a rerun must match them exactly).
    source, skipped : dict, list
        Where the bodies came from and the skipped rows, kept in the manifest.

    Attributes
    ----------
    parts : dict
        The ledger: chunk index (as text) to its entry.  Filled by
        :meth:`prepare`.
    """

    def __init__(self, out_dir, parameters, source, skipped):
        self.out_dir = Path(out_dir)
        self.parameters = parameters
        self.source = source
        self.skipped = list(skipped)
        self.parts = None

    @property
    def chunks(self):
        return chunk_count(self.parameters)

    def refuse_foreign_directory(self):
        """Refuse a path that is not (and is not becoming) a survey directory, or holds a link."""
        import re

        if self.out_dir.exists() and not self.out_dir.is_dir():
            raise InputError(f"{self.out_dir} exists and is not a directory")
        if not self.out_dir.is_dir():
            return
        refuse_links(self.out_dir)
        if (self.out_dir / MANIFEST).exists():
            return
        if has_parts(self.out_dir):
            raise InputError(_NO_MANIFEST.format(directory=self.out_dir))
        # a survey being created (by another run, or one killed) has only these;
        # the manifest too, since another run may write it between the check
        # above and this listing (a report without a manifest is damage)
        ours = re.compile(
            rf"{re.escape(LOCK)}|bodies|orbits|manifest\.json|\.manifest\.json\..*\.part"
        )
        if any(not ours.fullmatch(p.name) for p in self.out_dir.iterdir()):
            raise InputError(f"{self.out_dir} exists and is not a survey directory")

    def refuse_other_parameters(self, partial=False):
        """Refuse a directory that holds another survey (touching nothing).

        ``partial``: :attr:`parameters` holds only some of the keys (those
        known before a grid is built); only they are compared.
        """
        if (self.out_dir / MANIFEST).exists():
            self.compare(load_manifest(self.out_dir), partial)

    def compare(self, existing, partial=False):
        """Refuse a loaded manifest of another format or other parameters."""
        if existing["orbits_survey"] != SURVEY_FORMAT:
            raise InputError(
                f"{self.out_dir} holds a survey of an older orbits format "
                f"({existing['orbits_survey']}); it can be read but not resumed: "
                "use a new directory"
            )
        old = existing["parameters"]
        if partial:
            old = {key: old.get(key) for key in self.parameters}
        if old != self.parameters:
            new = self.parameters
            changed = sorted(k for k in set(old) | set(new) if old.get(k) != new.get(k))
            raise InputError(
                f"{self.out_dir} holds a survey with different parameters "
                f"({', '.join(changed)}); use a new directory"
            )
        # the same bodies from a file that skipped other rows: the report the
        # run rewrites would disagree with the manifest kept (--check: damaged)
        skipped = json.loads(json.dumps(self.skipped))
        if existing.get("skipped_rows", []) != skipped:
            raise InputError(
                f"{self.out_dir} holds a survey whose bodies file skipped other rows "
                f"({len(existing.get('skipped_rows', []))} there, {len(skipped)} now); "
                "use a new directory"
            )

    def prepare(self):
        """Create the directory and manifest, or load and check an existing one.

        Call under :meth:`lock`.

        Raises
        ------
        InputError
            The directory holds a survey with other parameters (they never
            mix: use a new directory), holds a link, or cannot be written.
        """
        self.refuse_foreign_directory()
        manifest = self.out_dir / MANIFEST
        existing = load_manifest(self.out_dir) if manifest.exists() else None
        if existing is not None:
            self.compare(existing)
        # a deleted table folder is made again (its chunks are recomputed)
        try:
            self.out_dir.mkdir(parents=True, exist_ok=True)
            for sub in TABLES:
                refuse_link(self.out_dir / sub)
                (self.out_dir / sub).mkdir(exist_ok=True)
        except OSError as error:
            where = error.filename or self.out_dir
            if isinstance(error, FileExistsError):  # DIR/bodies or DIR/orbits is a file
                raise InputError(
                    f"{where} is not a directory; a survey keeps its parts there"
                ) from None
            raise InputError(f"cannot create {where}: {error.strerror}") from None
        self.refuse_blocked_parts()
        if existing is not None:
            self.parts = existing["parts"]
        else:
            self.parts = {}
            self.write_manifest()

    def write_manifest(self):
        """Write the manifest (parameters and ledger, with its own SHA-256) atomically."""
        document = {
            "orbits_survey": SURVEY_FORMAT,
            "parameters": self.parameters,
            "source": self.source,
            "skipped_rows": self.skipped,
            # by chunk, whichever thread finished first
            "parts": dict(sorted(self.parts.items(), key=lambda item: int(item[0]))),
        }
        document["sha256"] = manifest_checksum(document)
        text = json.dumps(document, indent=1) + "\n"
        write_bytes_under(self.out_dir, MANIFEST, text.encode("utf-8"))

    def record(self, index, entry):
        """Add a finished chunk's entry (both parts on disk) and write the manifest."""
        self.parts[str(index)] = entry
        self.write_manifest()

    def lock(self):
        """The directory's exclusive lock (a context manager).

        Raises
        ------
        InputError
            Another run holds it, or ``.lock`` is a link or not a regular file.
        """
        return _DirectoryLock(self.out_dir)

    def clean_partial(self):
        """Remove temporary files of killed runs (never parts, never a live run's)."""
        for table in TABLES:
            remove_stale_temporaries(self.out_dir / table, r"part-\d+\.\w+", regex=True)
        remove_stale_temporaries(self.out_dir, MANIFEST)
        remove_stale_temporaries(self.out_dir, REPORT)

    def refuse_blocked_parts(self):
        """Refuse a part's name held by something no file may replace (a directory, a FIFO).

        Before anything is computed or dropped from the ledger: such a part
        could never be written, and the run stopped only at its chunk, after
        :meth:`verify` had taken the entry out of the manifest.
        """
        import os
        import re

        pattern = re.compile(rf"part-\d+\.{re.escape(self.parameters['format'])}")
        for table in TABLES:
            try:
                entries = list(os.scandir(self.out_dir / table))
            except OSError as error:
                raise InputError(f"cannot read {self.out_dir / table}: {error.strerror}") from None
            for entry in entries:
                if pattern.fullmatch(entry.name) and not entry.is_file(follow_symlinks=False):
                    what = "a directory" if entry.is_dir(follow_symlinks=False) else "not a file"
                    raise InputError(
                        f"{entry.path} is {what}; a survey part is only ever replaced by a "
                        "regular file: remove it and run the survey again"
                    )

    def verify(self):
        """Check every ledger entry against its chunk and files; drop the bad ones.

        Returns
        -------
        damaged : list of str
            Entries that were not bound to their chunk, or whose files were
            missing or did not match (removed from the ledger: recomputed).
        """
        damaged = []
        for key in sorted(self.parts, key=int):
            problem = _check_part(self.out_dir, key, self.parts[key], self.parameters)
            if problem:
                damaged.append(f"chunk {int(key)}: {problem}")
                del self.parts[key]
        return damaged

    def missing(self):
        """Indices of the chunks not (verifiably) written."""
        parts = self.parts
        if parts is None:
            parts = (
                load_manifest(self.out_dir)["parts"] if (self.out_dir / MANIFEST).exists() else {}
            )
        return [k for k in range(self.chunks) if str(k) not in parts]
