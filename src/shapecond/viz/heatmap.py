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
from .render import DEFAULT_VIEWS, guess_up, render_png
from ..symmetry.starts import classical_mds


def _points(shape):
    geom = getattr(shape, "geometry", None)
    if geom is not None and getattr(shape, "samples", None) is not None:
        return np.asarray(geom.vertices, float), geom.faces, np.asarray(shape.samples, np.int64)
    V = classical_mds(np.asarray(shape.D, float))
    return V, None, np.arange(V.shape[0])


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
    V, _, pts = _points(shape)
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
    kk = min(k, src.size)
    d, idx = cKDTree(V[src]).query(V, k=kk)
    if kk == 1:
        d, idx = d[:, None], idx[:, None]
    eps = 1e-9 + 1e-3 * np.median(d[:, -1])
    w = 1.0 / (d + eps) ** 2
    return (w * vals[idx]).sum(axis=1) / w.sum(axis=1)


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
    V, F, pts = _points(shape)
    vv = interpolate_to_vertices(shape, values, method=method)
    finite = vv[np.isfinite(vv)]
    vmax = float(finite.max()) if finite.size else 1.0
    vv = np.where(np.isfinite(vv), vv, vmax)
    if log is None:  # auto: a wide range (one near-symmetry left) would flatten everything else
        log = finite.size > 0 and finite.min() > 0 and vmax / finite.min() > 20.0
    shown = np.log10(vv) if log else vv
    label = f"log10 {colorbar_label}" if log else colorbar_label
    lm_vertices = [int(pts[int(i)]) for i in landmarks]
    up = up or guess_up(getattr(shape, "geometry", None))
    out = render_png(path, V, F, shown, lm_vertices, views=views, up=up, cmap=cmap, title=title,
                     colorbar_label=label, point_size=6.0 if F is not None or len(V) > 2000 else 30.0, fig=fig)
    if ply is not None:
        write_ply(ply, V, F, shown, lm_vertices, cmap=cmap)
    return out
