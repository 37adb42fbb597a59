"""Which shapes a batch scores: files, folders (recursively) and glob patterns, with content hashes."""

from __future__ import annotations

import glob
import hashlib
import os
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from ..checks import open_regular
from ..errors import InputError
from ..shapes.io import MESH_SUFFIXES

#: Suffixes collected from folders: what ``load_input`` reads, except ``.txt``
#: (folders hold text files that are not point clouds; name those explicitly)
#: and ``.tri`` (the ``.vert`` of a TOSCA pair stands for the pair).
FOLDER_SUFFIXES = frozenset(MESH_SUFFIXES | {".vert", ".xyz", ".npy"})


def _walk(folder: Path) -> list[str]:
    """Shape files below ``folder``; links to folders are not followed (a loop could not end), with a warning."""
    import warnings

    found = []
    for root, dirs, files in os.walk(folder):
        links = sorted(d for d in dirs if not d.startswith(".") and os.path.islink(os.path.join(root, d)))
        for d in links:
            warnings.warn(f"{os.path.join(root, d)}: a link to a folder, not followed (name the folder itself "
                          "to score its shapes)")
        dirs[:] = sorted(d for d in dirs if not d.startswith(".") and d not in links)
        found += [os.path.join(root, f) for f in sorted(files)
                  if not f.startswith(".") and Path(f).suffix.lower() in FOLDER_SUFFIXES]
    return found


def expand_inputs(specs) -> list[str]:
    """Absolute paths (or ``demo:`` specifications) of the shapes named by ``specs``, in order, once each.

    A folder contributes every file below it whose suffix is in ``FOLDER_SUFFIXES``;
    a glob pattern (``*``, ``?``, ``[``, ``**``) its matches (folders among them
    are walked); any other name is taken as a file, even one that does not
    exist (it becomes an error row).  InputError when nothing is found.
    """
    out, seen = [], set()
    for spec in specs:
        spec = str(spec)
        if spec.startswith("demo:"):
            names = [spec]
        elif Path(spec).is_dir():
            names = _walk(Path(spec))
            if not names:
                raise InputError(f"{spec}: no shape files in this folder "
                                 f"({', '.join(sorted(FOLDER_SUFFIXES))})")
        elif glob.has_magic(spec):
            names = []
            for match in sorted(glob.glob(spec, recursive=True)):
                names += _walk(Path(match)) if Path(match).is_dir() else [match]
            if not names:
                raise InputError(f"{spec}: no file matches this pattern")
        else:
            names = [spec]
        for name in names:
            name = name if name.startswith("demo:") else os.path.abspath(name)
            if name not in seen:
                seen.add(name)
                out.append(name)
    if not out:
        raise InputError("no input shapes given")
    return out


def content_hash(spec: str) -> str:
    """SHA-256 of a shape's bytes (``.vert`` then ``.tri`` for a TOSCA pair; the text of a
    ``demo:`` specification).

    ``InputError`` when a file is missing, unreadable or not a regular file: a FIFO
    or a device (``/dev/zero``) is refused before it is read (``checks.open_regular``),
    so hashing never blocks or runs forever.
    """
    h = hashlib.sha256()
    if spec.startswith("demo:"):
        h.update(spec.encode())
        return h.hexdigest()
    path = Path(spec)
    parts = [path, path.with_suffix(".tri")] if path.suffix.lower() == ".vert" else [path]
    for part in parts:
        fd = open_regular(part)
        try:
            with os.fdopen(fd, "rb") as fh:
                for chunk in iter(lambda: fh.read(1 << 20), b""):
                    h.update(chunk)
        except OSError as exc:
            raise InputError(f"{part}: cannot read ({exc.strerror or exc})") from None
    return h.hexdigest()


def _hash_or_reason(spec: str) -> tuple[str | None, str | None]:
    try:
        return content_hash(spec), None
    except InputError as exc:
        return None, str(exc).splitlines()[0]


def content_hashes(specs, threads: int = 8) -> list[tuple[str | None, str | None]]:
    """``(content_hash, None)`` of every spec, or ``(None, why it cannot be read)``; read by a few
    threads (hashing releases the GIL)."""
    with ThreadPoolExecutor(max_workers=threads) as pool:
        return list(pool.map(_hash_or_reason, specs))
