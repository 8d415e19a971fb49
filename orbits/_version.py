"""The package version: the one place it is written.

``pyproject.toml`` reads it from here (``[tool.setuptools.dynamic]``), so
the installed metadata and ``orbits.__version__`` cannot differ, and a
source tree run through ``PYTHONPATH`` knows its version too.  A literal
rather than :func:`importlib.metadata.version`, which scans every
``sys.path`` entry for distributions: 11-21 ms of every command's start-up.
"""

__version__ = "0.1.0"


def source_fingerprint():
    """SHA-256 of the package's Python sources as this process imported them.

    Over every ``*.py`` file under the package directory, in sorted order,
    its relative path and its bytes: two processes (a dask client and its
    workers) with the same fingerprint run the same code, whatever the
    version string says.  ``""`` when the sources cannot be read (a
    frozen or zipped install); computed once per process.
    """
    global _FINGERPRINT
    if _FINGERPRINT is None:
        import hashlib
        from pathlib import Path

        digest = hashlib.sha256()
        root = Path(__file__).resolve().parent
        try:
            for path in sorted(root.rglob("*.py")):
                digest.update(path.relative_to(root).as_posix().encode() + b"\0")
                digest.update(path.read_bytes() + b"\0")
            _FINGERPRINT = digest.hexdigest()
        except OSError:
            _FINGERPRINT = ""
    return _FINGERPRINT


_FINGERPRINT = None
