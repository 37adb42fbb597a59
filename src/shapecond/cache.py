"""The on-disk cache of slow results: distance matrices, distance rows, landmark selections.

Entries live in one folder, ``$SHAPECOND_CACHE`` or else the platform's cache
folder (``platformdirs.user_cache_dir("shapecond")``, e.g. ``~/.cache/shapecond``
on Linux), one file per entry named ``KIND-KEY.npz`` (arrays) or ``KIND-KEY.json``.
The key is a hash of everything the result was computed from (:func:`key_of`).

An entry is **checked, never trusted**: it carries its key and a keyed checksum
of key and content (below), and the caller states what it expects (array names
and shapes, and any further check).  An entry that does not match (edited,
damaged, written for another key or by another cache, a folder, FIFO or link in
its place: entries are opened only if they are regular files, never through a
link, so reading one cannot block) is skipped with a :class:`CacheWarning` and
the result recomputed; a cache that cannot be read or written (read-only, full
disk) only costs time, with a warning.  Entries are written with the one atomic
writer (``shapecond.output``).

**Integrity: a keyed checksum.** The checksum is an HMAC-SHA256 under a secret
of the user's: ``.secret`` in the cache folder, 32 random bytes created with the
cache (mode 0600), which must be a regular file owned by the user running
shapecond and readable by nobody else, or the cache is not used (a warning; the
results are computed).  Why: with a plain SHA-256 stored in the entry itself,
whoever could write the folder could change an entry's content and recompute its
checksum, and change results without a word (σ 0.50 instead of 0.68, every
sample id shifted, exit status 0).  Binding an entry's name to its content
cannot work for a cache (the key names the inputs; the content is what is
expensive to recompute), and a mere statement that the folder's writers control
the results would leave shared, group-writable or copied cache folders open.
The secret makes a changed, planted or copied entry (from another user or
another cache folder) a recomputation, not a wrong answer.  It does not protect
against programs running as the same user, which can read the secret (and could
as well change shapecond itself).  Workers that share a cache folder (``batch``
and ``evaluate`` on a cluster) must therefore run as the same user; other users
get a warning and compute without the cache.

``shapecond cache info`` / ``shapecond cache clear`` show and empty the folder.
Only the cache's own files count and are removed: an entry is recognised by its
name (``KIND-KEY`` with a 32-hex-digit key) **and** its content (it is a regular
file holding that same key and a 64-hex-digit checksum), so a user's
``scan-01.npz`` or ``report-final.json`` in the folder, even one named like an
entry, is kept and reported; ``clear`` also removes the cache's leftover
temporary files and the secret (only if it is one: a private 32-byte file of
the user's; a new one comes with the next entry).
"""

from __future__ import annotations

import hashlib
import hmac
import json
import os
import re
import secrets
import warnings
from pathlib import Path

import numpy as np

from .checks import open_regular
from .errors import InputError, OutputError
from .output import atomic_open

#: Bumped when the layout of every entry changes (old entries are then ignored).
#: 3: keyed checksums (``__tag__``, ``"tag"``) instead of plain SHA-256 ones.
FORMAT = "3"
#: The cache's secret (module docstring), in the cache folder.
SECRET_NAME = ".secret"
SECRET_BYTES = 32


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
            h.update(memoryview(a).cast("B"))  # the bytes of tobytes(), without copying them
        elif p is None:
            h.update(b"none")
        else:
            h.update(repr(p).encode())
    return h.hexdigest()[:32]


def _tag(key: str, arrays: dict, secret: bytes) -> str:
    """HMAC-SHA256 under ``secret`` of the key and of every array's name, dtype, shape and bytes."""
    h = hmac.new(secret, f"{FORMAT}:{key}".encode(), hashlib.sha256)
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}{a.dtype.str}{a.shape}".encode())
        h.update(memoryview(a).cast("B"))
    return h.hexdigest()


def _json_tag(key: str, payload, secret: bytes) -> str:
    text = f"{FORMAT}:{key}:" + json.dumps(payload, sort_keys=True)
    return hmac.new(secret, text.encode(), hashlib.sha256).hexdigest()


def _read_secret(path: Path) -> bytes:
    """The secret at ``path``; ``ValueError`` (``InputError``) unless it is a private file of this user."""
    fd = open_regular(path, follow_links=False)
    try:
        st = os.fstat(fd)
        data = os.read(fd, SECRET_BYTES + 1)
    finally:
        os.close(fd)
    if hasattr(os, "geteuid") and st.st_uid != os.geteuid():
        raise ValueError(f"the cache secret {path} belongs to another user")
    if st.st_mode & 0o077:
        raise ValueError(f"the cache secret {path} may be read by others (its mode must be 0600)")
    if len(data) != SECRET_BYTES:
        raise ValueError(f"the cache secret {path} is not {SECRET_BYTES} bytes long")
    return data


def _create_secret(path: Path) -> None:
    """A new secret at ``path``, unless another process made one first (it is never replaced)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f"{SECRET_NAME}.{secrets.token_hex(8)}.tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o600)
    try:
        os.write(fd, secrets.token_bytes(SECRET_BYTES))
        os.close(fd)
        os.link(tmp, path)  # atomic, and fails rather than replace an existing secret
    except FileExistsError:
        pass
    finally:
        tmp.unlink(missing_ok=True)


def cache_secret(create: bool = False) -> bytes:
    """The cache folder's secret (module docstring), made first if ``create`` and missing.

    Raises ``ValueError`` (with the reason) when it is missing or not a private file of this user.
    """
    path = cache_dir() / SECRET_NAME
    if create and not os.path.lexists(path):
        try:
            _create_secret(path)
        except OSError as exc:
            raise ValueError(f"cannot create the cache secret {path} ({exc.strerror or exc})") from None
    if not os.path.lexists(path):
        raise ValueError(f"the cache has no secret ({path}), so its entries cannot be checked")
    return _read_secret(path)


def _warn(message: str) -> None:
    warnings.warn(message, CacheWarning, stacklevel=3)


def _path(kind: str, key: str, suffix: str) -> Path:
    return cache_dir() / f"{kind}-{key}{suffix}"


def _open_entry(path: Path):
    """A binary file object on a cache entry: a regular file, not reached through a link
    (a FIFO planted in the folder must not block ``np.load``)."""
    return os.fdopen(open_regular(path, follow_links=False), "rb")


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

    def read(secret) -> dict:
        with _open_entry(path) as fh, np.load(fh, allow_pickle=False) as z:
            arrays = {name: z[name] for name in z.files}
        stored_key = str(arrays.pop("__key__", ""))
        tag = str(arrays.pop("__tag__", ""))
        if stored_key != key:
            raise ValueError("it was written for another input")
        if not hmac.compare_digest(tag, _tag(key, arrays, secret)):
            raise ValueError("its keyed checksum does not match its content (edited, or written by another cache)")
        for name, shape in shapes.items():
            got = arrays.get(name)
            if got is None or got.ndim != len(shape) or any(s not in (-1, g) for s, g in zip(shape, got.shape)):
                raise ValueError(f"array {name!r} is missing or has the wrong shape")
        if check is not None:
            check(arrays)
        return arrays

    return _verified(path, read)


def _verified(path: Path, read):
    """``read(secret)``, or None with a warning when the entry is damaged, forged or another input's:
    a bad entry may fail in any way and only costs the time to recompute it."""
    try:
        return read(cache_secret())
    except Exception as exc:  # noqa: BLE001
        _warn(f"ignoring cache entry {path.name}: {exc}; recomputing")
        return None


def save_arrays(kind: str, key: str, arrays: dict) -> None:
    """Write entry ``kind``/``key`` with its key and keyed checksum; warn if that fails."""
    arrays = {name: np.asarray(a) for name, a in arrays.items()}
    try:
        secret = cache_secret(create=True)
    except ValueError as exc:
        _warn(f"cache not written ({exc}); the result will be recomputed next time")
        return
    payload = dict(arrays, __key__=np.array(key), __tag__=np.array(_tag(key, arrays, secret)))
    _store(_path(kind, key, ".npz"), lambda fh: np.savez(fh, **payload))  # no copy in memory: 84 MB of
    # distance rows at 52k vertices took two (0.3 → 0.1 s CPU an entry)


def load_json(kind: str, key: str, check=None):
    """The payload of JSON entry ``kind``/``key``, or None (missing or skipped with a warning)."""
    path = _path(kind, key, ".json")
    if not os.path.lexists(path):
        return None

    def read(secret):
        with _open_entry(path) as fh:
            entry = json.loads(fh.read().decode("utf-8"))
        if not isinstance(entry, dict) or entry.get("key") != key:
            raise ValueError("it was written for another input")
        payload = entry.get("payload")
        if not hmac.compare_digest(str(entry.get("tag")), _json_tag(key, payload, secret)):
            raise ValueError("its keyed checksum does not match its content (edited, or written by another cache)")
        if check is not None:
            check(payload)
        return payload

    return _verified(path, read)


def save_json(kind: str, key: str, payload) -> None:
    """Write JSON entry ``kind``/``key`` (payload: JSON-ready, ``inf`` as the string "inf")."""
    try:
        secret = cache_secret(create=True)
    except ValueError as exc:
        _warn(f"cache not written ({exc}); the result will be recomputed next time")
        return
    # checksum what will be read back: JSON turns integer keys into strings, which sort differently
    payload = json.loads(json.dumps(payload, allow_nan=False))
    entry = {"key": key, "tag": _json_tag(key, payload, secret), "payload": payload}
    data = json.dumps(entry, allow_nan=False).encode()
    _store(_path(kind, key, ".json"), lambda fh: fh.write(data))


def _store(path: Path, write) -> None:
    """``write(fh)`` into ``path``, atomically; a warning if that fails."""
    try:
        with atomic_open(path, "wb") as fh:
            write(fh)
    except (InputError, OutputError) as exc:
        _warn(f"cache not written ({exc}); the result will be recomputed next time")


#: The name of an entry (``_path``) and of a temporary file of an entry or of the secret (``output``).
ENTRY_NAME = re.compile(r"[a-z][a-z0-9_]*-[0-9a-f]{32}\.(npz|json)")
TEMP_NAME = re.compile(r"\.([a-z][a-z0-9_]*-[0-9a-f]{32}\.(npz|json)|secret)\.[0-9a-f]{16}\.tmp")
_HEX64 = re.compile(r"[0-9a-f]{64}")


def is_entry(path: Path) -> bool:
    """Whether ``path`` is an entry this cache wrote: its name and, inside, its key and checksum.

    The checksum is not verified (an entry under a lost secret is still the
    cache's own); a link, FIFO or folder is never an entry.
    """
    if not ENTRY_NAME.fullmatch(path.name):
        return False
    key = path.name.split("-", 1)[1].split(".", 1)[0]
    try:
        with _open_entry(path) as fh:
            if path.suffix == ".json":
                entry = json.loads(fh.read().decode("utf-8"))
                return (isinstance(entry, dict) and entry.get("key") == key and "payload" in entry
                        and bool(_HEX64.fullmatch(str(entry.get("tag")))))
            with np.load(fh, allow_pickle=False) as z:
                return (str(z["__key__"]) == key and bool(_HEX64.fullmatch(str(z["__tag__"]))))
    except Exception:  # noqa: BLE001 - anything unreadable is not an entry of ours
        return False


def entries() -> list[Path]:
    """Every cache entry in the folder (``is_entry``)."""
    folder = cache_dir()
    if not folder.is_dir():
        return []
    return sorted(p for p in folder.iterdir() if is_entry(p))


def _foreign(folder: Path, own: list) -> int:
    """How many files of the folder are not the cache's (entries, temporary files, secret, numba's folder)."""
    if not folder.is_dir():
        return 0
    names = {p.name for p in own} | {SECRET_NAME, "numba"}
    return sum(1 for p in folder.iterdir() if p.name not in names and not TEMP_NAME.fullmatch(p.name))


def info() -> dict:
    """Folder, number of entries and bytes, by kind, and how many other files the folder holds."""
    kinds: dict = {}
    own = entries()
    for p in own:
        kind = p.name.split("-", 1)[0]
        k = kinds.setdefault(kind, {"entries": 0, "bytes": 0})
        k["entries"] += 1
        k["bytes"] += p.lstat().st_size
    return {"folder": str(cache_dir()), "entries": sum(k["entries"] for k in kinds.values()),
            "bytes": sum(k["bytes"] for k in kinds.values()), "kinds": kinds,
            "other_files": _foreign(cache_dir(), own)}


def _own_secret(path: Path) -> bool:
    try:
        _read_secret(path)
        return True
    except (ValueError, InputError, OSError):
        return False


def clear() -> dict:
    """Delete every entry (and the cache's leftover temporary files, and its secret); return what was
    removed and how many other files were kept."""
    removed, size = 0, 0
    folder = cache_dir()
    own = entries()
    leftovers = [p for p in folder.iterdir() if TEMP_NAME.fullmatch(p.name)] if folder.is_dir() else []
    secret = folder / SECRET_NAME
    if os.path.lexists(secret) and _own_secret(secret):  # not counted: no entry is left for it to check
        try:
            secret.unlink()
        except OSError as exc:
            raise InputError(f"{secret}: cannot remove ({exc.strerror or exc})") from None
    for p in own + leftovers:
        try:
            n = p.lstat().st_size
            p.unlink()
        except IsADirectoryError:
            continue
        except OSError as exc:
            raise InputError(f"{p}: cannot remove ({exc.strerror or exc})") from None
        removed, size = removed + 1, size + n
    kept = _foreign(folder, []) + os.path.lexists(secret)  # a file at the secret's name that is not one
    return {"folder": str(folder), "removed": removed, "bytes": size, "kept": kept}
