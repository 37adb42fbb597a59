"""Heat maps on the mesh: per-sample values spread to every vertex (paper Figures 1, 4).

The CNBS heat map gives one number per sample: the symmetry score with
that sample fixed as a landmark.  To draw it on the surface every vertex needs a
value.  Two interpolations are offered:

* ``"nearest"``: the value of the closest sample (``MetricShape.nearest`` when the
  values cover all M points of Y, otherwise the Euclidean-closest sample of X);
  piecewise constant (Voronoi cells), honest about the resolution.
* ``"smooth"`` (default): inverse-distance weighting over the ``k = 4`` Euclidean-
  nearest samples, weights ``1 / (d + ε)²``.  Euclidean rather than geodesic
  neighbours: this is only used for pictures, and with k = 4 neighbours at the
  sampling scale bleeding between touching parts is at most one cell wide.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..errors import InputError
from .ply import write_ply
from .render import render_scene
from .scene import DEFAULT_VIEWS, heatmap_scene, shape_points


def idw(V: np.ndarray, sources, values, k: int = 4) -> np.ndarray:
    """Inverse-distance weighting of ``values`` at vertices ``sources`` over the ``k`` Euclidean-nearest
    of them, weights ``1 / (d + ε)²`` (the ``"smooth"`` interpolation); every value must be finite."""
    src = np.asarray(sources, dtype=np.int64)
    vals = np.asarray(values, dtype=float)
    kk = min(k, src.size)
    d, idx = cKDTree(V[src]).query(V, k=kk)
    if kk == 1:
        d, idx = d[:, None], idx[:, None]
    eps = 1e-9 + 1e-3 * np.median(d[:, -1])
    w = 1.0 / (d + eps) ** 2
    return (w * vals[idx]).sum(axis=1) / w.sum(axis=1)


def interpolate_to_vertices(shape, values, method: str = "smooth", k: int = 4) -> np.ndarray:
    """Spread per-sample ``values`` ((N,) over X or (M,) over Y) to every vertex.

    Returns an (n_vertices,) array (for a matrix input: one value per point of Y).
    Non-finite values (σ = ∞) are kept as ``inf`` by ``"nearest"``; ``"smooth"``
    treats them as the largest finite value so the colour scale stays usable.
    """
    values = np.asarray(values, dtype=float)
    n, m = int(shape.n_samples), int(np.asarray(shape.D).shape[0])
    if values.shape not in ((n,), (m,)):
        raise InputError(f"values must have {n} (samples) or {m} (targets) entries, got {values.shape}")
    V, _, pts, _ = shape_points(shape)
    src = pts[: values.size]
    if method == "nearest":
        near = getattr(shape, "nearest", None)
        if values.size == m and near is not None and getattr(shape, "geometry", None) is not None:
            return values[np.asarray(near)]
        _, idx = cKDTree(V[src]).query(V)
        return values[idx]
    if method != "smooth":
        raise InputError(f"unknown interpolation {method!r} (nearest or smooth)")
    vals = values.copy()
    finite = np.isfinite(vals)
    if not finite.any():
        return np.full(V.shape[0], np.inf)
    vals[~finite] = vals[finite].max()
    return idw(V, src, vals, k)


def render_heatmap_png(shape, values, path, *, landmarks=(), up: str | None = None, views=DEFAULT_VIEWS,
                       method: str = "smooth", cmap: str = "turbo", title: str | None = None,
                       colorbar_label: str = "σ with the point fixed", ply: str | None = None,
                       log: bool | None = None, fig=None):
    """Draw a per-sample heat map on the shape (Figure 1/4 style), optionally also as PLY.

    Parameters
    ----------
    shape : MetricShape
    values : (N,) or (M,) array
        One value per sample (e.g. the CNBS heat map) or per point of Y.
    path : str or path-like
        PNG to write.
    landmarks : sequence of int
        Sample indices already chosen, drawn as markers (first three red, then green).
    up : {"x", "y", "z"} or None
        Vertical axis; None guesses it (``render.guess_up``).
    ply : str or None
        Also write a PLY with the interpolated colours there.
    log : bool or None
        Colour by log10 of the values; None: when max/min > 20 (e.g. points near a
        mirror plane keep huge scores and would flatten the rest of the scale).
        Infinite values are drawn with the largest finite one.
    fig : matplotlib Figure or None
        Draw onto it; with ``path=None`` the Figure is returned (no PNG written).
    """
    scene = heatmap_scene(shape, values, landmarks=landmarks, up=up, views=views, method=method, cmap=cmap,
                          title=title, colorbar_label=colorbar_label, log=log)
    out = render_scene(path, scene, fig=fig)
    if ply is not None:
        layer = scene.layers[0]  # the PNG's colours, in the input's coordinates
        write_ply(ply, shape_points(shape)[0], scene.faces, layer.rgba, layer.landmarks)
    return out
