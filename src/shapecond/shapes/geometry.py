"""The ``Geometry`` type: a triangle mesh or a point cloud with the file's vertex ids.

Every id a user sees is the id in *their* file.  Internally, unreferenced
vertices of a mesh are dropped (they break Laplacians and geodesics) and
vertices are renumbered ``0..n-1``; ``ids[i]`` is the file's id of internal
vertex ``i``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError


@dataclass(frozen=True, eq=False)
class Geometry:
    """A surface (``faces`` given) or a point cloud (``faces is None``).

    Attributes
    ----------
    vertices : (n, 3) float64
    faces : (m, 3) int64 or None
        Triangles indexing internal vertices.
    ids : (n,) int64
        The file's vertex id of each internal vertex.
    name : str
        A short name (file stem or generated shape name).
    symmetry : (n,) int64 or None
        Internal index of each vertex's mirror image, when a symmetry map is known
        (generated symmetric shapes, or a ``.sym`` file given by the user).
    """

    vertices: np.ndarray
    faces: np.ndarray | None
    ids: np.ndarray
    name: str = "shape"
    symmetry: np.ndarray | None = field(default=None)

    def __repr__(self) -> str:
        kind = f"{self.faces.shape[0]} faces" if self.faces is not None else "point cloud"
        return (f"Geometry({self.name!r}, {self.n_vertices} vertices, {kind}"
                + (", with a symmetry map)" if self.symmetry is not None else ")"))

    @property
    def is_mesh(self) -> bool:
        return self.faces is not None

    @property
    def n_vertices(self) -> int:
        return int(self.vertices.shape[0])

    def to_internal(self, file_ids) -> np.ndarray:
        """Map the file's vertex ids to internal indices; ``InputError`` for unknown ids."""
        file_ids = np.asarray(list(file_ids) if not isinstance(file_ids, np.ndarray) else file_ids)
        if file_ids.size == 0:
            return np.zeros(0, dtype=np.int64)
        if not np.issubdtype(file_ids.dtype, np.integer):
            raise InputError("vertex ids must be integers")
        lookup = {int(v): i for i, v in enumerate(self.ids)}
        out = np.empty(file_ids.size, dtype=np.int64)
        for k, v in enumerate(file_ids.ravel()):
            i = lookup.get(int(v))
            if i is None:
                hi = int(self.ids.max()) if self.ids.size else -1
                raise InputError(
                    f"vertex id {int(v)} is not a vertex of {self.name} "
                    f"(valid ids: 0..{hi}, unreferenced vertices excluded)"
                )
            out[k] = i
        return out

    def shares_vertex_order(self, other: "Geometry") -> bool:
        """Whether ``other`` is this shape's mesh with its vertices moved (one vertex order).

        Equal vertex ids are necessary but not enough: TOSCA's david and michael have the
        same 52,565 vertex count and nothing else in common (3.5 % of their triangles
        agree; the ground truth "identity" sends an edge to one 14× longer, median).  A
        deformed copy keeps every triangle (a flipped one keeps its vertex set), a
        different triangulation shares almost none, so a mesh pair must agree on more than
        half of its triangles, compared as vertex sets.  Point clouds have only their ids.
        """
        if self.n_vertices != other.n_vertices or not np.array_equal(self.ids, other.ids):
            return False
        if self.faces is None or other.faces is None:
            return True  # a point cloud has only its ids to compare
        mine = {tuple(f) for f in np.sort(self.faces, axis=1).tolist()}
        shared = sum(tuple(f) in mine for f in np.sort(other.faces, axis=1).tolist())
        return 2 * shared > max(len(mine), other.faces.shape[0])

    def with_symmetry(self, symmetry_file_ids: np.ndarray) -> "Geometry":
        """Attach a symmetry map given in the file's ids (0-based, one entry per file vertex)."""
        sym = np.asarray(symmetry_file_ids, dtype=np.int64)
        n_file = int(self.ids.max()) + 1 if self.ids.size else 0
        if sym.ndim != 1 or sym.size < n_file:
            raise InputError(
                f"symmetry map has {sym.size} entries but {self.name} has {n_file} vertices"
            )
        if sym.min() < 0 or sym.max() >= sym.size:
            raise InputError("symmetry map refers to vertex ids out of range")
        internal = self.to_internal(sym[self.ids])
        return Geometry(self.vertices, self.faces, self.ids, self.name, internal)
