"""Atomic file output: a failed or interrupted run never leaves a partial file.

Every file ``orbits`` writes goes first to a temporary file in the target's
directory, is flushed and fsync'ed, and then replaces the target with
``os.replace`` (atomic on POSIX and Windows).  On any exception, including
``KeyboardInterrupt``, the temporary file is removed and an existing target
is left untouched.
"""

import os
import tempfile
from contextlib import contextmanager
from pathlib import Path

from .errors import InputError

# 17 significant digits always round-trip an IEEE double
FLOAT_FORMAT = "%.17g"


def ensure_writable(path):
    """Raise :class:`InputError` now if ``path`` could not be written later."""
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    if not directory.is_dir():
        raise InputError(f"cannot write {path}: directory {directory} does not exist")
    if not os.access(directory, os.W_OK | os.X_OK):
        raise InputError(f"cannot write {path}: directory {directory} is not writable")
    if path.is_dir():
        raise InputError(f"cannot write {path}: it is a directory")


def _target_mode(path):
    try:
        return os.stat(path).st_mode & 0o7777
    except FileNotFoundError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


@contextmanager
def atomic_path(path):
    """Yield a temporary path; on success move it onto ``path``.

    Raises
    ------
    InputError
        The target's directory does not exist or is not writable.
    """
    path = Path(path)
    ensure_writable(path)
    try:
        handle, temporary = tempfile.mkstemp(
            prefix=f".{path.name}.", suffix=".part",
            dir=path.parent if str(path.parent) else ".")
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
        os.replace(temporary, path)
    except BaseException:
        try:
            os.unlink(temporary)
        except FileNotFoundError:
            pass
        raise


def write_text_atomic(path, text):
    """Write ``text`` to ``path`` atomically."""
    with atomic_path(path) as temporary:
        temporary.write_text(text)


def write_csv_atomic(frame, path, header_lines=()):
    """Write a DataFrame as CSV atomically, floats round-tripping exactly.

    ``header_lines`` are written first, each prefixed with ``# `` (read back
    with ``pandas.read_csv(path, comment="#")``).
    """
    with atomic_path(path) as temporary:
        with open(temporary, "w", newline="") as handle:
            for line in header_lines:
                handle.write(f"# {line}\n")
            frame.to_csv(handle, index=False, float_format=FLOAT_FORMAT)
