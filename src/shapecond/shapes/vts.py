"""Ground-truth correspondence files of the remeshed benchmarks (``corres/NAME.vts``).

The remeshed FAUST and SCAPE releases, SHREC'19, SMAL_r and DT4D-H give every
shape its own triangulation and one ``.vts`` file beside it: line ``j`` holds the
**1-based** id of the vertex of this mesh at reference point ``j`` of the
dataset's template.  Two shapes ``a`` and ``b`` of a dataset correspond at
``(vts_a[j], vts_b[j])`` for every ``j``; a vertex may stand for several
reference points, so ids repeat.

``read_vts`` reads one such file strictly: one integer per non-empty line, every
id in ``1..n_vertices``.  A ``0`` means the file is 0-based by mistake and is
refused as such, as are fractional, negative or non-numeric lines, several ids
on one line, an empty file, binary content and anything that is not a regular
file.  The returned ids are 0-based.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError
from .formats import read_text


def read_vts(path, n_vertices: int | None = None, name: str | None = None) -> np.ndarray:
    """The 0-based vertex id of every reference point in a ``.vts`` file (module docstring).

    Parameters
    ----------
    path : the ``.vts`` file.
    n_vertices : vertex count of the mesh it belongs to (ids must be at most this); None: unchecked.
    name : how to name the file in messages (default: its file name).

    Returns
    -------
    (R,) int64, ids in ``0..n_vertices − 1``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "a.vts"
    >>> _ = p.write_text("3\\n1\\n3\\n")
    >>> read_vts(p, n_vertices=3).tolist()
    [2, 0, 2]
    """
    path = Path(path)
    label = name or path.name
    tokens = [(i + 1, ln.split()) for i, ln in enumerate(read_text(path).splitlines()) if ln.strip()]
    if not tokens:
        raise InputError(f"{label}: no reference points (the file holds no ids)")
    ids = np.empty(len(tokens), dtype=np.int64)
    for j, (line, words) in enumerate(tokens):
        if len(words) != 1 or not (words[0].isascii() and words[0].isdigit()):  # '²'.isdigit() is True
            raise InputError(f"{label}, line {line}: expected one positive integer vertex id, got "
                             f"{' '.join(words)[:40]!r}")
        if len(words[0].lstrip("0")) > 18:  # beyond int64, and beyond any mesh
            raise InputError(f"{label}, line {line}: vertex id {words[0][:30]} is out of range")
        ids[j] = int(words[0])
    if ids.min() == 0:
        raise InputError(f"{label}, line {tokens[int(np.argmin(ids))][0]}: vertex id 0, but .vts ids are "
                         "1-based (is the file 0-based by mistake?)")
    if n_vertices is not None and ids.max() > n_vertices:
        j = int(np.argmax(ids))
        raise InputError(f"{label}, line {tokens[j][0]}: vertex id {ids[j]} is out of range for a mesh of "
                         f"{n_vertices} vertices (ids are 1..{n_vertices})")
    return ids - 1
