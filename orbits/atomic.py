"""Atomic file output: a failed or interrupted run never leaves a partial file.

Every file ``orbits`` writes goes first to a temporary file in the target's
directory, is flushed and fsync'ed, and then replaces the target with
``os.replace`` (atomic on POSIX).  The guarantees:

* On any exception, including ``KeyboardInterrupt`` and the SIGTERM/SIGHUP
  the command line turns into :class:`Terminated`, the temporary file is
  removed and an existing target is left untouched.
* A target that exists and is not a regular file (a device such as
  ``/dev/null``, a FIFO, a socket) is refused: it is never replaced by a
  regular file.  A symbolic link at the target is refused too, whatever it
  points to: nothing is written through a link, so nothing is written
  outside the path given; one planted after the check is replaced itself
  (``os.replace`` never follows it), never written through.  (Links in the
  directories above the target are the user's own layout and are used.)
  :func:`write_bytes_under` and :func:`file_set` go further: they write
  through directory descriptors held from a root down, so a directory
  swapped for a link during a long run is refused, never written through.
* Temporary names are ``.NAME.PID.RANDOM.part`` (NAME shortened, with a
  hash of the whole, when the name is too long to take the suffix).  A
  process killed with
  SIGKILL cannot clean up, so every later write to the same directory
  removes the leftovers of ``.NAME.*.part`` whose process is gone; the
  temporaries of a live process are never touched.
* A write that fails (disk full, quota, I/O error) raises
  :class:`~orbits.errors.InputError` naming the path.
* :func:`make_directories` returns the directories it made for a target,
  so that :func:`remove_directories` removes them again after an error or
  a stop (only those, and only while empty).
"""

import errno
import io
import os
import re
import stat
import sys
import tempfile
import threading
from contextlib import contextmanager
from pathlib import Path

from .errors import InputError

# 17 significant digits always round-trip an IEEE double
FLOAT_FORMAT = "%.17g"


def csv_float_options():
    """``read_csv`` keyword arguments that read floats back bit for bit.

    pandas 3 parses floats correctly rounded by default (and deprecates the
    option); pandas 2.x needs ``float_precision="round_trip"``.
    """
    import pandas as pd

    major = int(pd.__version__.split(".")[0])
    return {} if major >= 3 else {"float_precision": "round_trip"}


class Terminated(BaseException):
    """SIGTERM or SIGHUP, raised so that clean-up code runs (see the CLI)."""

    def __init__(self, signum):
        super().__init__(signum)
        self.signum = signum


def ensure_writable(path, stdout_hint=True):
    """Raise :class:`InputError` now if ``path`` could not be written later.

    ``path`` may be a string: a trailing ``/`` names a directory, which
    cannot take a file's contents, and is refused with a clear message.
    With ``stdout_hint`` a target that is no regular file is refused with
    the hint "use '--out -' for standard output" (False for an output that
    has no standard-output form).
    """
    text = os.fspath(path)
    if isinstance(text, str) and text.endswith(os.sep) and text != os.sep:
        raise InputError(
            f"cannot write {text}: the trailing '/' names a directory; "
            f"give a file name (e.g. {text}catalog.csv)"
        )
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    try:
        if not directory.is_dir():
            if directory.exists():
                raise InputError(f"cannot write {path}: {directory} is not a directory")
            raise InputError(f"cannot write {path}: directory {directory} does not exist")
        if not os.access(directory, os.W_OK | os.X_OK):
            raise InputError(f"cannot write {path}: directory {directory} is not writable")
        if path.is_dir():
            raise InputError(f"cannot write {path}: it is a directory")
    except OSError as error:  # a name too long for the file system (ENAMETOOLONG)
        raise InputError(f"cannot write {path}: {error.strerror or error}") from None
    _refuse_special(path, stdout_hint)
    refuse_link(path)  # found now, not after the work
    probe_directory(directory, path)


def probe_directory(directory, path=None):
    """Raise :class:`InputError` unless a file can be created in ``directory``.

    ``os.access`` answers from the permission bits, and for root almost
    always yes: a read-only mount, ``/sys`` or ``/proc`` are found only by
    trying.  The probe is an unnamed temporary file where the file system
    has ``O_TMPFILE`` (Linux: nothing is left in the directory, even if the
    process is killed); elsewhere a named temporary (``tmp...``) removed
    at once, which only a kill in that instant would leave.  ``path`` names
    the target in the message (default: the directory).
    """
    import tempfile

    try:
        tempfile.TemporaryFile(dir=directory).close()
    except OSError as error:
        what = error.strerror or type(error).__name__
        target = directory if path is None else path
        raise InputError(f"cannot write {target}: {what} (in {directory})") from None


def _refuse_special(path, stdout_hint=True):
    """Refuse a target that exists and is not a regular file (after symlinks)."""
    hint = " (use '--out -' for standard output)" if stdout_hint else ""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        if os.path.islink(path):
            raise InputError(f"cannot write {path}: it is a dangling symbolic link") from None
        return
    except OSError as error:
        raise InputError(f"cannot write {path}: {error.strerror}") from None
    if stat.S_ISREG(mode):
        through = _magic_link(path)
        if through:
            raise InputError(
                f"cannot write {path}: it is a symbolic link into {through} "
                f"(a process's stream or a device); orbits only replaces regular files{hint}"
            )
        return
    kind = (
        "a directory"
        if stat.S_ISDIR(mode)
        else "a character device"
        if stat.S_ISCHR(mode)
        else "a block device"
        if stat.S_ISBLK(mode)
        else "a FIFO (named pipe)"
        if stat.S_ISFIFO(mode)
        else "a socket"
        if stat.S_ISSOCK(mode)
        else "not a regular file"
    )
    link = " (through a symbolic link)" if os.path.islink(path) else ""
    raise InputError(
        f"cannot write {path}: it is {kind}{link}; orbits only replaces regular files{hint}"
    )


def _magic_link(path):
    """``/proc`` or ``/dev`` if a symlink chain from ``path`` passes through it."""
    current = os.path.abspath(path)
    for _ in range(40):
        for root in ("/proc/", "/dev/"):
            if current.startswith(root):
                return root.rstrip("/")
        if not os.path.islink(current):
            return ""
        target = os.readlink(current)
        current = os.path.normpath(os.path.join(os.path.dirname(current), target))
    return ""


def _current_umask():
    """The process's umask, read without changing it where the system can.

    ``os.umask`` can only be read by setting it: for that instant every
    file another thread created got mode 0666 (an audit saw one world-
    writable file).  Linux (4.7 and later) states it in
    ``/proc/self/status``; elsewhere the set-and-restore is the only way,
    done under a lock so that at least this package's writers never race.
    """
    try:
        with open("/proc/self/status", encoding="ascii", errors="replace") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    with _UMASK_LOCK:
        umask = os.umask(0o077)  # the strictest value for the instant it holds
        os.umask(umask)
    return umask


_UMASK_LOCK = threading.Lock()


def _target_mode(path):
    try:
        return os.stat(path).st_mode & 0o7777
    except FileNotFoundError:
        return 0o666 & ~_current_umask()


def _pid_alive(pid):
    """Whether process ``pid`` exists and can still write (a zombie cannot).

    ``os.kill(pid, 0)`` succeeds for a zombie -- a process that has ended
    and waits for its parent to collect its status, for as long as the
    parent takes (a killed survey's temporaries outlived the rerun that
    should have removed them) -- so on Linux its state is read from
    ``/proc/PID/stat``.
    """
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        # exists, owned by someone else: alive (with hidepid its /proc
        # entry is hidden from us, which must not read as ended)
        return True
    return not _zombie(pid)


def _zombie(pid):
    """Whether ``/proc/PID/stat`` says the process has ended (Z, or X: dead)."""
    try:
        with open(f"/proc/{int(pid)}/stat", "rb") as handle:
            text = handle.read()
    except FileNotFoundError:
        return False  # gone since os.kill, or hidden: taken as alive (a rerun cleans it)
    except OSError:
        return False  # no /proc here (macOS) or not readable: taken as alive
    # "pid (comm) state ...": comm may hold spaces and parentheses
    after = text.rfind(b")") + 2
    return text[after : after + 1] in (b"Z", b"X")


def remove_stale_temporaries(directory, name, regex=False):
    """Remove ``.NAME.PID.*.part`` files of processes that no longer exist.

    ``name`` is a file name, or with ``regex`` a regular expression for one.

    Returns
    -------
    int
        How many were removed.  Temporaries of live processes (including
        this one) and files of any other pattern are never touched.
    """
    stem = name if regex else re.escape(temporary_stem(name))
    # RANDOM is mkstemp's (or write_bytes_under's) letters, digits and
    # underscores, never a dot: ".run.4242.mp4.PID.RANDOM.part", the
    # temporary of "run.4242.mp4", is not one of "run" (of process 4242)
    pattern = re.compile(r"^\." + stem + r"\.(\d+)\.[a-z0-9_]+\.part$")
    removed = 0
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return 0
    for entry in entries:
        match = pattern.match(entry.name)
        if not match or not entry.is_file(follow_symlinks=False):
            continue
        if _pid_alive(int(match.group(1))):
            continue
        try:
            os.unlink(entry.path)
            removed += 1
        except FileNotFoundError:
            pass
    return removed


@contextmanager
def atomic_path(path):
    """Yield a temporary path; on success move it onto ``path``.

    A symbolic link at ``path`` is refused (:func:`refuse_link`), never
    written through.

    Raises
    ------
    InputError
        The target's directory does not exist or is not writable, the target
        is not a regular file, or the write failed (the message names the
        path and the reason, e.g. no space left on device).
    """
    ensure_writable(path)  # a link at path refused with the other checks
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    remove_stale_temporaries(directory, path.name)
    try:
        handle, temporary = tempfile.mkstemp(
            prefix=f".{temporary_stem(path.name)}.{os.getpid()}.", suffix=".part", dir=directory
        )
    except OSError as error:
        raise InputError(f"cannot write {path}: {error.strerror}") from None
    os.close(handle)
    try:
        # mkstemp makes the file private (0600); give it the mode a plain
        # open() would, or keep the mode of the file it replaces
        os.chmod(temporary, _target_mode(path))
        yield Path(temporary)
        with open(temporary, "rb") as done:
            os.fsync(done.fileno())
        # a special file may have appeared since the check: never replace it
        _refuse_special(path)
        os.replace(temporary, path)
    except BaseException as error:
        try:
            os.unlink(temporary)
        except FileNotFoundError:
            pass
        failure = _write_failure(error, path)
        if failure is not None:
            raise failure from None
        raise


def _write_failure(error, target):
    """``error`` as an :class:`InputError` naming ``target`` if a write failed
    (disk full, quota, I/O error, permission); None for any other error."""
    if (
        isinstance(error, OSError)
        and not isinstance(error, InputError)
        and error.errno in _WRITE_ERRNOS
    ):
        return InputError(f"cannot write {target}: {os.strerror(error.errno)}")
    return None


# set while file_set moves its files into place, or make_directories makes
# one (see committing)
_COMMITTING = []


def committing():
    """Whether a :func:`file_set` is moving its files into place right now
    (or :func:`make_directories` is making and recording a directory).

    The command line puts a stop signal off until it is done, so that a set
    is written whole or not at all (and no directory made goes unrecorded).
    """
    return bool(_COMMITTING)


_SET_PREFIX = ".orbits-set."


@contextmanager
def file_set(directory, names):
    """Write the files ``names`` into ``directory``: all of them, or none.

    Every target is checked before anything is made (:func:`ensure_writable`,
    no symbolic link).  Yields a staging directory (a private
    ``.orbits-set.PID.RANDOM.part`` in ``directory``) to write the files
    into under the same names.  When the block ends normally each staged
    file replaces its target (checked again, ``os.replace``) while stop
    signals wait (:func:`committing`), and the staging directory is removed;
    on any exception, including a stop signal, it is removed and no target
    is touched.  A staging directory left by a killed process is removed by
    the next set written to the same directory.

    Raises
    ------
    InputError
        A target that cannot be written, or a missing file at the end.  An
        :class:`InputError` raised in the block that names the staging
        directory (a write into it failed: disk full) names ``directory``
        instead, the user's target.
    """

    directory = Path(directory)
    names = list(dict.fromkeys(names))
    check_targets(directory, names)
    _remove_stale_sets(directory)
    try:
        stage = Path(
            tempfile.mkdtemp(prefix=f"{_SET_PREFIX}{os.getpid()}.", suffix=".part", dir=directory)
        )
    except OSError as error:
        raise InputError(f"cannot write into {directory}: {error.strerror}") from None
    descriptors = []
    try:
        # held from the start: the files are moved from this stage into this
        # directory, even if either path is swapped for a link meanwhile
        descriptors.append(_open_directory(directory))
        descriptors.append(open_directory_nofollow(stage))
        directory_fd, stage_fd = descriptors
        yield stage
        missing = [name for name in names if not _regular_at(stage_fd, name)]
        if missing:
            raise InputError(f"{directory}: {missing[0]} was not made")
        _COMMITTING.append(True)
        try:
            for name in names:
                _refuse_special_at(directory_fd, name, directory / name)
                os.replace(name, name, src_dir_fd=stage_fd, dst_dir_fd=directory_fd)
        finally:
            _COMMITTING.clear()
    except InputError as error:
        # a write that failed in the stage (disk full) names the user's target,
        # not the private staging directory
        text = str(error)
        # the stage as mkdtemp named it (absolute from Python 3.12), or as
        # a caller joined it to the directory it was given
        named = [str(stage), str(directory / stage.name)]
        if not any(name in text for name in named):
            raise
        for name in named:
            text = text.replace(name, str(directory))
        error.args = (text,)
        raise
    finally:
        for descriptor in descriptors:
            os.close(descriptor)
        _remove_stage(directory, stage)


def _open_directory(directory):
    """A descriptor of ``directory`` (its own path followed: the caller's layout)."""
    try:
        return os.open(directory, _DIRECTORY_ACCESS | os.O_DIRECTORY | os.O_CLOEXEC)
    except OSError as error:
        raise InputError(f"cannot write into {directory}: {error.strerror or error}") from None


def _regular_at(fd, name):
    """Whether ``name`` in directory ``fd`` is a regular file (not a link)."""
    try:
        return stat.S_ISREG(os.stat(name, dir_fd=fd, follow_symlinks=False).st_mode)
    except OSError:
        return False


def _remove_stage(directory, stage):
    """Remove a set's staging directory, unless a link was put in its place."""
    import shutil

    if os.path.islink(stage):
        return  # never removed through: the link is the other process's
    shutil.rmtree(stage, ignore_errors=True)


def make_directories(path, made=None):
    """Create the directory ``path`` and its missing parents; return those made.

    Each is made with ``os.mkdir`` in turn, top first, and added to
    ``made`` (a list, new if omitted) at once, a stop signal waiting
    meanwhile (:func:`committing`): the list holds exactly the directories
    this call created, even when it is stopped (``.`` and ``..`` are never
    made, an existing one is kept).  Give it to :func:`remove_directories`
    to undo the call.

    Returns
    -------
    list of Path
        ``made``: the real paths (``os.path.realpath``) of the directories
        made, top first (none when ``path`` existed).

    Raises
    ------
    OSError
        As ``os.mkdir`` (``FileExistsError`` for a file in the way); the
        directories made before are left in ``made``.
    """
    path = Path(path)
    made = [] if made is None else made
    for step in [*reversed(path.parents), path]:
        if step.name in ("", ".", "..") or os.path.isdir(step):
            continue
        _COMMITTING.append(True)
        try:
            os.mkdir(step)
            # its real path: one after a ".." still names it once the
            # directory before the ".." is removed
            made.append(Path(os.path.realpath(step)))
        finally:
            _COMMITTING.pop()
    return made


def remove_directories(made):
    """Remove the directories ``made`` by :func:`make_directories`, deepest first.

    Only those still empty: a directory that holds anything (files written,
    or put there by someone else) is kept, and so are those above it.
    """
    for directory in reversed(made):
        try:
            os.rmdir(directory)
        except OSError:
            pass


def check_targets(directory, names):
    """Raise :class:`InputError` unless every file ``names`` in ``directory`` can be written.

    :func:`ensure_writable` (no symbolic link among its checks), for each;
    what :func:`file_set` checks before anything is made.
    """
    for name in names:
        # a file of a set has no standard-output form: no '--out -' hint
        ensure_writable(Path(directory) / name, stdout_hint=False)


def _remove_stale_sets(directory):
    import shutil

    pattern = re.compile(r"^" + re.escape(_SET_PREFIX) + r"(\d+)\.[^/]*\.part$")
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return
    for entry in entries:
        match = pattern.match(entry.name)
        if match and entry.is_dir(follow_symlinks=False) and not _pid_alive(int(match.group(1))):
            shutil.rmtree(entry.path, ignore_errors=True)


_WRITE_ERRNOS = {
    errno.ENOSPC,
    errno.EDQUOT,
    errno.EIO,
    errno.EFBIG,
    errno.EROFS,
    errno.EACCES,
    errno.EPERM,
    errno.ENOENT,
}


def write_text_atomic(path, text):
    """Write ``text`` to ``path`` atomically (see :func:`atomic_path`)."""
    with atomic_path(path) as temporary:
        temporary.write_text(text)


def write_bytes_atomic(path, data):
    """Write ``data`` (bytes) to ``path`` atomically (see :func:`atomic_path`)."""
    with atomic_path(path) as temporary:
        temporary.write_bytes(data)


# O_PATH (Linux): a descriptor that needs no read permission on the
# directory (a drop box, mode 0733, takes files) and still serves as dir_fd
_DIRECTORY_ACCESS = getattr(os, "O_PATH", os.O_RDONLY)
_DIRECTORY_FLAGS = _DIRECTORY_ACCESS | os.O_DIRECTORY | os.O_NOFOLLOW | os.O_CLOEXEC


def open_directory_nofollow(path, shown=None, dir_fd=None):
    """A descriptor of the directory ``path`` (relative to ``dir_fd``), never through a link.

    Only ``path``'s last component is checked: the directories above it
    are the user's layout.  ``shown`` names it in messages.

    Raises
    ------
    InputError
        ``path`` is a symbolic link, not a directory, or cannot be opened.
    """
    shown = path if shown is None else shown
    try:
        return os.open(path, _DIRECTORY_FLAGS, dir_fd=dir_fd)
    except OSError as error:
        try:
            link = stat.S_ISLNK(os.lstat(path, dir_fd=dir_fd).st_mode)
        except OSError:
            link = False
        if link:
            refuse_link(shown)  # raises
        if error.errno == errno.ENOTDIR:
            raise InputError(f"cannot write into {shown}: it is not a directory") from None
        raise InputError(f"cannot write into {shown}: {error.strerror or error}") from None


def write_bytes_under(root, relative, data):
    """Write ``data`` to ``root/relative`` atomically, following no link from ``root`` down.

    As :func:`write_bytes_atomic`, but every directory from ``root`` (its
    last component included) to the file is opened in turn without
    following a link, and the temporary file is made, moved and removed
    through the last one's descriptor: a directory swapped for a link
    while a long run writes (a survey's ``orbits/`` folder) is refused,
    never written through.  The directories above ``root`` are the user's
    layout and are used as they are.

    Raises
    ------
    InputError
        A link or a non-directory on the way, a target that is a link or
        not a regular file, or a write that failed (naming the path).
    """
    import secrets

    root, relative = Path(root), Path(relative)
    target = root / relative
    shown = root
    fd = open_directory_nofollow(root)
    try:
        for name in relative.parts[:-1]:
            shown = shown / name
            inner = open_directory_nofollow(name, shown, dir_fd=fd)
            os.close(fd)
            fd = inner
        name = relative.name
        mode = _refuse_special_at(fd, name, target)
        temporary = f".{temporary_stem(name)}.{os.getpid()}.{secrets.token_hex(4)}.part"
        try:
            handle = os.open(
                temporary,
                os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC,
                0o666 if mode is None else 0o600,  # a new file: as open() makes it
                dir_fd=fd,
            )
        except OSError as error:
            raise InputError(f"cannot write {target}: {error.strerror}") from None
        try:
            with os.fdopen(handle, "wb") as stream:
                if mode is not None:  # keep the mode of the file it replaces
                    os.fchmod(stream.fileno(), mode)
                stream.write(data)
                stream.flush()
                os.fsync(stream.fileno())
            # a link or a special file may have appeared since: never replace it
            _refuse_special_at(fd, name, target)
            os.replace(temporary, name, src_dir_fd=fd, dst_dir_fd=fd)
        except BaseException as error:
            try:
                os.unlink(temporary, dir_fd=fd)
            except FileNotFoundError:
                pass
            failure = _write_failure(error, target)
            if failure is not None:
                raise failure from None
            raise
    finally:
        os.close(fd)


def _refuse_special_at(fd, name, target):
    """The mode of ``name`` in directory ``fd`` (None: it does not exist).

    Raises :class:`InputError` if it is a link or exists and is not a
    regular file (``target`` names it).
    """
    try:
        info = os.stat(name, dir_fd=fd, follow_symlinks=False)
    except FileNotFoundError:
        return None
    if stat.S_ISLNK(info.st_mode):
        refuse_link(target)
    if not stat.S_ISREG(info.st_mode):
        kind = "a directory" if stat.S_ISDIR(info.st_mode) else "not a regular file"
        raise InputError(
            f"cannot write {target}: it is {kind}; orbits only replaces regular files"
        )
    return info.st_mode & 0o7777


def refuse_link(path):
    """Raise :class:`InputError` if ``path`` is a symbolic link (it is not followed)."""
    if os.path.islink(path):
        raise InputError(
            f"{path} is a symbolic link; orbits never writes through a link "
            "(give the real path, or remove the link)"
        )


# a file name's longest stem in a temporary name: NAME + ".PID.RANDOM.part"
# (up to ~40 bytes) must stay within the 255 bytes of a file name
_STEM_BYTES = 200


def temporary_stem(name):
    """``name`` as it appears in its temporaries: shortened, with a hash, when long.

    The same for every call with the same name, so that the temporaries
    left by a killed process are found again (:func:`remove_stale_temporaries`).
    """
    raw = os.fsencode(name)
    if len(raw) <= _STEM_BYTES:
        return name
    import hashlib

    digest = hashlib.sha256(raw).hexdigest()[:16]
    head = raw[:100].decode("utf-8", "ignore") if isinstance(name, str) else raw[:100]
    return f"{head}~{digest}"


def open_nofollow(path):
    """A regular file opened for reading in binary, never through a symbolic link.

    The checks are made on the open descriptor, so a file swapped for a
    link or a FIFO after a caller's ``lstat`` is still refused.

    Raises
    ------
    InputError
        ``path`` is a symbolic link or not a regular file.
    FileNotFoundError, OSError
        As ``open``.
    """
    try:
        handle = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_CLOEXEC | os.O_NONBLOCK)
    except OSError as error:
        if error.errno == errno.ELOOP:
            refuse_link(path)
        raise
    stream = os.fdopen(handle, "rb")
    if not stat.S_ISREG(os.fstat(stream.fileno()).st_mode):
        stream.close()
        raise InputError(f"{path} is not a regular file")
    return stream


def read_limited(path, limit):
    """The bytes of an input file (links, pipes and devices allowed), at most ``limit``.

    Raises
    ------
    InputError
        More than ``limit`` bytes (``/dev/zero``, an endless pipe, a file too
        large for this machine's memory budget), naming the limit.
    OSError
        As ``open``.
    """
    with open(path, "rb") as handle:
        data = handle.read(limit + 1)
    if len(data) > limit:
        raise InputError(
            f"{path} holds more than {limit / 2**20:.0f} MiB (or never ends: a device "
            "or a pipe), more than an input file of this machine may take"
        )
    return data


def read_bytes_nofollow(path):
    """The bytes of a regular file, never through a symbolic link (:func:`open_nofollow`)."""
    with open_nofollow(path) as stream:
        return stream.read()


def write_stdout(text, what="the results"):
    """Write ``text`` to standard output whole, or raise.

    Python's buffered stdout drops the rest of a large write silently when
    the system writes only part of it (a disk that fills, a file-size
    limit): ``orbits catalog --out - > file`` left a truncated file with
    exit 0.  Where stdout is a file descriptor the bytes go to it directly
    until all are written; a failure is an :class:`InputError` naming
    ``what``.
    """
    stream = sys.stdout
    if stream is None or getattr(stream, "closed", False):
        raise InputError(f"standard output is closed: give a file to write {what} to")
    stream.flush()
    descriptor = None
    # the console's own stdout only: a notebook kernel's stream can name a
    # descriptor that leads to the kernel's terminal, not to the notebook
    if isinstance(stream, io.TextIOWrapper) and os.linesep == "\n":
        try:
            descriptor = stream.fileno()
            encoding = stream.encoding
        except (AttributeError, OSError, ValueError):  # a capture over BytesIO
            descriptor = None
    if descriptor is None:
        stream.write(text)
        stream.flush()
        return
    data = memoryview(
        text.encode(encoding or "utf-8", getattr(stream, "errors", None) or "strict")
    )
    try:
        while data:
            data = data[os.write(descriptor, data) :]
    except BrokenPipeError:  # the reader has gone (`| head`): the command line's to tell
        raise
    except OSError as error:
        raise InputError(
            f"cannot write {what} to standard output: {error.strerror or error}"
        ) from None


def write_csv_atomic(frame, path, header_lines=()):
    """Write a DataFrame as CSV atomically, floats round-tripping exactly.

    ``header_lines`` are written first, each prefixed with ``# `` (read back
    with ``pandas.read_csv(path, comment="#")``).  ``path`` ``"-"`` writes
    to standard output.
    """
    if os.fspath(path) == "-":
        text = "".join(f"# {line}\n" for line in header_lines)
        write_stdout(text + frame.to_csv(index=False, float_format=FLOAT_FORMAT))
        return
    with atomic_path(path) as temporary:
        with open(temporary, "w", newline="") as handle:
            for line in header_lines:
                handle.write(f"# {line}\n")
            frame.to_csv(handle, index=False, float_format=FLOAT_FORMAT)
