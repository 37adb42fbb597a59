"""PLY files with per-vertex colours for MeshLab or Blender.

The file is written by ``shapes.io.write_mesh`` (trimesh's exporter with
``process=False``, so that the vertex order, and with it every vertex id, is kept,
through the atomic writer).
Scalars are turned into colours by ``scene.colour_layer`` (the PNG's colour map); landmarks can be painted
on top (first three red, the rest green, as the paper's Figure 6) together with their
one-ring so that they are visible in a viewer.
"""

from __future__ import annotations

import numpy as np
import trimesh

from ..errors import InputError
from ..shapes.io import write_mesh
from .scene import Colouring, colour_layer, landmark_colour


def scalar_colours(values, colouring: Colouring = Colouring()) -> np.ndarray:
    """Map scalars (n,) to uint8 RGBA colours (n, 4); non-finite values get the top colour."""
    v = np.asarray(values, dtype=float).ravel()
    rgba = colour_layer(v, v.size, colouring).rgba
    return np.round(rgba * 255).astype(np.uint8)


def write_ply(path, vertices, faces=None, values=None, landmarks=(), *, ring: bool = True,
              colouring: Colouring = Colouring()) -> str:
    """Write a PLY with per-vertex colours.

    Parameters
    ----------
    path : str or path-like
    vertices : (n, 3) array
    faces : (m, 3) int array or None
        ``None`` writes a point cloud.
    values : (n,) scalars, (n, 3|4) colours (floats in [0, 1] or uint8), or None (grey)
    landmarks : sequence of int
        Internal vertex indices in order; painted red (first three) and green (rest).
    ring : bool
        Also paint the landmarks' neighbouring vertices (meshes only).
    colouring : scene.Colouring of scalar values (``cmap``, default "viridis", ``vmin``, ``vmax``).

    Returns
    -------
    str
        The path written.
    """
    V = np.asarray(vertices, dtype=float)
    if V.ndim != 2 or V.shape[1] != 3:
        raise InputError("vertices must be an (n, 3) array")
    n = V.shape[0]
    if values is None:
        colours = np.tile(np.array([190, 190, 190, 255], np.uint8), (n, 1))
    else:
        v = np.asarray(values)
        if v.ndim == 1:
            if v.shape[0] != n:
                raise InputError(f"values must have {n} entries, got {v.shape[0]}")
            colours = scalar_colours(v, colouring)
        elif v.ndim == 2 and v.shape[0] == n and v.shape[1] in (3, 4):
            c = v.astype(float)
            if v.dtype.kind == "f":
                c = np.round(np.clip(c, 0, 1) * 255)
            colours = np.full((n, 4), 255, np.uint8)
            colours[:, : v.shape[1]] = c.astype(np.uint8)
        else:
            raise InputError(f"values must have shape ({n},) or ({n}, 3|4), got {v.shape}")
    F = None if faces is None else np.asarray(faces, dtype=np.int64)
    nbrs = None
    if F is not None and ring and len(landmarks):
        nbrs = trimesh.Trimesh(V, F, process=False).vertex_neighbors
    for i, vid in enumerate(landmarks):
        vid = int(vid)
        if not 0 <= vid < n:
            raise InputError(f"landmark vertex index {vid} out of range")
        c = np.round(np.array([*landmark_colour(i), 1.0]) * 255).astype(np.uint8)
        colours[vid] = c
        if nbrs is not None:
            colours[list(nbrs[vid])] = c

    write_mesh(path, V, F, colors=colours, file_type="ply")
    return str(path)
