"""Reading shapes, landmark files and symmetry maps; writing outputs atomically.

Supported inputs
----------------
* meshes: OFF, OBJ, PLY, STL through trimesh with ``process=False`` (vertex order
  is kept, DESIGN.md section 4), and TOSCA ``.vert``/``.tri`` pairs (1-based faces);
* point clouds: ``.xyz``/``.txt`` (first three columns), ``.npy`` of shape (n, 3),
  PLY without faces;
* an N x N distance matrix as ``.npy``;
* ``demo:NAME[:key=value,...]``: a generated shape (``shapecond.shapes.synthetic``).
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

import numpy as np

from ..errors import InputError
from .geometry import Geometry
from .validate import check_distance_matrix, clean_mesh, inspect_mesh

MESH_SUFFIXES = {".off", ".obj", ".ply", ".stl"}
CLOUD_SUFFIXES = {".xyz", ".txt"}


def parse_demo_spec(spec: str) -> tuple[str, dict]:
    """``demo:animal:delta=0.05,resolution=0.02`` -> ("animal", {"delta": 0.05, ...})."""
    parts = spec.split(":", 2)
    name = parts[1] if len(parts) > 1 else ""
    params = {}
    if len(parts) == 3 and parts[2]:
        for item in parts[2].split(","):
            key, sep, value = item.partition("=")
            if not sep:
                raise InputError(f"bad demo parameter {item!r}: expected key=value")
            try:
                params[key.strip()] = int(value) if value.strip().lstrip("-").isdigit() else float(value)
            except ValueError:
                raise InputError(f"bad value for demo parameter {key!r}: {value!r}") from None
    return name, params


def load_input(spec: str, largest_component: bool = False):
    """A ``Geometry`` for a mesh, point cloud or ``demo:NAME``; an (N, N) array for a matrix."""
    spec = str(spec)
    if spec.startswith("demo:"):
        from .synthetic import generate

        name, params = parse_demo_spec(spec)
        return generate(name, **params)
    path = Path(spec)
    if path.suffix.lower() == ".npy":
        arr = _load_npy(path)
        if arr.ndim == 2 and arr.shape[0] == arr.shape[1] and arr.shape[1] != 3:
            return check_distance_matrix(arr, path.name)
        if arr.ndim == 2 and arr.shape[1] == 3 and arr.shape[0] != 3:
            return clean_mesh(arr, None, path.stem)
        if arr.ndim == 2 and arr.shape == (3, 3):
            return check_distance_matrix(arr, path.name)
        raise InputError(f"{path.name}: expected an (n, 3) point cloud or an N x N distance matrix, got {arr.shape}")
    return load_geometry(path, largest_component=largest_component)


def describe_input(spec: str) -> dict:
    """What ``shapecond info`` reports: counts, bounding box, components, problems.

    Mesh files are read raw (``read_mesh_arrays``) so that their problems are
    listed instead of raised; other inputs go through ``load_input`` (and raise
    ``InputError`` when unusable).  A distance matrix reports its size and
    diameter only.
    """
    spec = str(spec)
    path = Path(spec)
    if spec.startswith("demo:") or path.suffix.lower() not in MESH_SUFFIXES:
        loaded = load_input(spec)
        if not isinstance(loaded, Geometry):
            n = loaded.shape[0]
            return {"input": spec, "kind": "distance matrix", "n_vertices": n, "n_faces": None,
                    "bounding_box": None, "components": None, "boundary_edges": None,
                    "isolated_vertices": None, "diameter": float(loaded.max()), "problems": []}
        report = inspect_mesh(loaded.vertices, loaded.faces)
    else:
        vertices, faces = read_mesh_arrays(path)
        report = inspect_mesh(vertices, faces)
    return {"input": spec, **report}


def _check_file(path: Path) -> None:
    if not path.exists():
        raise InputError(f"{path}: no such file")
    if path.is_dir():
        raise InputError(f"{path}: is a directory, not a shape file")
    if path.stat().st_size == 0:
        raise InputError(f"{path}: the file is empty")


def _load_npy(path: Path) -> np.ndarray:
    _check_file(path)
    try:
        arr = np.load(path, allow_pickle=False)
    except Exception as exc:  # numpy raises several types for broken files
        raise InputError(f"{path.name}: not a readable .npy array ({exc.__class__.__name__})") from None
    if not np.issubdtype(arr.dtype, np.number):
        raise InputError(f"{path.name}: the array does not hold numbers")
    return arr


def load_geometry(path, largest_component: bool = False) -> Geometry:
    """Read a mesh or point cloud file into a validated ``Geometry``."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in (".vert", ".tri"):
        vertices, faces = _read_tosca(path)
    elif suffix in MESH_SUFFIXES:
        vertices, faces = read_mesh_arrays(path)
    elif suffix in CLOUD_SUFFIXES:
        vertices, faces = _read_text_cloud(path), None
    elif suffix == ".npy":
        arr = _load_npy(path)
        if arr.ndim != 2 or arr.shape[1] != 3:
            raise InputError(f"{path.name}: expected an (n, 3) array of points, got {arr.shape}")
        vertices, faces = arr, None
    else:
        raise InputError(f"{path.name}: unknown file type {suffix or '(none)'}; "
                         "use OFF, OBJ, PLY, STL, .vert/.tri, .xyz, .txt or .npy")
    return clean_mesh(vertices, faces, path.stem, largest_component=largest_component)


def read_mesh_arrays(path: Path):
    """Raw (vertices, faces or None) of an OFF/OBJ/PLY/STL file, without validation."""
    import trimesh

    path = Path(path)
    _check_file(path)
    try:
        loaded = trimesh.load(str(path), process=False, maintain_order=True)
    except Exception as exc:
        raise InputError(f"{path.name}: not a readable mesh ({exc.__class__.__name__}: {str(exc)[:80]})") from None
    if isinstance(loaded, trimesh.Scene):
        geoms = list(loaded.geometry.values())
        if len(geoms) != 1:
            raise InputError(f"{path.name}: holds {len(geoms)} geometries, expected one mesh or point cloud")
        loaded = geoms[0]
    vertices = np.asarray(getattr(loaded, "vertices", np.zeros((0, 3))), dtype=np.float64)
    faces = getattr(loaded, "faces", None)
    if faces is not None:
        faces = np.asarray(faces)
        if faces.size == 0 and suffix_is_cloud_capable(path):
            faces = None
    if vertices.shape[0] == 0:
        raise InputError(f"{path.name}: no vertices found (empty, truncated or not a mesh)")
    if path.suffix.lower() == ".stl" and faces is not None:
        vertices, faces = _merge_stl_corners(vertices, faces)
    return vertices, faces


def _merge_stl_corners(vertices: np.ndarray, faces: np.ndarray):
    """STL stores three corners per triangle: merge equal corners, numbered by first use."""
    _, first, inverse = np.unique(vertices, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    return vertices[first[order]], rank[inverse.ravel()][faces]


def suffix_is_cloud_capable(path: Path) -> bool:
    return path.suffix.lower() in (".ply", ".obj")


def _read_text_cloud(path: Path) -> np.ndarray:
    _check_file(path)
    try:
        arr = np.loadtxt(path, ndmin=2, comments="#")
    except Exception:
        raise InputError(f"{path.name}: not a text file of point coordinates") from None
    if arr.shape[1] < 3:
        raise InputError(f"{path.name}: expected at least 3 columns (x y z), got {arr.shape[1]}")
    return arr[:, :3]


def _read_tosca(path: Path):
    vert, tri = path.with_suffix(".vert"), path.with_suffix(".tri")
    for p in (vert, tri):
        _check_file(p)
    try:
        vertices = np.loadtxt(vert, ndmin=2)
        faces = np.loadtxt(tri, ndmin=2)
    except Exception:
        raise InputError(f"{path.stem}: the .vert/.tri pair is not numeric text") from None
    if vertices.shape[1] != 3 or faces.shape[1] != 3:
        raise InputError(f"{path.stem}: .vert needs 3 columns and .tri 3 columns")
    if np.any(faces != np.round(faces)):
        raise InputError(f"{path.stem}: .tri holds non-integer indices")
    return vertices, faces.astype(np.int64) - 1  # TOSCA faces are 1-based


def read_landmarks(path) -> np.ndarray:
    """Vertex ids from a text file: first column of each non-empty line (e.g. BIM ``.pid``)."""
    path = Path(path)
    _check_file(path)
    ids = []
    for k, line in enumerate(path.read_text().splitlines(), 1):
        line = line.split("#")[0].strip()
        if not line:
            continue
        tok = line.replace(",", " ").split()[0]
        try:
            value = float(tok)
        except ValueError:
            raise InputError(f"{path.name}:{k}: {tok!r} is not a vertex id") from None
        if value != int(value) or value < 0:
            raise InputError(f"{path.name}:{k}: {tok!r} is not a non-negative integer vertex id")
        ids.append(int(value))
    if not ids:
        raise InputError(f"{path.name}: no landmark ids found")
    return np.asarray(ids, dtype=np.int64)


def read_symmetry_map(path) -> np.ndarray:
    """A ``.sym`` file: line i holds the 1-based id of the vertex symmetric to vertex i."""
    path = Path(path)
    _check_file(path)
    try:
        sym = np.loadtxt(path, ndmin=1)
    except Exception:
        raise InputError(f"{path.name}: a symmetry map must hold one integer per line") from None
    if sym.ndim != 1 or np.any(sym != np.round(sym)) or sym.min() < 1:
        raise InputError(f"{path.name}: a symmetry map holds 1-based integer vertex ids, one per line")
    return sym.astype(np.int64) - 1


@contextlib.contextmanager
def atomic_write(path):
    """Yield a temporary path beside ``path``; rename it onto ``path`` only on success."""
    path = Path(path)
    if path.parent and not path.parent.exists():
        raise InputError(f"{path}: the folder {path.parent} does not exist")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent or ".")
    os.close(fd)
    try:
        yield Path(tmp)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def write_mesh(path, vertices, faces, colors=None) -> None:
    """Write a mesh (or a point cloud when ``faces`` is None) with optional RGB(A) colours."""
    import trimesh

    path = Path(path)
    if faces is None:
        obj = trimesh.PointCloud(vertices, colors=colors)
    else:
        obj = trimesh.Trimesh(vertices, faces, vertex_colors=colors, process=False)
    with atomic_write(path) as tmp:
        obj.export(str(tmp), file_type=path.suffix.lstrip(".").lower() or "ply")
