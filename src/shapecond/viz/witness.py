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
The picture's render data is ``scene.witness_scene`` (the HTML viewer shows the same).
"""

from __future__ import annotations

from .render import render_scene
from .scene import Place, witness_scene


def render_witness_png(shape, witness, path, *, landmarks=(), fig=None, place: Place = Place(up=None),
                       max_segments: int = 80):
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
    fig : matplotlib Figure or None
        Draw onto it; with ``path=None`` the Figure is returned, nothing written.
    place : scene.Place: ``up`` ({"x", "y", "z"}, optionally signed ("-y"), or None: guessed from the
        shape, ``scene.guess_up``: the direction whose floor most of its extremities touch), ``views``,
        ``title``.
    max_segments : int
        Number of the longest moves drawn as segments.

    Returns
    -------
    str (the path written) or Figure (``path=None``)
    """
    scene = witness_scene(shape, witness, landmarks=landmarks, place=place, max_segments=max_segments)
    return render_scene(path, scene, fig=fig)
