"""Harmonic coordinates of landmarks: where a point lies between the landmarks, kept off isometry.

For ``L`` landmarks, ``h_i`` is the harmonic function (``Δh_i = 0``) equal to 1 on a small geodesic
disk around landmark ``i`` and 0 on the disks around the others; ``(h_1, ..., h_L)`` sums to 1 and
tells a point's place among the landmarks as the probability that a random walk started there reaches
each landmark first.  The Dirichlet energy of a surface is invariant under conformal maps, so these
coordinates survive the deformations two bodies or two species differ by (a longer leg, a wider
chest: local changes of scale), which change geodesic distances to the landmarks — the only thing
the dense stage compared besides the spectra.  Measured on the SMAL_r training split (cow to 8
other species, 6 exact landmarks, the dense stage started from the true map): the ZoomOut fixed
point errs 0.042 sqrt(area) without the harmonic coordinates and 0.034 with them; from the FAQ
matcher's map, 0.040 → 0.037 (``zoomout`` weighs them).  On TOSCA_r pairs (one body, two poses)
nothing changed by more than ±1 ×10⁻³.

Why disks and not points: a harmonic function pinned at a single vertex of a surface is a discrete
artefact (a point has zero capacity in two dimensions: the function tends to a constant as the mesh
is refined, at a speed set by the vertex spacing).  Pinned on disks of a fixed geodesic radius it
converges with refinement, so two shapes meshed differently get the same coordinates.  The radius is
the dense stage's anchor width (``zoomout.anchor_width``: the half-wavelength of the last basis
function), the accuracy to which the basis can locate a landmark anyway.

Solved with one sparse Cholesky factor of the stiffness matrix restricted to the vertices off the
disks (``cholesky.SparseCholesky``), ``L`` right-hand sides; a part of the shape that no disk touches
(a second component) leaves the system singular and no coordinates are returned.
"""

from __future__ import annotations

import numpy as np

from shapecond.cholesky import NotPositiveDefinite, SparseCholesky
from shapecond.shapes.geometry import Geometry
from shapecond.shapes.laplace import operators


def landmark_disks(rows: np.ndarray, radius: float) -> np.ndarray:
    """Label of every vertex: the landmark whose disk of ``radius`` holds it (the nearest landmark
    where disks overlap; each landmark's own vertex always), −1 off every disk.

    Parameters
    ----------
    rows : (L, n) distances from each landmark to every vertex (the unit of ``radius``).
    radius : disk radius.
    """
    rows = np.asarray(rows, dtype=np.float64)
    nearest = np.argmin(rows, axis=0)
    label = np.where(rows[nearest, np.arange(rows.shape[1])] <= radius, nearest, -1)
    label[np.argmin(rows, axis=1)] = np.arange(rows.shape[0])
    return label


def harmonic_coordinates(geometry: Geometry, rows: np.ndarray, radius: float) -> np.ndarray | None:
    """``(h_1, ..., h_L)`` at every vertex (module docstring).

    Parameters
    ----------
    geometry : Geometry (mesh or point cloud: ``shapes.laplace.operators``).
    rows : (L, n) distances from each landmark to every vertex.
    radius : radius of the landmark disks, in the unit of ``rows``.

    Returns
    -------
    (n, L) float64, rows summing to 1, or None (fewer than 2 landmarks, or a part of the shape
    that no disk reaches).
    """
    L_count = int(rows.shape[0])
    if L_count < 2:
        return None
    stiffness, _ = operators(geometry)
    label = landmark_disks(rows, radius)
    on, off = np.flatnonzero(label >= 0), np.flatnonzero(label < 0)
    H = np.zeros((geometry.n_vertices, L_count))
    H[on, label[on]] = 1.0
    if off.size == 0:
        return H
    A = stiffness[off][:, off]
    try:
        H[off] = SparseCholesky(A).solve(-(stiffness[off][:, on] @ H[on]))
    except NotPositiveDefinite:
        return None
    return H if np.all(np.isfinite(H)) else None
