"""Pairs lists: which shapes to match with which, as the releases' ``test_pairs.txt`` gives them.

Two shape names a line (tab, space or comma between; ``#`` starts a comment;
blank lines are skipped), the first matched to the second.  A name may carry its
mesh suffix (``cat0.off``), which is dropped.  Read by ``shapecond evaluate
--pairs`` (``evaluation.datasets``), ``shapecond batch --pairs`` and
``sc.match_collection(..., pairs=...)``; the file is read through
``formats.read_text`` (regular files only, size limit, no binary data).
"""

from __future__ import annotations

from pathlib import Path

from ..errors import InputError
from .formats import read_text
from .io import MESH_SUFFIXES


def read_pairs(path) -> list[tuple[str, str]]:
    """The pairs of a pairs list (module docstring).  Refuses a line with another number of names, a
    shape paired with itself and an empty list.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "pairs.txt"
    >>> _ = p.write_text("# source target\\ncat0.off cat1\\ncat0,cat2  # a comma\\n")
    >>> read_pairs(p)
    [('cat0', 'cat1'), ('cat0', 'cat2')]
    """
    out = []
    for i, line in enumerate(read_text(Path(path)).splitlines(), 1):
        words = line.split("#", 1)[0].replace(",", " ").split()
        if not words:
            continue
        if len(words) != 2:
            raise InputError(f"{path}, line {i}: expected two shape names, got {len(words)}")
        a, b = (Path(w).stem if Path(w).suffix.lower() in MESH_SUFFIXES else w for w in words)
        if a == b:
            raise InputError(f"{path}, line {i}: {a} is paired with itself")
        out.append((a, b))
    if not out:
        raise InputError(f"{path}: no pairs (two shape names a line)")
    return out


__all__ = ["read_pairs"]
