"""The witness map drawn on the shape.

The witness T of the global symmetry score (paper Eq. 5) is the near-isometry that
makes the shape hard to match.  The picture has two rows of views:

1. *reference*: every vertex coloured by its own position (RGB from the coordinates,
   normalised to the bounding box), so that each region has its own colour;
2. *witness*: every vertex coloured by the reference colour of the image of its
   nearest sample, T(x).  Where T is the identity the two rows agree; a mirror
   ambiguity shows up as the left/right colours swapped.  Segments join each moved
   sample x to T(x) (the ``max_segments`` farthest moves, straight chords in space),
   and fixed landmarks are marked as in Figure 6.

A distance-matrix input has no geometry: its points are then placed by classical
multidimensional scaling of ``D`` (3 leading eigenvectors) and drawn as a point cloud.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..errors import InputError
from ..symmetry.starts import classical_mds
from .render import DEFAULT_VIEWS, guess_up, render_rows


def position_colours(V: np.ndarray) -> np.ndarray:
    """RGB in [0.1, 0.95] from coordinates normalised to the bounding box."""
    lo, hi = V.min(axis=0), V.max(axis=0)
    c = (V - lo) / np.where(hi > lo, hi - lo, 1.0)
    return 0.1 + 0.85 * c


def render_witness_png(shape, witness, path, *, landmarks=(), up: str | None = None,
                       views=DEFAULT_VIEWS, max_segments: int = 80, title: str | None = None, fig=None):
    """Draw a witness map on its shape (see the module docstring).

    Parameters
    ----------
    shape : MetricShape
        Needs ``D`` (M, M), ``n_samples`` and, for meshes and point clouds,
        ``geometry`` and ``samples`` (internal vertex ids of the M points).
    witness : (N,) int array
        ``witness[i] = j``: sample i is sent to point j of Y (``j < M``).
    path : str or path-like
        PNG to write.
    landmarks : sequence of int
        Sample indices fixed by the map, drawn as markers.
    up : {"x", "y", "z"} or None
        Vertical axis of the data; None guesses it (``render.guess_up``: TOSCA z,
        the generated animal y).
    max_segments : int
        Number of the longest moves drawn as segments.

    fig : matplotlib Figure or None
        Draw onto it; with ``path=None`` the Figure is returned, nothing written.

    Returns
    -------
    str (the path written) or Figure (``path=None``)
    """
    D = np.asarray(shape.D, dtype=float)
    n = int(shape.n_samples)
    t = np.asarray(witness, dtype=np.int64)
    if t.shape != (n,) or t.min() < 0 or t.max() >= D.shape[0]:
        raise InputError(f"witness must be {n} indices into range({D.shape[0]})")
    geom = getattr(shape, "geometry", None)
    if geom is not None and getattr(shape, "samples", None) is not None:
        V = np.asarray(geom.vertices, dtype=float)
        F = geom.faces
        pts = np.asarray(shape.samples, dtype=np.int64)  # vertex of each point of Y
    else:
        V = classical_mds(D)
        F = None
        pts = np.arange(D.shape[0])
    ref = position_colours(V)
    # every vertex -> nearest sample of X (Euclidean; only used for colouring)
    _, near = cKDTree(V[pts[:n]]).query(V)
    moved_col = ref[pts[t[near]]]
    disp = D[np.arange(n), t]
    order = np.argsort(-disp)[:max_segments]
    order = order[disp[order] > 0]
    a, b = V[pts[order]], V[pts[t[order]]]
    lm_vertices = [int(pts[int(i)]) for i in landmarks]

    def segments(ax, project):
        pa, pb = project(a), project(b)
        for p, q in zip(pa, pb):
            ax.plot([p[0], q[0]], [p[1], q[1]], color="black", lw=0.7, alpha=0.7, zorder=4)
        if len(pa):
            ax.scatter(pb[:, 0], pb[:, 1], s=4, c="black", zorder=4)

    moved = int(np.count_nonzero(disp > 0))
    rows = [
        dict(values=ref, landmarks=lm_vertices, label="reference (colour = position)"),
        dict(values=moved_col, landmarks=lm_vertices, extra=segments,
             label=f"witness T ({moved}/{n} samples moved)"),
    ]
    point_size = 6.0 if F is not None or len(V) > 2000 else 30.0
    up = up or guess_up(geom)
    return render_rows(path, V, F, rows, views=views, up=up, title=title, point_size=point_size, fig=fig)
