"""Dense map: every source vertex to a target vertex, from a sample map.

Given the sample map ``t`` (source sample ``x`` -> target sample ``t[x]``) and
the distance rows of both shapes (``sampled.SampledSurface``), each source
vertex ``v`` is sent to a target vertex (the paper matches samples only and is
silent on this step).  Two methods:

``"nearest"``   nearest-sample propagation: ``v`` goes where its nearest source
                sample went.  Error at most the sample error plus about one
                covering radius.
``"distances"`` (default) local distance matching: with ``s`` the nearest
                sample of ``v`` and ``A`` the ``n_anchors`` samples nearest to
                ``s`` (``s`` included), ``v`` goes to the target vertex ``w``
                minimising ``Σ_{a∈A} (d_s(v, a) − d_t(w, t[a]))²``, searched
                among the target vertices whose nearest target sample is one of
                ``t[A]``.  It places ``v`` between the samples instead of on
                one, and the local anchors keep it robust to the metric
                distortion of far distances under non-isometric poses.
                The costs of a cell's vertices against its candidates are
                computed in blocks of source vertices (``COST_ENTRIES``): on a
                non-uniformly meshed shape a cell holds up to 20× the mean
                vertex count (10,188 vertices of 210,163 in 400 cells, TOSCA
                david subdivided), and one matrix of all its costs peaked at
                6.2 GB.  Each vertex's row of costs is the same either way, so
                is its image.

Direction: **source to target**; the result has one entry per source vertex.
"""

from __future__ import annotations

import numpy as np

from shapecond.errors import InputError
from shapecond.matching.sampled import SampledSurface

DENSE_METHODS = ("distances", "nearest")
#: Entries (float64) of one block of ``"distances"``'s cost matrix: 32 MB (module docstring).
COST_ENTRIES = 1 << 22


def dense_map(source: SampledSurface, target: SampledSurface, t, method: str = "distances",
              n_anchors: int = 8) -> np.ndarray:
    """Target vertex (internal index) of every source vertex.

    Parameters
    ----------
    source, target : SampledSurface
        Sampled shapes; ``t`` indexes their samples.
    t : (N_s,) int array
        Sample map, source to target.
    method : {"distances", "nearest"}
    n_anchors : int
        Anchors per neighbourhood for ``"distances"``.

    Returns
    -------
    (n_source_vertices,) int64
    """
    if method not in DENSE_METHODS:
        raise InputError(f"unknown dense method {method!r} ({' or '.join(DENSE_METHODS)})")
    t = np.asarray(t, dtype=np.int64)
    if t.shape != (source.n_samples,) or t.min() < 0 or t.max() >= target.n_samples:
        raise InputError("the sample map does not fit the sampled shapes")
    near_s = source.nearest
    if method == "nearest":
        return target.samples[t[near_s]].astype(np.int64)
    # compare distances in the common unit of the two shapes (sqrt(area)), in float64: scale-free
    Rs, Rt = source.rows, target.rows
    near_t = target.nearest
    by_target_sample = _groups(near_t, target.n_samples)
    by_source_sample = _groups(near_s, source.n_samples)
    D_s = source.D
    k = min(n_anchors, source.n_samples)
    anchors = np.argsort(D_s, axis=1, kind="stable")[:, :k]
    out = np.empty(source.geometry.n_vertices, dtype=np.int64)
    # the cost blocks written into two buffers (fresh arrays of a megabyte each cost a page fault
    # every 4 kB), the cost (|a|² + |b|²) − 2 a·b rounded as before: the same map
    widths = np.bincount(near_t, minlength=target.n_samples)[t[anchors]].sum(axis=1)  # |W| of each cell
    heights = np.minimum(np.bincount(near_s, minlength=source.n_samples),
                         np.maximum(1, COST_ENTRIES // np.maximum(widths, 1)))  # |Vi| of its blocks
    size = int((heights * widths).max())
    products, costs = np.empty(size), np.empty(size)
    for s in range(source.n_samples):
        V = by_source_sample[s]
        if V.size == 0:
            continue
        A = anchors[s]
        W = np.concatenate([by_target_sample[j] for j in t[A]])
        if W.size == 0:
            out[V] = target.samples[t[s]]
            continue
        b = Rt[np.ix_(t[A], W)].astype(np.float64) / target.unit   # (k, |W|)
        bb = (b * b).sum(0)[None, :]
        step = max(1, COST_ENTRIES // W.size)
        for i in range(0, V.size, step):
            Vi = V[i:i + step]
            a = Rs[np.ix_(A, Vi)].astype(np.float64) / source.unit  # (k, |Vi|)
            shape = (Vi.size, W.size)
            ab = np.matmul((2.0 * a).T, b, out=products[:Vi.size * W.size].reshape(shape))  # 2 a·b exactly
            cost = np.add((a * a).sum(0)[:, None], bb, out=costs[:Vi.size * W.size].reshape(shape))
            cost -= ab
            out[Vi] = W[np.argmin(cost, axis=1)]
    return out


def _groups(labels: np.ndarray, n: int) -> list[np.ndarray]:
    """Indices of ``labels`` grouped by value ``0..n-1``."""
    order = np.argsort(labels, kind="stable")
    bounds = np.searchsorted(labels[order], np.arange(n + 1))
    return [order[bounds[i]:bounds[i + 1]] for i in range(n)]
