"""Pictures: headless PNG renderings (several views), coloured PLY files and HTML pages.

* ``scene``: the render data every picture is drawn from (display frame, colourings,
  colour bars, landmark styles, views, shading): one place computes them.
* ``html`` / ``pages``: self-contained HTML pages with a 3-D viewer of the same scenes
  (``--html``, ``result.to_html``, ``report.html``, ``demo.html``).

* ``render.render_png`` / ``render.render_rows``: a shape with per-vertex values and
  landmarks (paper Figure 6 colours) from several views, with a colour bar.
* ``ply.write_ply``: per-vertex colours for MeshLab or Blender.
* ``witness.render_witness_png``: the witness map of the symmetry score on the shape.
* ``heatmap.render_heatmap_png``: per-sample values (the CNBS heat map, Figures 1, 4)
  interpolated to every vertex.
"""

from .heatmap import render_heatmap_png
from .scene import DEFAULT_VIEWS, interpolate_to_vertices
from .ply import write_ply
from .render import render_png, render_rows
from .witness import render_witness_png

__all__ = ["DEFAULT_VIEWS", "interpolate_to_vertices", "render_heatmap_png", "render_png",
           "render_rows", "render_witness_png", "write_ply"]
