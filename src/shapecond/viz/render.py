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
``render_png``/``render_rows`` write a PNG with the atomic writer.  Everything drawn
(colours, views, landmark styles, labels, shading) comes from a ``scene.Scene``, the
render data the HTML viewer (``viz.html``) is built from too; ``draw_scene`` and
``render_scene`` draw one.

Values are either scalars ``(n,)`` mapped through a colour map, or colours
``(n, 3)``/``(n, 4)`` in [0, 1].  Faces take the mean of their vertices' values.
"""

from __future__ import annotations

from dataclasses import dataclass

import matplotlib
import numpy as np
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure

from ..errors import InputError
from ..output import atomic_open
from .scene import (AMBIENT, DEFAULT_VIEWS, DIFFUSE, FACING, Colouring, Place, Scene, landmark_colour, make_scene,
                    view_label)

__all__ = ["draw_rows", "draw_scene", "new_figure", "render_png", "render_rows", "render_scene", "save_figure",
           "view_rotation"]


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


def new_figure(figsize=(6.4, 4.8)) -> Figure:
    """A matplotlib Figure that belongs to no pyplot state (the backend is untouched)."""
    return Figure(figsize=figsize)


def save_figure(fig: Figure, path, dpi: int = 110, bbox_inches="tight") -> str:
    """Write ``fig`` as PNG to ``path`` with the atomic writer."""
    with atomic_open(path) as fh:
        fig.savefig(fh, format="png", dpi=dpi, bbox_inches=bbox_inches)
    return str(path)


def _draw_view(ax, scene: Scene, layer, R, fnormals, labels):
    V, F = scene.vertices, scene.faces
    P = V @ R.T  # screen x, screen y, depth (larger = nearer)
    rgba = layer.rgba
    if F is not None:
        depth = P[F, 2].mean(axis=1)
        order = np.argsort(depth)
        fc = rgba[F].mean(axis=1)
        fn = fnormals @ R.T
        ln = np.linalg.norm(fn, axis=1)
        shade = AMBIENT + DIFFUSE * np.abs(fn[:, 2]) / np.where(ln > 0, ln, 1.0)
        fc[:, :3] *= shade[:, None]
        polys = P[F[order]][:, :, :2]
        pc = PolyCollection(polys, facecolors=fc[order], edgecolors="none", antialiaseds=False)
        ax.add_collection(pc)
    else:
        order = np.argsort(P[:, 2])
        ax.scatter(P[order, 0], P[order, 1], c=rgba[order], s=scene.point_size, linewidths=0)
    if layer.segments is not None and len(layer.segments):
        S = layer.segments @ R.T
        for p, q in S:
            ax.plot([p[0], q[0]], [p[1], q[1]], color="black", lw=0.7, alpha=0.7, zorder=4)
        ax.scatter(S[:, 1, 0], S[:, 1, 1], s=4, c="black", zorder=4)
    for i, vid in enumerate(layer.landmarks):
        colour = landmark_colour(layer.rank(i))
        facing = scene.normals is None or (scene.normals[vid] @ R[2]) > FACING
        ax.scatter(
            [P[vid, 0]], [P[vid, 1]], s=70 if facing else 35, color=colour if facing else "none",
            edgecolors="black" if facing else colour, linewidths=1.0, zorder=5,
        )
        if labels and facing:
            ax.annotate(str(layer.rank(i) + 1), (P[vid, 0], P[vid, 1]), xytext=(4, 4),
                        textcoords="offset points", fontsize=7, zorder=6)
    pad = 0.03 * np.ptp(P[:, :2], axis=0).max()
    ax.set_xlim(P[:, 0].min() - pad, P[:, 0].max() + pad)
    ax.set_ylim(P[:, 1].min() - pad, P[:, 1].max() + pad)
    ax.set_aspect("equal")
    ax.axis("off")


@dataclass(frozen=True)
class Look:
    """How a picture of a shape is framed, coloured and drawn (``render_png``, ``render_rows``).

    Attributes
    ----------
    views : sequence of (elevation, azimuth) in degrees, camera positions around ``up``
        (``view_rotation``).
    up : {"x", "y", "z"}, optionally signed ("-y"): the data's vertical direction (TOSCA meshes: ``"z"``;
        ``scene.guess_up`` guesses it).
    title : the figure's title.
    point_size : marker size of a point cloud.
    labels : number the landmarks.
    dpi : resolution of the PNG.
    colouring : how ``render_png``'s scalar values are coloured (``scene.Colouring``: ``cmap``, default
        "viridis", ``vmin``, ``vmax`` and the colour bar's ``label``); ``render_rows``' rows colour themselves.
    extra : ``render_png``: ``extra(ax, project)`` is called for every view after the shape is drawn, with
        ``project(points (k, 3)) -> (k, 3)`` taking points in the input's coordinates to screen x, screen y
        and depth (used by the witness picture); None: nothing.
    """

    views: tuple = DEFAULT_VIEWS
    up: str = "z"
    title: str | None = None
    point_size: float = 6.0
    labels: bool = True
    dpi: int = 110
    colouring: Colouring = Colouring()
    extra: object = None


def render_png(path, vertices, faces=None, values=None, landmarks=(), *, fig=None, look: Look = Look()):
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
    fig : matplotlib Figure or None
        Draw onto this Figure; with ``path=None`` the Figure (``fig`` or a new
        one) is returned instead of writing a file.
    look : Look (views, up, title, point size, labels, dpi, the colouring of ``values`` and ``extra``).

    Returns
    -------
    str (the path written) or Figure (``path=None``)
    """
    c = look.colouring
    row = dict(values=values, landmarks=landmarks, cmap=c.cmap, vmin=c.vmin, vmax=c.vmax, colorbar_label=c.label,
               extra=look.extra, label=None)
    return render_rows(path, vertices, faces, [row], fig=fig, look=look)


def render_rows(path, vertices, faces, rows, *, fig=None, look: Look = Look()):
    """Several colourings of one shape, one row of views each, in one PNG (or Figure).

    ``rows`` is a list of dicts with the keys ``values``, ``landmarks``, ``extra``, ``cmap``,
    ``vmin``, ``vmax``, ``colorbar_label`` (as ``render_png``'s) and ``label`` (a caption written
    left of the row).  Each row with scalar values gets its own colour bar.  ``look``: views, up,
    title, point size, labels and dpi (its colouring is ``render_png``'s).  With ``path=None`` the
    Figure is returned (see ``render_png``).
    """
    fig = draw_rows(fig, vertices, faces, rows, look)
    return fig if path is None else save_figure(fig, path, look.dpi)


def draw_rows(fig, vertices, faces, rows, look: Look = Look()) -> Figure:
    """Draw the rows of ``render_rows`` onto ``fig`` (a new Figure when None) and return it."""
    rows = [dict(r) for r in rows]
    extras = [r.pop("extra", None) for r in rows]
    scene = make_scene(vertices, faces, rows,
                       place=Place(look.up, look.views, look.title, point_size=look.point_size))
    return draw_scene(fig, scene, labels=look.labels, extras=extras)


def draw_scene(fig, scene: Scene, *, labels: bool = True, extras=()) -> Figure:
    """Draw a Scene (one row of views per layer, a colour bar per scalar layer) onto ``fig``.

    ``extras[r]``, if given, is called as ``extra(ax, project)`` for every view of
    row ``r`` (see ``render_png``).  Returns the Figure (a new one when ``fig`` is None).
    """
    V, F = scene.vertices, scene.faces
    fn = None if F is None else np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    nv, nr = len(scene.views), len(scene.layers)
    if fig is None:
        fig = new_figure(figsize=(3.4 * nv + 0.9, 3.6 * nr))
    elif not isinstance(fig, Figure):
        raise InputError(f"fig must be a matplotlib Figure or None, got {type(fig).__name__}")
    axes = fig.subplots(nr, nv, squeeze=False)
    extras = list(extras) + [None] * (nr - len(extras))
    for r, layer in enumerate(scene.layers):
        for ax, (elev, azim) in zip(axes[r], scene.views):
            R = view_rotation(elev, azim)
            _draw_view(ax, scene, layer, R, fn, labels)
            if extras[r] is not None:
                extras[r](ax, lambda pts, R=R: scene.to_display(pts) @ R.T)
            if r == 0:
                ax.set_title(view_label(elev, azim), fontsize=8)
        if layer.label:
            axes[r][0].text(-0.02, 0.5, layer.label, transform=axes[r][0].transAxes,
                            rotation=90, ha="right", va="center", fontsize=9)
        if layer.colorbar is not None:
            cb = fig.colorbar(layer.colorbar.mappable(), ax=list(axes[r]), fraction=0.025, pad=0.01)
            if layer.colorbar.label:
                cb.set_label(layer.colorbar.label)
    if scene.title:
        fig.suptitle(scene.title, fontsize=10)
    return fig


def render_scene(path, scene: Scene, *, labels: bool = True, dpi: int = 110, fig=None):
    """Draw a Scene into a PNG written atomically (or onto ``fig``, returned, with ``path=None``)."""
    fig = draw_scene(fig, scene, labels=labels)
    return fig if path is None else save_figure(fig, path, dpi)
