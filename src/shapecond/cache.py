"""The on-disk cache of slow results: distance matrices, distance rows, landmark selections.

Entries live in one folder, ``$SHAPECOND_CACHE`` or else the platform's cache
folder (``platformdirs.user_cache_dir("shapecond")``, e.g. ``~/.cache/shapecond``
on Linux), one file per entry named ``KIND-KEY.npz`` (arrays) or ``KIND-KEY.json``.
The key is a hash of everything the result was computed from (:func:`key_of`).

An entry is **checked, never trusted**: it carries its key and a SHA-256
checksum of its content, and the caller states what it expects (array names and
shapes, and any further check).  An entry that does not match (edited, damaged,
written for another key, a folder in its place) is skipped with a
:class:`CacheWarning` and the result recomputed; a cache that cannot be read or
written (read-only, full disk) only costs time, with a warning.  Entries are
written with the one atomic writer (``shapecond.output``).

``shapecond cache info`` / ``shapecond cache clear`` show and empty the folder.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import warnings
from pathlib import Path

import numpy as np

from .errors import InputError
from .output import atomic_open

#: Bumped when the layout of every entry changes (old entries are then ignored).
FORMAT = "2"


class CacheWarning(UserWarning):
    """A cache entry was skipped or could not be written; the result is recomputed."""


def cache_dir() -> Path:
    """The cache folder: ``$SHAPECOND_CACHE`` or the platform's user cache folder."""
    env = os.environ.get("SHAPECOND_CACHE")
    if env:
        return Path(env)
    import platformdirs

    return Path(platformdirs.user_cache_dir("shapecond", appauthor=False))


def key_of(*parts) -> str:
    """A 32-hex-digit hash of arrays (dtype, shape and bytes), None and plain values."""
    h = hashlib.sha256(FORMAT.encode())
    for p in parts:
        if isinstance(p, np.ndarray):
            a = np.ascontiguousarray(p)
            h.update(f"array{a.dtype.str}{a.shape}".encode())
            h.update(a.tobytes())
        elif p is None:
            h.update(b"none")
        else:
            h.update(repr(p).encode())
    return h.hexdigest()[:32]


def _checksum(arrays: dict) -> str:
    h = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _warn(message: str) -> None:
    warnings.warn(message, CacheWarning, stacklevel=3)


def _path(kind: str, key: str, suffix: str) -> Path:
    return cache_dir() / f"{kind}-{key}{suffix}"


def load_arrays(kind: str, key: str, shapes: dict, check=None) -> dict | None:
    """The arrays of entry ``kind``/``key``, or None (missing, or skipped with a warning).

    Parameters
    ----------
    shapes : {name: expected shape}; ``-1`` in a shape matches any length.
    check : optional callable(arrays) raising ``InputError`` (or ``ValueError``)
        when the content is not usable; the entry is then skipped.
    """
    path = _path(kind, key, ".npz")
    if not os.path.lexists(path):
        return None
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {name: z[name] for name in z.files}
        stored_key = str(arrays.pop("__key__", ""))
        checksum = str(arrays.pop("__checksum__", ""))
        if stored_key != key:
            raise ValueError("it was written for another input")
        if checksum != _checksum(arrays):
            raise ValueError("its checksum does not match its content")
        for name, shape in shapes.items():
            got = arrays.get(name)
            if got is None or got.ndim != len(shape) or any(s not in (-1, g) for s, g in zip(shape, got.shape)):
                raise ValueError(f"array {name!r} is missing or has the wrong shape")
        if check is not None:
            check(arrays)
    except Exception as exc:  # a damaged entry may fail in any way: it only costs time
        _warn(f"ignoring cache entry {path.name}: {exc}; recomputing")
        return None
    return arrays


def save_arrays(kind: str, key: str, arrays: dict) -> None:
    """Write entry ``kind``/``key`` with its key and checksum; warn if that fails."""
    arrays = {name: np.asarray(a) for name, a in arrays.items()}
    payload = dict(arrays, __key__=np.array(key), __checksum__=np.array(_checksum(arrays)))
    buffer = io.BytesIO()
    np.savez(buffer, **payload)
    _store(_path(kind, key, ".npz"), buffer.getvalue())


def load_json(kind: str, key: str, check=None):
    """The payload of JSON entry ``kind``/``key``, or None (missing or skipped with a warning)."""
    path = _path(kind, key, ".json")
    if not os.path.lexists(path):
        return None
    try:
        entry = json.loads(path.read_text(encoding="utf-8"))
        if not isinstance(entry, dict) or entry.get("key") != key:
            raise ValueError("it was written for another input")
        payload = entry.get("payload")
        if entry.get("checksum") != _json_checksum(payload):
            raise ValueError("its checksum does not match its content")
        if check is not None:
            check(payload)
    except Exception as exc:  # a damaged entry may fail in any way: it only costs time
        _warn(f"ignoring cache entry {path.name}: {exc}; recomputing")
        return None
    return payload


def _json_checksum(payload) -> str:
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()


def save_json(kind: str, key: str, payload) -> None:
    """Write JSON entry ``kind``/``key`` (payload: JSON-ready, ``inf`` as the string "inf")."""
    # checksum what will be read back: JSON turns integer keys into strings, which sort differently
    payload = json.loads(json.dumps(payload, allow_nan=False))
    entry = {"key": key, "checksum": _json_checksum(payload), "payload": payload}
    _store(_path(kind, key, ".json"), json.dumps(entry, allow_nan=False).encode())


def _store(path: Path, data: bytes) -> None:
    try:
        with atomic_open(path, "wb") as fh:
            fh.write(data)
    except InputError as exc:
        _warn(f"cache not written ({exc}); the result will be recomputed next time")


def entries() -> list[Path]:
    """Every cache entry in the folder."""
    folder = cache_dir()
    if not folder.is_dir():
        return []
    return sorted(p for p in folder.iterdir() if p.suffix in (".npz", ".json") and p.name.count("-") >= 1)


def info() -> dict:
    """Folder, number of entries and bytes, by kind."""
    kinds: dict = {}
    for p in entries():
        kind = p.name.split("-", 1)[0]
        k = kinds.setdefault(kind, {"entries": 0, "bytes": 0})
        k["entries"] += 1
        k["bytes"] += p.lstat().st_size
    return {"folder": str(cache_dir()), "entries": sum(k["entries"] for k in kinds.values()),
            "bytes": sum(k["bytes"] for k in kinds.values()), "kinds": kinds}


def clear() -> dict:
    """Delete every entry (and leftover temporary files); return what was removed."""
    removed, size = 0, 0
    folder = cache_dir()
    leftovers = list(folder.glob(".*.tmp")) if folder.is_dir() else []
    for p in entries() + leftovers:
        try:
            n = p.lstat().st_size
            p.unlink()
        except IsADirectoryError:
            continue
        except OSError as exc:
            raise InputError(f"{p}: cannot remove ({exc.strerror or exc})") from None
        removed, size = removed + 1, size + n
    return {"folder": str(folder), "removed": removed, "bytes": size}
