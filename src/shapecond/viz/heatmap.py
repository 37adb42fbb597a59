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


from .ply import write_ply
from .render import render_scene
from .scene import HeatMapStyle, heatmap_scene, shape_points


def render_heatmap_png(shape, values, path, *, landmarks=(), ply: str | None = None, fig=None,
                       style: HeatMapStyle = HeatMapStyle()):
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
    ply : str or None
        Also write a PLY with the interpolated colours there.
    fig : matplotlib Figure or None
        Draw onto it; with ``path=None`` the Figure is returned (no PNG written).
    style : HeatMapStyle (``up``, ``views``, ``title``, the interpolation ``method``, ``cmap``,
        ``colorbar_label`` and ``log``).
    """
    scene = heatmap_scene(shape, values, landmarks=landmarks, style=style)
    out = render_scene(path, scene, fig=fig)
    if ply is not None:
        layer = scene.layers[0]  # the PNG's colours, in the input's coordinates
        write_ply(ply, shape_points(shape)[0], scene.faces, layer.rgba, layer.landmarks)
    return out
