"""numba's on-disk cache of a package's kernels, stale when any of its files changes.

numba (``cache=True``) keeps each kernel's machine code with a stamp of the
one file that defines it, and reuses it while that file is unchanged.  A
kernel here also carries, compiled into it, every ``@njit`` helper it
calls from the other files of :mod:`orbits.core` (a phase kernel inlines
the angle fold of :mod:`orbits.core.angles`, the elliptic integrals of
:mod:`orbits.core.elliptic`, ...).  With the per-file stamp alone, a change
to a helper leaves every kernel of the *other* files running the old
helper from the cache: silently, after a ``git pull`` into an editable
install, or after an upgrade that changes only the helper's file (numba
0.68 stamps a file by its content, so reinstalling an unchanged file keeps
its stale cache).

:func:`track_package` makes the stamp of every kernel defined in a
directory the pair (numba's own stamp of its file, the SHA-256 of all the
``.py`` files of that directory): any change to any of them recompiles the
kernels as they are next used, and nothing else changes (the cache stays
where numba puts it, with the same file names).  It does so through
numba's cache-locator list, the hook numba's caching machinery consults
for each cached function (``numba.core.caching``, numba 0.60 to 0.68);
:func:`tracking` tells whether it is in place (the test suite checks it,
so a numba without the hook fails there, not silently).  A user's
``NUMBA_CACHE_LOCATOR_CLASSES`` replaces numba's list, this locator
included.
"""

import hashlib
import os

from numba.core import caching

# the class whose locator list numba consults (CacheImpl in numba 0.68,
# _CacheImpl in 0.60)
_IMPL = getattr(caching, "CacheImpl", None) or caching._CacheImpl

# directory (absolute, normalised) -> fingerprint of its .py files
_TRACKED = {}


def sources_fingerprint(directory):
    """SHA-256 (hex) of the names and contents of the ``.py`` files in ``directory``.

    Sorted by name; subdirectories are not read.  About 0.5 ms for the
    200 kB of :mod:`orbits.core`.
    """
    digest = hashlib.sha256()
    for name in sorted(os.listdir(directory)):
        if not name.endswith(".py"):
            continue
        with open(os.path.join(directory, name), "rb") as handle:
            content = handle.read()
        digest.update(f"{name}\0{len(content)}\0".encode())
        digest.update(content)
    return digest.hexdigest()


class PackageLocator(caching._CacheLocator):
    """numba's own locator for a function, with the package's fingerprint in its stamp.

    The cache directory, the file names and the writability test are those
    of the locator numba would have chosen (in-tree ``__pycache__``,
    ``NUMBA_CACHE_DIR``, the user-wide cache, ...); only the stamp differs.
    """

    def __init__(self, base, fingerprint):
        self._base = base
        self._fingerprint = fingerprint

    def ensure_cache_path(self):
        self._base.ensure_cache_path()

    def get_cache_path(self):
        return self._base.get_cache_path()

    def get_source_stamp(self):
        return (self._base.get_source_stamp(), "package sources", self._fingerprint)

    def get_disambiguator(self):
        return self._base.get_disambiguator()

    @classmethod
    def from_function(cls, py_func, py_file):
        fingerprint = _TRACKED.get(os.path.dirname(os.path.abspath(py_file)))
        if fingerprint is None:
            return None
        for other in _IMPL._locator_classes:
            if other is cls:
                continue
            base = other.from_function(py_func, py_file)
            if base is not None:
                return cls(base, fingerprint)
        # neither the package's __pycache__ nor the user's cache directory can
        # be written (a read-only install, HOME unset or read-only): numba
        # would refuse to import the kernels at all
        base = PrivateTempLocator.from_function(py_func, py_file)
        return None if base is None else cls(base, fingerprint)


class PrivateTempLocator(caching.UserWideCacheLocator):
    """A cache in ``TMPDIR/orbits-numba-UID``: the last resort, private to the user.

    Used only where no locator of numba's applies.  numba's cache index is
    a pickle, so the directory must be the user's own: made with mode 0700,
    and never used if it is a link, belongs to another user or can be read
    or written by others; the process then compiles into a fresh private
    directory of its own (``mkdtemp``), removed when it exits.
    """

    def __init__(self, py_func, py_file):
        import tempfile

        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        self._root = os.path.join(tempfile.gettempdir(), f"orbits-numba-{os.getuid()}")
        self._cache_path = os.path.join(self._root, self.get_suitable_cache_subpath(py_file))

    def ensure_cache_path(self):
        if not _private(self._root):
            # another user took the name first (a link, or a directory open
            # to others): this process's own fresh directory, not its cache
            self._root = _process_directory()
            self._cache_path = os.path.join(
                self._root, self.get_suitable_cache_subpath(self._py_file)
            )
        super().ensure_cache_path()


def _private(root):
    """Make ``root`` (mode 0700) if missing; whether it is this user's private directory."""
    import stat

    try:
        os.mkdir(root, 0o700)
    except FileExistsError:
        pass
    except OSError:
        return False
    try:
        info = os.lstat(root)
    except OSError:
        return False
    return bool(
        stat.S_ISDIR(info.st_mode) and info.st_uid == os.getuid() and not info.st_mode & 0o077
    )


_PROCESS_DIRECTORY = []


def _process_directory():
    """A fresh private directory (``mkdtemp``, 0700) for this process, removed at exit."""
    if not _PROCESS_DIRECTORY:
        import atexit
        import shutil
        import tempfile

        path = tempfile.mkdtemp(prefix="orbits-numba-run-")
        atexit.register(shutil.rmtree, path, True)
        _PROCESS_DIRECTORY.append(path)
    return _PROCESS_DIRECTORY[0]


def track_package(directory):
    """Stamp the cached kernels defined in ``directory`` with all of its sources.

    Call it before the kernels are defined (numba picks a function's cache
    locator when ``@njit(cache=True)`` decorates it): :mod:`orbits.core`
    calls it for itself on import.  Idempotent.

    Returns
    -------
    str or None
        The fingerprint, or None when the directory's files cannot be read
        (numba's per-file stamp then applies, as without this module).
    """
    directory = os.path.normpath(os.path.abspath(directory))
    try:
        fingerprint = sources_fingerprint(directory)
    except OSError:
        return None
    _TRACKED[directory] = fingerprint
    locators = _IMPL._locator_classes
    if PackageLocator not in locators:
        locators.insert(0, PackageLocator)
    return fingerprint


def tracking(function):
    """Whether the cached numba dispatcher ``function`` is stamped by its package.

    False for a function that is not cached, or whose package is not
    tracked.
    """
    cache = getattr(function, "_cache", None)
    impl = getattr(cache, "_impl", None)
    return isinstance(getattr(impl, "locator", None), PackageLocator)
