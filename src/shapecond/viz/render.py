"""Headless pictures of a mesh or point cloud with per-vertex values.

One picture holds several views of the same shape side by side, one shared colour
bar, and landmark markers in the style of the paper's Figure 6 (the first three red,
the rest green, numbered in order).  Rendering is a painter's algorithm written on
top of matplotlib's 2-D ``PolyCollection``: the shape is rotated into each view,
projected orthographically, faces are sorted back to front and shaded by a
headlight (Lambert, ``0.35 + 0.65 |n·v|``).  This is much faster than ``mplot3d``
(100k faces in a few seconds) and needs no display.

Figures are ``matplotlib.figure.Figure`` objects made without pyplot, so drawing
never changes the caller's backend (inline plots in Jupyter keep working):
``draw_rows`` draws onto a Figure the caller passes (or a new one, returned);
``render_png``/``render_rows`` write a PNG with the atomic writer.

Values are either scalars ``(n,)`` mapped through a colour map, or colours
``(n, 3)``/``(n, 4)`` in [0, 1].  Faces take the mean of their vertices' values.
"""

from __future__ import annotations

import matplotlib
import numpy as np
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure

from ..errors import InputError
from ..output import atomic_open

#: Default views as (elevation, azimuth) in degrees around the up axis: three-quarter
#: front, both sides (a mirror ambiguity shows up as a left/right difference) and top.
DEFAULT_VIEWS = ((20.0, -60.0), (5.0, 0.0), (5.0, 180.0), (80.0, 0.0))

_AXES = {"x": 0, "y": 1, "z": 2}


def _up_frame(up: str, V: np.ndarray | None = None) -> np.ndarray:
    """Rotation taking the data's ``up`` axis to z (rows: new x, y, z axes).

    Of the two horizontal axes, the one along which the shape is longer becomes the
    new y, so that azimuth 0 and 180 look at the shape's broad sides (an animal's
    flanks, a standing human's front and back) whatever the file's convention.
    """
    if up not in _AXES:
        raise InputError(f"up axis must be one of x, y, z, got {up!r}")
    k = _AXES[up]
    z = np.eye(3)[k]
    a, b = np.eye(3)[(k + 1) % 3], np.eye(3)[(k + 2) % 3]
    if V is not None and np.ptp(V @ a) > np.ptp(V @ b):
        a, b = b, a
    y = b
    x = np.cross(y, z)
    return np.stack([x, y, z])


def guess_up(geometry) -> str:
    """Vertical axis of a shape: ``"y"`` for the generated animal, ``"z"`` otherwise (TOSCA)."""
    return "y" if getattr(geometry, "name", "") == "animal" else "z"


def view_rotation(elev: float, azim: float) -> np.ndarray:
    """Rotation (3, 3) whose rows are screen-right, screen-up and toward-viewer.

    The camera sits at elevation ``elev`` above the xy-plane and azimuth ``azim``
    around the z axis (matplotlib's convention), looking at the origin.
    """
    e, a = np.radians(elev), np.radians(azim)
    toward = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    right = np.array([-np.sin(a), np.cos(a), 0.0])
    upv = np.cross(toward, right)
    return np.stack([right, upv, toward])


def _vertex_colours(values, n, cmap, vmin, vmax):
    """Return (n, 4) RGBA colours and the ScalarMappable (or None for direct colours)."""
    if values is None:
        return np.tile([0.75, 0.75, 0.75, 1.0], (n, 1)), None
    v = np.asarray(values, dtype=float)
    if v.ndim == 2 and v.shape[0] == n and v.shape[1] in (3, 4):
        rgba = np.ones((n, 4))
        rgba[:, : v.shape[1]] = np.clip(v, 0.0, 1.0)
        return rgba, None
    if v.shape != (n,):
        raise InputError(f"values must have shape ({n},), ({n}, 3) or ({n}, 4), got {v.shape}")
    finite = v[np.isfinite(v)]
    lo = float(np.min(finite)) if vmin is None and finite.size else (vmin if vmin is not None else 0.0)
    hi = float(np.max(finite)) if vmax is None and finite.size else (vmax if vmax is not None else 1.0)
    if hi <= lo:
        hi = lo + 1.0
    norm = matplotlib.colors.Normalize(lo, hi)
    sm = matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap)
    rgba = sm.to_rgba(np.where(np.isfinite(v), v, hi))
    return np.asarray(rgba, dtype=float), sm


def new_figure(figsize=(6.4, 4.8)) -> Figure:
    """A matplotlib Figure that belongs to no pyplot state (the backend is untouched)."""
    return Figure(figsize=figsize)


def save_figure(fig: Figure, path, dpi: int = 110, bbox_inches="tight") -> str:
    """Write ``fig`` as PNG to ``path`` with the atomic writer."""
    with atomic_open(path) as fh:
        fig.savefig(fh, format="png", dpi=dpi, bbox_inches=bbox_inches)
    return str(path)


def _draw_view(ax, V, F, rgba, R, landmarks, vnormals, fnormals, point_size, labels):
    P = V @ R.T  # screen x, screen y, depth (larger = nearer)
    if F is not None:
        depth = P[F, 2].mean(axis=1)
        order = np.argsort(depth)
        fc = rgba[F].mean(axis=1)
        fn = fnormals @ R.T
        ln = np.linalg.norm(fn, axis=1)
        shade = 0.35 + 0.65 * np.abs(fn[:, 2]) / np.where(ln > 0, ln, 1.0)
        fc[:, :3] *= shade[:, None]
        polys = P[F[order]][:, :, :2]
        pc = PolyCollection(polys, facecolors=fc[order], edgecolors="none", antialiaseds=False)
        ax.add_collection(pc)
    else:
        order = np.argsort(P[:, 2])
        ax.scatter(P[order, 0], P[order, 1], c=rgba[order], s=point_size, linewidths=0)
    for i, vid in enumerate(landmarks):
        colour = "red" if i < 3 else "limegreen"
        facing = True
        if vnormals is not None:
            facing = (vnormals[vid] @ R[2]) > -0.2
        ax.scatter(
            [P[vid, 0]], [P[vid, 1]], s=70 if facing else 35, c=colour if facing else "none",
            edgecolors="black" if facing else colour, linewidths=1.0, zorder=5,
        )
        if labels and facing:
            ax.annotate(str(i + 1), (P[vid, 0], P[vid, 1]), xytext=(4, 4),
                        textcoords="offset points", fontsize=7, zorder=6)
    pad = 0.03 * np.ptp(P[:, :2], axis=0).max()
    ax.set_xlim(P[:, 0].min() - pad, P[:, 0].max() + pad)
    ax.set_ylim(P[:, 1].min() - pad, P[:, 1].max() + pad)
    ax.set_aspect("equal")
    ax.axis("off")


def render_png(
    path,
    vertices,
    faces=None,
    values=None,
    landmarks=(),
    *,
    views=DEFAULT_VIEWS,
    up: str = "z",
    title: str | None = None,
    cmap: str = "viridis",
    vmin: float | None = None,
    vmax: float | None = None,
    colorbar_label: str | None = None,
    point_size: float = 6.0,
    labels: bool = True,
    extra=None,
    dpi: int = 110,
    fig=None,
):
    """Render a shape from several views into one PNG (written atomically), or onto a Figure.

    Parameters
    ----------
    path : str or path-like
        Output file (``.png``).
    vertices : (n, 3) array
    faces : (m, 3) int array or None
        ``None`` draws a point cloud.
    values : (n,) scalars, (n, 3|4) colours in [0, 1], or None (grey)
        Per-vertex values; scalars get a colour bar.
    landmarks : sequence of int
        Vertex indices (internal, 0-based) in selection order; the first three are
        drawn red, the rest green (paper Figure 6), numbered from 1.  Landmarks on
        the far side of a view are drawn as hollow circles.
    views : sequence of (elevation, azimuth) in degrees
        Camera positions around the ``up`` axis (see ``view_rotation``).
    up : {"x", "y", "z"}
        The data's vertical axis (TOSCA meshes: ``"z"``).
    extra : callable or None
        ``extra(ax, project)`` is called for every view after the shape is drawn,
        with ``project(points (k, 3)) -> (k, 3)`` taking points in the input's
        coordinates to screen x, screen y and depth; used by the witness picture.

    fig : matplotlib Figure or None
        Draw onto this Figure; with ``path=None`` the Figure (``fig`` or a new
        one) is returned instead of writing a file.

    Returns
    -------
    str (the path written) or Figure (``path=None``)
    """
    row = dict(values=values, landmarks=landmarks, extra=extra, cmap=cmap, vmin=vmin,
               vmax=vmax, colorbar_label=colorbar_label, label=None)
    return render_rows(path, vertices, faces, [row], views=views, up=up, title=title,
                       point_size=point_size, labels=labels, dpi=dpi, fig=fig)


def render_rows(path, vertices, faces, rows, *, views=DEFAULT_VIEWS, up: str = "z",
                title: str | None = None, point_size: float = 6.0, labels: bool = True,
                dpi: int = 110, fig=None):
    """Several colourings of one shape, one row of views each, in one PNG (or Figure).

    ``rows`` is a list of dicts with the keys of ``render_png`` (``values``,
    ``landmarks``, ``extra``, ``cmap``, ``vmin``, ``vmax``, ``colorbar_label``) and
    ``label`` (a caption written left of the row).  Each row with scalar values gets
    its own colour bar.  With ``path=None`` the Figure is returned (see ``render_png``).
    """
    fig = draw_rows(fig, vertices, faces, rows, views=views, up=up, title=title, point_size=point_size,
                    labels=labels)
    return fig if path is None else save_figure(fig, path, dpi)


def draw_rows(fig, vertices, faces, rows, *, views=DEFAULT_VIEWS, up: str = "z", title: str | None = None,
              point_size: float = 6.0, labels: bool = True) -> Figure:
    """Draw the rows of ``render_rows`` onto ``fig`` (a new Figure when None) and return it."""
    from ..deformation.energy import vertex_normals

    V = np.asarray(vertices, dtype=float)
    if V.ndim != 2 or V.shape[1] != 3 or V.shape[0] == 0:
        raise InputError("vertices must be a non-empty (n, 3) array")
    n = V.shape[0]
    F = None if faces is None else np.asarray(faces, dtype=np.int64)
    if F is not None and (F.ndim != 2 or F.shape[1] != 3 or (F.size and (F.min() < 0 or F.max() >= n))):
        raise InputError("faces must be an (m, 3) array of vertex indices")
    if not views:
        raise InputError("at least one view is needed")
    centre, frame = V.mean(axis=0), _up_frame(up, V)
    V = (V - centre) @ frame.T
    if F is not None:
        vn = vertex_normals(V, F)
        fn = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    else:
        vn, fn = None, None

    nv, nr = len(views), len(rows)
    if fig is None:
        fig = new_figure(figsize=(3.4 * nv + 0.9, 3.6 * nr))
    axes = fig.subplots(nr, nv, squeeze=False)
    for r, row in enumerate(rows):
        lms = [int(v) for v in row.get("landmarks", ())]
        if any(v < 0 or v >= n for v in lms):
            raise InputError("landmark vertex index out of range")
        rgba, sm = _vertex_colours(row.get("values"), n, row.get("cmap", "viridis"),
                                   row.get("vmin"), row.get("vmax"))
        extra = row.get("extra")
        for ax, (elev, azim) in zip(axes[r], views):
            R = view_rotation(elev, azim)
            _draw_view(ax, V, F, rgba, R, lms, vn, fn, point_size, labels)
            if extra is not None:
                extra(ax, lambda pts, R=R: ((np.asarray(pts, float) - centre) @ frame.T) @ R.T)
            if r == 0:
                ax.set_title(f"elev {elev:g}°, azim {azim:g}°", fontsize=8)
        if row.get("label"):
            axes[r][0].text(-0.02, 0.5, row["label"], transform=axes[r][0].transAxes,
                            rotation=90, ha="right", va="center", fontsize=9)
        if sm is not None:
            cb = fig.colorbar(sm, ax=list(axes[r]), fraction=0.025, pad=0.01)
            if row.get("colorbar_label"):
                cb.set_label(row["colorbar_label"])
    if title:
        fig.suptitle(title, fontsize=10)
    return fig
