"""Which side of a landmark pair a point lies on: an orientation-aware landmark descriptor.

Every criterion the matchers use — geodesic distances to the landmarks, the
distortion of sample distances, the Laplace–Beltrami spectra — is intrinsic,
and an intrinsic criterion cannot tell a map from its composition with an
orientation-reversing near-isometry.  Between two poses of one body such
reversals are rare once a landmark breaks the left–right mirror, but between
two *bodies* there is another: a human's front–back reflection keeps both hands,
both feet and the head in place, changes distances only by the difference of
chest and back, and is within the distortion that separates two people.  With
landmarks at the extremities only (the σ-greedy choice, or any 3 landmarks),
every matcher then returns a torso turned front to back (FAUST_r, two people:
0.085 sqrt(area) for every matcher, issue 31).  BCICP (Ren et al. 2018) adds an
orientation-preserving term to the functional map for this reason.

Here the orientation enters pointwise.  For landmarks ``a``, ``b`` and a point
``x`` away from them, let ``u_a(x)``, ``u_b(x)`` be the unit gradients of the
geodesic distances to ``a`` and ``b`` (the directions pointing away from each)
and ``n(x)`` the outward unit normal.  Then::

    s_ab(x) = n(x) · (u_a(x) × u_b(x))   ∈ [−1, 1]

is the sine of the signed angle from the direction of ``a`` to that of ``b``:
positive on one side of the geodesic between ``a`` and ``b``, negative on the
other, and it changes sign under any orientation-reversing map while every
orientation-preserving one keeps it (up to the metric distortion of the
angle).  It is read off the distance rows the landmarks already have, needs
no constant, and is a smooth function of the shape: between two bodies it
changes only as the angles do.

The features of a shape are ``s_ab`` for every landmark pair, divided by
``sqrt(P / L)`` (``P`` pairs, ``L`` landmarks) so that the whole block weighs as
much as the ``L`` landmark anchors of the dense stage (each ``|s_ab| ≤ 1`` has
``L²`` norm at most 1 on a surface of area 1, like one anchor or one basis
function): the orientation decides between maps the spectra cannot separate,
and leaves the localisation to the basis.

Known failure, measured and not fixed: the sides of a pair whose landmarks sit at two
extremities that a pose moves (the two hands of a human) disagree between the poses across the
body between them.  TOSCA_r david1 → david6 with its six HKS landmarks (three on each hand): under
the *true* map the nine hand-to-hand sides correlate 0.28 and 23 % of the reference points, on the
torso, have a strong side of the opposite sign; the dense stage errs 45.6 ×10⁻³ sqrt(area) with
the sides and 23.4 without them (35.2 and 25.0 with the first three landmarks), so here a correct
landmark costs accuracy.  Tried and not adopted: the sides read off the gradients of the landmarks'
harmonic coordinates (conformally invariant angles, no cut locus).  They agree better under the
true map (SMAL_r 0.80-0.95 against 0.62-0.76) and fix that pair (23.4), but the matching ends worse
on average: six landmarks, FAQ start, every landmark method, TOSCA_r test pairs 17.4 → 18.9 (17 of
40 worse by 5 %, 13 better) and SMAL_r 43.6 → 46.2 (25 of 40 worse, 5 better), in the project's
benchmark ``sides``.  Weighting the block by its
effective number of independent columns (a participation ratio) brought the pair to 30.7 and cost 4-5 ×10⁻³
on cat2 → cat3; whitening every column on its own or sharing the block's weight by column
multiplicity left it at 39-42.  Also tried, 6 exact landmarks, FAQ's sample map fixed, the dense stage
varied (TOSCA_r one test pair per class, FPS/PLS/HKS/CNBS: 32 rows; SMAL_r the cow to 8 animals, 5 landmark
methods: 40 rows; means in 10⁻³ sqrt(area)): no sides in the dense stage, TOSCA_r 17.9 → 18.1 (david 45.5 →
23.5) but SMAL_r 43.4 → 51.6; the sides of the first three landmarks' pairs only, TOSCA_r 17.9 → 18.7;
each pair's sides weighted by ``exp(−e² / 2σ²)`` of the detour ``e = d_a + d_b − d_ab`` through the point
(σ the anchors' width; the sides near the geodesic between the pair, where a pose cannot turn them), TOSCA_r
17.9 → 17.5 (david 45.5 → 37.7) but SMAL_r 43.4 → 47.4; the less distorted of the maps with and without the
sides (``error_bar.map_distortion``), SMAL_r 43.4 → 44.2.  Between species every pair's sides, far ones
included, are what localise the map.

The outward normal: face normals by the file's vertex order, the whole mesh
flipped when its signed volume is negative (a closed surface given inside
out); meshes are assumed consistently oriented otherwise (a few flipped
triangles are averaged away at the vertices).  Point clouds have no
orientation: no features.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from shapecond.shapes.geometry import Geometry


def _face_frames(V: np.ndarray, F: np.ndarray):
    """Unit face normals (outward by the signed volume) and twice the face areas."""
    e1, e2 = V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]
    cross = np.cross(e1, e2)
    twice_area = np.linalg.norm(cross, axis=1)
    normals = cross / np.maximum(twice_area, 1e-300)[:, None]
    centre = V.mean(axis=0)
    signed_volume = float(np.einsum("ij,ij->", V[F[:, 0]] - centre, cross))
    return (normals if signed_volume >= 0 else -normals), twice_area


def distance_gradients(geometry: Geometry, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit vertex gradients of each distance row and the outward unit vertex normals.

    Parameters
    ----------
    geometry : a mesh.
    rows : (L, n) distances from each landmark to every vertex.

    Returns
    -------
    (gradients (L, n, 3), normals (n, 3)): per face ``∇f = Σ_i f_i (n × e_i) / (2A)``
    (``e_i`` the edge opposite vertex ``i``, counter-clockwise), averaged at the vertices
    with the face areas as weights and projected on the vertex's tangent plane.
    """
    V = np.asarray(geometry.vertices, dtype=np.float64)
    F = np.asarray(geometry.faces, dtype=np.int64)
    normals, twice_area = _face_frames(V, F)
    n, m = V.shape[0], F.shape[0]
    # vertex <- face sums as one sparse product (each face counted at its three corners)
    to_vertex = sp.csr_matrix((np.ones(3 * m), (F.T.reshape(-1), np.tile(np.arange(m), 3))), shape=(n, m))
    # the face gradient's Σ_i f_i (n × e_i): e_0 = v2 − v1, e_1 = v0 − v2, e_2 = v1 − v0
    rot = [np.cross(normals, V[F[:, (i + 2) % 3]] - V[F[:, (i + 1) % 3]]) for i in range(3)]
    vnormal = to_vertex @ (normals * twice_area[:, None])
    vnormal /= np.maximum(np.linalg.norm(vnormal, axis=1), 1e-300)[:, None]
    grads = np.zeros((rows.shape[0], n, 3))
    for j, f in enumerate(np.asarray(rows, dtype=np.float64)):
        g = to_vertex @ sum(f[F[:, i]][:, None] * rot[i] for i in range(3))  # faces' 2A ∇f: area-weighted
        g -= np.einsum("ij,ij->i", g, vnormal)[:, None] * vnormal
        grads[j] = g / np.maximum(np.linalg.norm(g, axis=1), 1e-300)[:, None]
    return grads, vnormal


def orientation_features(geometry: Geometry, rows: np.ndarray) -> np.ndarray | None:
    """``s_ab`` of every landmark pair at every vertex, weighted (module docstring).

    Parameters
    ----------
    geometry : Geometry (None is returned for a point cloud).
    rows : (L, n) distances from each landmark to every vertex (any unit).

    Returns
    -------
    (n, P) float32 with ``P = L (L − 1) / 2``, or None (point cloud, or fewer than 2 landmarks).
    """
    L = int(rows.shape[0])
    if geometry.faces is None or L < 2:
        return None
    grads, normals = distance_gradients(geometry, rows)
    pairs = [(a, b) for a in range(L) for b in range(a + 1, L)]
    out = np.empty((geometry.n_vertices, len(pairs)), dtype=np.float32)
    for k, (a, b) in enumerate(pairs):
        out[:, k] = np.einsum("ij,ij->i", normals, np.cross(grads[a], grads[b]))
    return out / np.float32(math.sqrt(len(pairs) / L))


def orientation_agreement(source: Geometry, target: Geometry, vertex_map: np.ndarray,
                          source_rows: np.ndarray, target_rows: np.ndarray) -> float:
    """Mean of ``s_ab(x) · s_ab(T x)`` over vertices and landmark pairs, divided by the mean of
    ``s_ab(x)²``: 1 for a map that keeps every side, −1 for a reflection, NaN without features."""
    fs = orientation_features(source, source_rows)
    ft = orientation_features(target, target_rows)
    if fs is None or ft is None:
        return math.nan
    fs, ft = fs.astype(np.float64), ft[np.asarray(vertex_map)].astype(np.float64)
    den = float(np.sum(fs * fs))
    return float(np.sum(fs * ft) / den) if den > 0 else math.nan
