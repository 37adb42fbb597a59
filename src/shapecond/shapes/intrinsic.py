"""The intrinsic Delaunay triangulation of a mesh's tufted cover (Sharp and Crane, SGP 2020).

The heat method (``shapes/heat.py``) needs a Laplacian with non-negative
weights, and the one potpourri3d and robust-laplacian use is built this way:

1. the *tufted cover*: every face is doubled (a front copy and a back copy
   with reversed orientation, sharing the vertices), and the copies are glued
   so that every edge has exactly two faces: across an interior edge front
   meets front and back meets back, across a boundary edge the front copy of
   a face meets its own back copy.  A surface with boundary becomes a closed
   "pillow"; faces wound inconsistently (TOSCA david and michael have some)
   are glued to the other sheet, so orientation does not matter;
2. *mollification*: every edge grows by the smallest ε for which each
   triangle inequality holds with a margin of 1e-5 × the mean edge length;
3. *edge flips* (a FIFO queue over all edges, as geometry-central's
   ``flipToDelaunay``) until every edge's cotangent weight is ≥ −1e-6.  Only
   lengths change: the vertices stay where they are.  On the cover, edges
   across the boundary can flip too, which is how the cover treats boundaries.

No Python package exposes this triangulation (robust-laplacian returns only
the matrices; libigl's intrinsic Delaunay triangulation does not take the
cover, leaves boundary edges alone and differed from potpourri3d's distances
by up to 0.3 % of the diameter on TOSCA meshes with holes), so the flips are
written here, compiled with numba.

A mesh with an edge shared by more than two faces is refused (``None``); the
caller falls back to potpourri3d, whose cover sorts such faces by angle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

MOLLIFY = 1e-5
DELAUNAY_EPS = 1e-6


@dataclass(frozen=True)
class IntrinsicTriangulation:
    """Faces of the flipped cover with the lengths of their edges.

    Attributes
    ----------
    faces : (2m, 3) int64 vertex indices (a vertex may appear twice in a face
        that straddles the two sheets).
    lengths : (2m, 3) float64, the length of the edge opposite each corner.
    mean_edge_length : float, over the edges of the flipped cover.
    """

    faces: np.ndarray
    lengths: np.ndarray
    mean_edge_length: float


def tufted_cover(faces: np.ndarray, n_vertices: int):
    """Halfedge arrays of the tufted cover, or None if an edge has more than two faces.

    Halfedge ``3f + i`` runs from corner i to corner i + 1 of cover face f;
    faces ``m..2m-1`` are the back copies ``(c0, c2, c1)``.

    Returns
    -------
    (tail, twin, nxt) int64 arrays over the 6m halfedges.
    """
    F = np.asarray(faces, dtype=np.int64)
    m = F.shape[0]
    cover = np.concatenate([F, F[:, [0, 2, 1]]])
    tail = cover.ravel()
    tip = np.roll(cover, -1, axis=1).ravel()
    front = np.arange(3 * m)
    mirror = 3 * (front // 3 + m) + (2 - front % 3)  # the back copy of each front halfedge
    key = np.minimum(tail[front], tip[front]) * n_vertices + np.maximum(tail[front], tip[front])
    order = np.argsort(key, kind="stable")
    uniq, start, count = np.unique(key[order], return_index=True, return_counts=True)
    if np.any(count > 2):
        return None
    twin = np.full(6 * m, -1, dtype=np.int64)
    single = order[start[count == 1]]
    twin[single], twin[mirror[single]] = mirror[single], single
    h1, h2 = order[start[count == 2]], order[start[count == 2] + 1]
    opposite = tail[h1] == tip[h2]
    a = np.where(opposite, h2, mirror[h2])  # partner of h1: opposite direction
    b = np.where(opposite, mirror[h2], h2)  # partner of mirror(h1)
    twin[h1], twin[a] = a, h1
    twin[mirror[h1]], twin[b] = b, mirror[h1]
    nxt = 3 * (np.arange(6 * m) // 3) + (np.arange(6 * m) % 3 + 1) % 3
    return tail, twin, nxt


def intrinsic_delaunay_cover(vertices: np.ndarray, faces: np.ndarray) -> IntrinsicTriangulation | None:
    """Mollified, flipped-to-Delaunay tufted cover of a mesh (module docstring); None if not edge-manifold."""
    V = np.asarray(vertices, dtype=np.float64)
    arrays = tufted_cover(faces, V.shape[0])
    if arrays is None:
        return None
    tail, twin, nxt = arrays
    H = tail.size
    edge_of = np.full(H, -1, dtype=np.int64)
    first = np.flatnonzero(np.arange(H) < twin)  # one halfedge per edge, in halfedge order
    edge_of[first] = np.arange(first.size)
    edge_of[twin[first]] = np.arange(first.size)
    length = np.linalg.norm(V[tail[first]] - V[tail[twin[first]]], axis=1)
    lh = length[edge_of].reshape(-1, 3)  # per halfedge, by face
    delta = MOLLIFY * float(length.mean())
    eps = max(0.0, float(np.max(delta + np.roll(lh, -2, axis=1) - lh - np.roll(lh, -1, axis=1))))
    length = length + eps
    face_he = 3 * np.arange(H // 3, dtype=np.int64)
    _flip_to_delaunay(tail, twin, nxt, edge_of, first.copy(), length, face_he, DELAUNAY_EPS)
    h0 = face_he
    h1 = nxt[h0]
    h2 = nxt[h1]
    tri = np.stack([tail[h0], tail[h1], tail[h2]], axis=1)
    lengths = np.stack([length[edge_of[h1]], length[edge_of[h2]], length[edge_of[h0]]], axis=1)
    return IntrinsicTriangulation(tri, lengths, float(length.mean()))


@njit(cache=True)
def _half_cotan(he, nxt, edge_of, length):  # pragma: no cover - compiled
    lij = length[edge_of[he]]
    ljk = length[edge_of[nxt[he]]]
    lki = length[edge_of[nxt[nxt[he]]]]
    s = 0.5 * (lij + ljk + lki)
    area = np.sqrt(max(0.0, s * (s - lij) * (s - ljk) * (s - lki)))
    return (-lij * lij + ljk * ljk + lki * lki) / (4.0 * area) / 2.0


@njit(cache=True)
def _apex(l_ab, l_bc, l_ca):  # pragma: no cover - compiled
    """(x, y ≥ 0) of C with A = (0, 0), B = (l_ab, 0), |BC| = l_bc, |CA| = l_ca."""
    x = (l_ab * l_ab + l_ca * l_ca - l_bc * l_bc) / (2.0 * l_ab)
    return x, np.sqrt(max(0.0, l_ca * l_ca - x * x))


@njit(cache=True)
def _flip_to_delaunay(tail, twin, nxt, edge_of, edge_he, length, face_he, eps):  # pragma: no cover
    """Flip edges (FIFO over all edges, then the four edges around each flip) until no weight < −eps."""
    n_edges = edge_he.size
    face_of = np.empty(tail.size, dtype=np.int64)
    for f in range(face_he.size):
        h = face_he[f]
        for _ in range(3):
            face_of[h] = f
            h = nxt[h]
    queue = np.arange(n_edges)
    in_queue = np.ones(n_edges, dtype=np.bool_)
    head, size = 0, n_edges
    while size > 0:
        e = queue[head]
        head = (head + 1) % n_edges
        size -= 1
        in_queue[e] = False
        ha1 = edge_he[e]
        hb1 = twin[ha1]
        ha2, hb2 = nxt[ha1], nxt[hb1]
        ha3, hb3 = nxt[ha2], nxt[hb2]
        if ha2 == hb1 or hb2 == ha1:  # incident on a vertex of degree one
            continue
        w = _half_cotan(ha1, nxt, edge_of, length) + _half_cotan(hb1, nxt, edge_of, length)
        if not w < -eps:
            continue
        # va = tail(ha1), vb = tail(hb1); apexes vc = tail(ha3) (face A), vd = tail(hb3) (face B)
        l_ab = length[e]
        xc, yc = _apex(l_ab, length[edge_of[ha2]], length[edge_of[ha3]])
        xd, yd = _apex(l_ab, length[edge_of[hb3]], length[edge_of[hb2]])
        new_len = np.sqrt((xc - xd) ** 2 + (yc + yd) ** 2)
        if not np.isfinite(new_len):
            continue
        fa, fb = face_of[ha1], face_of[hb1]
        tail[ha1], tail[hb1] = tail[hb3], tail[ha3]           # ha1: vd -> vc, hb1: vc -> vd
        nxt[ha1], nxt[ha3], nxt[hb2] = ha3, hb2, ha1          # face A: vd, vc, va
        nxt[hb1], nxt[hb3], nxt[ha2] = hb3, ha2, hb1          # face B: vc, vd, vb
        face_of[hb2], face_of[ha2] = fa, fb
        face_he[fa], face_he[fb] = ha1, hb1
        length[e] = new_len
        for h in (ha2, ha3, hb2, hb3):
            k = edge_of[h]
            if not in_queue[k]:
                queue[(head + size) % n_edges] = k
                size += 1
                in_queue[k] = True
