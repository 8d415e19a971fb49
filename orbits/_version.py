"""The installed package version (from the package metadata)."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("orbits")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"


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
