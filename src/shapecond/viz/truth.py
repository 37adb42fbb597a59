"""The ground truth a match page shows the error against (``match --html --truth``).

Three forms: ``"same-ids"`` (shapes with one vertex order), a map file (line i:
the true target vertex id of source vertex i, ``-1`` and only ``-1`` for none),
or two ``.vts`` files of a remeshed release (``shapes.vts``: the source's and the
target's vertex at each reference point; the truth is then known at the source's
reference vertices).  Read up front through the regular-file check, checked
against both shapes before any matching.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..checks import MAX_ID
from ..errors import InputError
from ..shapes.formats import read_text
from ..shapes.vts import read_vts


@dataclass(frozen=True)
class ReferenceTruth:
    """The ground truth of a remeshed release (``shapes.vts``): 0-based input vertex ids of the source
    (``source``) and of the target (``target``) at each reference point; equal rows correspond."""

    source: np.ndarray
    target: np.ndarray
    names: tuple = ("source .vts", "target .vts")


def read_truth(spec):
    """``--truth`` read and checked before any work: None, ``"same-ids"``, a ``ReferenceTruth`` from
    ``"SOURCE.vts,TARGET.vts"``, or the ids of a map file (line i: the target vertex id of source vertex
    i, -1 for none; one integer per line, ``#`` comments).  Files must be regular files (a FIFO or
    ``/dev/zero`` is refused without reading); ``InputError`` for anything else."""
    if spec is None or (isinstance(spec, str) and spec == "same-ids"):
        return spec
    text = str(spec)
    if not text.strip():
        raise InputError("--truth: an empty file name")
    parts = text.split(",")
    if not Path(text).exists() and len(parts) == 2 and all(p.lower().endswith(".vts") for p in parts):
        a, b = read_vts(parts[0]), read_vts(parts[1])
        if a.size != b.size:
            raise InputError(f"--truth: {parts[0]} has {a.size} reference points but {parts[1]} has {b.size}; "
                             "give the two .vts files of one release")
        return ReferenceTruth(a, b, (Path(parts[0]).name, Path(parts[1]).name))
    if not Path(text).exists() and "," in text:
        raise InputError(f"--truth {text}: give a map file, 'same-ids' or two .vts files SOURCE.vts,TARGET.vts")
    return _read_map(Path(text))


def _read_map(path: Path) -> np.ndarray:
    """The ids of a ground-truth map file (``read_truth``)."""
    ids = []
    for number, line in enumerate(read_text(path).splitlines(), 1):
        words = line.split("#", 1)[0].split()
        if not words:
            continue
        word = words[0]
        digits = word[1:] if word.startswith("-") else word
        if len(words) != 1 or not (digits.isascii() and digits.isdigit()):
            raise InputError(f"{path.name}, line {number}: not a ground-truth map line (one integer target "
                             f"vertex id per line), got {line.strip()[:40]!r}")
        value = int(word)
        if value < -1:
            raise InputError(f"{path.name}, line {number}: target vertex id {value}; only -1 means 'no true image'")
        if value > MAX_ID:
            raise InputError(f"{path.name}, line {number}: target vertex id {word[:30]} is too large")
        ids.append(value)
    if not ids:
        raise InputError(f"{path.name}: no ids in the ground-truth map")
    return np.asarray(ids, dtype=np.int64)


def truth_map(truth, src, tgt) -> np.ndarray:
    """The ground truth as the target's internal vertex per source internal vertex (-1: unknown).

    ``truth``: ``"same-ids"``, a ``ReferenceTruth`` (known at the source's reference vertices only; a
    vertex at several reference points takes the first), a path or ``"A.vts,B.vts"`` (``read_truth``),
    or one target id per source id (-1: no true image).  ``InputError`` when it does not fit the shapes.
    """
    if isinstance(truth, (str, Path)) and truth != "same-ids":
        truth = read_truth(truth)
    n_ids = int(src.ids.max()) + 1
    t = np.full(src.n_vertices, -1, dtype=np.int64)
    if isinstance(truth, ReferenceTruth):
        for ids, g, name in ((truth.source, src, truth.names[0]), (truth.target, tgt, truth.names[1])):
            if ids.size and int(ids.max()) > int(g.ids.max()):
                raise InputError(f"--truth {name}: vertex id {int(ids.max()) + 1} (1-based) is out of range for "
                                 f"{g.name} ({int(g.ids.max()) + 1} vertices)")
        s_int, t_int = _internal(src, truth.source), _internal(tgt, truth.target)
        vertices, first = np.unique(s_int, return_index=True)  # the first reference point of a vertex wins
        t[vertices] = t_int[first]
        return t
    if isinstance(truth, str):  # "same-ids": the identity, a truth only for one mesh deformed
        if not src.shares_vertex_order(tgt):
            raise InputError(f"--truth same-ids: {src.name} and {tgt.name} do not share their vertex order "
                             "(vertex ids and triangles), so the identity is not their ground truth")
        truth = np.arange(n_ids)
    truth = np.asarray(truth)
    if truth.ndim != 1 or truth.size < n_ids or not np.issubdtype(truth.dtype, np.integer):
        raise InputError(f"the ground truth needs one target vertex id per source vertex id "
                         f"(0..{n_ids - 1}), got {truth.shape[0] if truth.ndim else 0}")
    if truth.size and int(truth.min()) < -1:
        raise InputError(f"ground-truth id {int(truth.min())}: only -1 means 'no true image'")
    known = truth[src.ids] >= 0  # -1: a source vertex without a true image
    t[known] = _internal(tgt, truth[src.ids][known])
    return t


def _internal(g, ids) -> np.ndarray:
    try:
        return g.to_internal(ids)
    except InputError as exc:
        raise InputError(f"the ground truth: {exc}") from None
