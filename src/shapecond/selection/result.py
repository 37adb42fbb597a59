"""The result of a landmark selection and the conversions shared by every method.

Landmarks are chosen among the samples X of a ``MetricShape`` (sample indices,
which the symmetry score fixes, T(l) = l) and reported in the input's own ids
(file vertex ids for a mesh or point cloud, row indices for a distance matrix).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..jsonable import jsonable
from ..errors import InputError


@dataclass(frozen=True)
class LandmarkSelection:
    """Landmarks in selection order with the symmetry score after each one.

    Attributes
    ----------
    landmarks : tuple of int
        The input's ids (file vertex ids; matrix rows) of the landmarks, in order.
    sample_indices : tuple of int
        The same landmarks as indices of the samples X.
    vertices : tuple of int
        Internal vertex indices (for drawing); equal to ``landmarks`` for a matrix.
    scores : tuple of (float or None)
        σ (lower bound with witness, paper Eq. 5) with the first i+1 landmarks
        fixed: the "vector of symmetry scores" of Section 6.  None where not computed.
    method : str
    seconds : float
    initial_score : float or None
        σ with none of the selected landmarks fixed.
    heat_maps : tuple of arrays
        CNBS only: per step, σ with each sample fixed (inf-safe); empty otherwise.
    score : "sigma" (σ, Eq. 5) or "scale" (δ(ε), ``shapecond.symmetry.scale``): what
        ``scores`` and ``initial_score`` are.
    """

    landmarks: tuple
    sample_indices: tuple
    vertices: tuple
    scores: tuple
    method: str
    seconds: float
    initial_score: float | None = None
    heat_maps: tuple = field(default=(), repr=False)
    score: str = "sigma"
    shape: object = field(default=None, repr=False, compare=False)  # the MetricShape they were chosen on

    def to_dict(self) -> dict:
        """JSON-ready dict (keys of the CLI: landmarks, scores, method, seconds, ...)."""
        return jsonable({
            "landmarks": [int(v) for v in self.landmarks],
            "scores": [None if s is None else float(s) for s in self.scores],
            "method": self.method,
            "seconds": float(self.seconds),
            "sample_indices": [int(v) for v in self.sample_indices],
            "initial_score": None if self.initial_score is None else float(self.initial_score),
            "score": self.score,
        })


def sample_of_vertex(shape, vertex: int) -> int:
    """Sample index (into X) standing for internal vertex ``vertex``.

    The vertex itself when it is a sample; otherwise the sample closest (in D) to the
    point of Y nearest to the vertex (``MetricShape.nearest``).  For a matrix input
    ``vertex`` is a row index of the original matrix.
    """
    n = int(shape.n_samples)
    pos = np.flatnonzero(np.asarray(shape.samples[:n]) == int(vertex))
    if pos.size:
        return int(pos[0])
    if shape.geometry is None:
        raise InputError(f"row {int(vertex)} is not one of the samples")
    if shape.nearest is None:
        raise InputError("this shape has no nearest-point map; cannot place a landmark off the samples")
    if not 0 <= int(vertex) < len(shape.nearest):
        raise InputError(f"vertex {int(vertex)} out of range")
    j = int(shape.nearest[int(vertex)])
    return j if j < n else int(np.argmin(shape.D[j, :n]))


def make_result(shape, sample_indices, scores, method, seconds, initial_score=None, heat_maps=(),
                score="sigma"):
    """Assemble a ``LandmarkSelection`` from sample indices (adds ids and vertices)."""
    s = [int(i) for i in sample_indices]
    verts = [int(shape.samples[i]) for i in s]
    ids = [int(shape.sample_ids[i]) for i in s]
    clean = []
    for v in scores:
        clean.append(None if v is None else (math.inf if not math.isfinite(v) and v > 0 else float(v)))
    return LandmarkSelection(tuple(ids), tuple(s), tuple(verts), tuple(clean), method, float(seconds),
                          initial_score, tuple(heat_maps), score, shape)
