"""The installed shapecond version (what batch rows record and Dask workers must share)."""

from importlib.metadata import PackageNotFoundError, version as _version

try:
    __version__ = _version("shapecond")
except PackageNotFoundError:  # pragma: no cover - a source tree that was never installed
    __version__ = "0+unknown"
