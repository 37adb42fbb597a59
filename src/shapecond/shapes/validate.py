"""Checks of a mesh or point cloud before anything is computed on it.

``inspect_mesh`` reports (for ``shapecond info``); ``clean_mesh`` raises
``InputError`` on what cannot be used and drops unreferenced vertices, keeping
the map back to the file's ids (TOSCA's gorilla has 1,328 isolated vertices,
which break Laplacians).  Checks are scale-free: areas are measured on the
shape scaled to a unit bounding-box diagonal (``unit_length``), so a mesh in
metres and the same mesh in nanometres get the same verdict.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..checks import check_point_cloud
from ..errors import InputError
from .geometry import Geometry

#: A face whose area is below this fraction of the squared bounding-box diagonal
#: is degenerate (exactly repeated or collinear vertices, not a thin sliver).
ZERO_AREA_RTOL = 1e-14
#: Coordinates must lie within +-MAX_COORD and the shape's size above MIN_SIZE:
#: distances are kept as float32 rows (normal range 1e-38 .. 3e38) and computed
#: on the shape scaled to unit size, so every scale in between gives the same result.
MAX_COORD = 1e35
MIN_SIZE = 1e-35


def unit_length(vertices: np.ndarray) -> float:
    """Bounding-box diagonal of finite vertices, computed without overflow."""
    span = np.ptp(vertices, axis=0)
    top = float(np.max(span)) if span.size else 0.0
    return top * float(np.linalg.norm(span / top)) if top > 0 else 0.0


def face_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    e1 = vertices[faces[:, 1]] - vertices[faces[:, 0]]
    e2 = vertices[faces[:, 2]] - vertices[faces[:, 0]]
    return 0.5 * np.linalg.norm(np.cross(e1, e2), axis=1)


def face_components(n_vertices: int, faces: np.ndarray) -> tuple[int, np.ndarray]:
    """Connected components of the referenced vertices; labels -1 for isolated vertices."""
    rows = np.concatenate([faces[:, 0], faces[:, 1], faces[:, 2]])
    cols = np.concatenate([faces[:, 1], faces[:, 2], faces[:, 0]])
    adj = sp.coo_matrix((np.ones(rows.size), (rows, cols)), shape=(n_vertices, n_vertices))
    _, labels = connected_components(adj, directed=False)
    used = np.zeros(n_vertices, dtype=bool)
    used[faces.ravel()] = True
    labels = np.where(used, labels, -1)
    uniq = np.unique(labels[used])
    out = np.full(n_vertices, -1, dtype=np.int64)
    out[used] = np.searchsorted(uniq, labels[used])
    return len(uniq), out


def boundary_edge_count(faces: np.ndarray) -> int:
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return int(np.sum(counts == 1))


def mesh_problems(vertices: np.ndarray, faces: np.ndarray | None) -> list[str]:
    """Every problem that makes the input unusable, as one-line messages."""
    problems = []
    if vertices.ndim != 2 or vertices.shape[1] != 3 or vertices.shape[0] == 0:
        return ["no vertices" if vertices.size == 0 else f"vertices have shape {vertices.shape}, expected (n, 3)"]
    if not np.all(np.isfinite(vertices)):
        problems.append(f"{int(np.sum(~np.all(np.isfinite(vertices), axis=1)))} vertices have NaN or infinite coordinates")
    elif np.max(np.abs(vertices)) > MAX_COORD:
        problems.append(f"coordinates up to {np.max(np.abs(vertices)):.3g} are beyond +-{MAX_COORD:g}; rescale the shape")
    elif faces is not None and unit_length(vertices) == 0:  # e.g. a tiny mesh written with fixed decimals
        problems.append(f"all {vertices.shape[0]} vertices have the same coordinates, so the shape has no size "
                        "(a tiny shape written with too few decimals? write it with more digits or rescale it)")
    elif faces is not None and unit_length(vertices) < MIN_SIZE:
        problems.append(f"the shape is {unit_length(vertices):.3g} across, below {MIN_SIZE:g}; rescale it")
    if faces is None:
        return problems
    if faces.size == 0:
        problems.append("the mesh has no faces")
        return problems
    if faces.ndim != 2 or faces.shape[1] != 3:
        return problems + [f"faces have shape {faces.shape}, expected (m, 3) triangles"]
    if faces.min() < 0 or faces.max() >= vertices.shape[0]:
        problems.append(f"faces index vertex {int(faces.max()) if faces.max() >= vertices.shape[0] else int(faces.min())} "
                        f"but there are {vertices.shape[0]} vertices")
        return problems
    repeated = (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 0] == faces[:, 2])
    size = unit_length(vertices) if np.all(np.isfinite(vertices)) else 0.0
    if size > 0:
        unit = (vertices - vertices.min(axis=0)) / size
        zero = repeated | (face_areas(unit, faces) <= ZERO_AREA_RTOL)
    elif np.all(np.isfinite(vertices)):  # every face of a shape without size has zero area
        zero = np.ones(faces.shape[0], dtype=bool)
    else:
        zero = repeated
    if np.any(zero):
        problems.append(f"{int(zero.sum())} faces have zero area")
    _, counts = np.unique(np.sort(faces, axis=1), axis=0, return_counts=True)
    if np.any(counts > 1):
        problems.append(f"{int(np.sum(counts - 1))} duplicate faces")
    return problems


def inspect_mesh(vertices: np.ndarray, faces: np.ndarray | None) -> dict:
    """Counts, bounding box, components, boundary edges, isolated vertices, problems."""
    report = {
        "n_vertices": int(vertices.shape[0]) if vertices.ndim == 2 else 0,
        "n_faces": None if faces is None else int(faces.shape[0]),
        "kind": "point cloud" if faces is None else "mesh",
        "bounding_box": None,
        "components": None,
        "boundary_edges": None,
        "isolated_vertices": None,
        "problems": mesh_problems(vertices, faces),
    }
    if vertices.ndim == 2 and vertices.shape[0] and np.all(np.isfinite(vertices)):
        report["bounding_box"] = {"min": vertices.min(0).tolist(), "max": vertices.max(0).tolist()}
    if faces is not None and faces.size and faces.ndim == 2 and faces.shape[1] == 3 \
            and faces.min() >= 0 and faces.max() < vertices.shape[0]:
        n_comp, _ = face_components(vertices.shape[0], faces)
        used = np.zeros(vertices.shape[0], dtype=bool)
        used[faces.ravel()] = True
        report["components"] = n_comp
        report["boundary_edges"] = boundary_edge_count(faces)
        report["isolated_vertices"] = int(np.sum(~used))
        if n_comp > 1:
            report["problems"].append(f"the mesh has {n_comp} connected components")
    return report


def clean_mesh(vertices, faces, name: str, largest_component: bool = False, file_ids=None) -> Geometry:
    """Validate, drop unreferenced vertices (keeping file ids) and check connectivity."""
    vertices = np.asarray(vertices)
    if np.iscomplexobj(vertices) or not (np.issubdtype(vertices.dtype, np.number) or vertices.dtype == bool):
        raise InputError(f"{name}: vertex coordinates must be real numbers")
    vertices = np.asarray(vertices, dtype=np.float64)
    if faces is not None:
        faces = np.asarray(faces)
        if faces.size and not (np.issubdtype(faces.dtype, np.integer) or np.issubdtype(faces.dtype, np.floating)):
            raise InputError(f"{name}: face indices are not integers")
        if faces.size and not np.issubdtype(faces.dtype, np.integer):
            if not np.all(np.isfinite(faces)) or np.any(faces != np.round(faces)) or np.max(np.abs(faces)) > 2**62:
                raise InputError(f"{name}: face indices are not integers")
        faces = faces.astype(np.int64)
    ids = np.arange(vertices.shape[0], dtype=np.int64) if file_ids is None else np.asarray(file_ids, np.int64)
    problems = mesh_problems(vertices, faces)
    if problems:
        raise InputError(f"{name}: {problems[0]}")
    if faces is None:
        check_point_cloud(vertices, name)
        return Geometry(vertices, None, ids, name)
    n_comp, labels = face_components(vertices.shape[0], faces)
    if n_comp > 1:
        if not largest_component:
            raise InputError(f"{name}: the mesh has {n_comp} connected components; "
                             "use --largest-component to keep the largest one")
        sizes = np.bincount(labels[faces[:, 0]], minlength=n_comp)
        keep_label = int(np.argmax(sizes))
        faces = faces[labels[faces[:, 0]] == keep_label]
    used = np.zeros(vertices.shape[0], dtype=bool)
    used[faces.ravel()] = True
    new_index = np.cumsum(used) - 1
    return Geometry(vertices[used], new_index[faces], ids[used], name)


def make_geometry(vertices, faces=None, name="shape", symmetry=None) -> Geometry:
    """A validated ``Geometry`` from arrays; ids are the row indices of ``vertices``.

    Validation is that of a file (``validate.clean_mesh``): unreferenced vertices
    are dropped (their ids kept), a broken mesh raises ``InputError``.
    ``symmetry`` gives the mirror row of each row.
    """
    g = clean_mesh(vertices, faces, name)
    return g if symmetry is None else g.with_symmetry(np.asarray(symmetry, dtype=np.int64))
