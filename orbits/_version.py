"""The installed package version (from the package metadata)."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("orbits")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"
