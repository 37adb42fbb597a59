"""Reading shapes and symmetry maps; writing meshes.

Supported inputs
----------------
* meshes: OFF and OBJ (strict readers of ``formats``), PLY and STL through
  trimesh with ``process=False`` (vertex order is kept) after checking them
  against their headers, and TOSCA ``.vert``/``.tri`` pairs (1-based faces);
* point clouds: ``.xyz``/``.txt`` (first three columns), ``.npy`` of shape (n, 3),
  PLY or OBJ without faces;
* an N x N distance matrix as ``.npy``, or the ``.npz`` written by ``shapecond
  sample`` (its matrix ``D``, rows in FPS order);
* ``demo:NAME[:key=value,...]``: a generated shape (``shapecond.shapes.synthetic``).

Every problem is one ``InputError`` naming the file; files larger than
``formats.MAX_INPUT_BYTES`` are refused before they are read unless ``force``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..checks import check_distance_matrix
from ..errors import InputError
from ..output import atomic_open
from . import formats
from .geometry import Geometry
from .validate import clean_mesh, inspect_mesh

MESH_SUFFIXES = {".off", ".obj", ".ply", ".stl"}
CLOUD_SUFFIXES = {".xyz", ".txt"}


def parse_demo_spec(spec: str) -> tuple[str, dict]:
    """``demo:animal:delta=0.05,resolution=0.02`` -> ("animal", {"delta": "0.05", ...}).

    Values stay strings: ``synthetic.generate`` checks them against each
    generator's parameter ranges.
    """
    parts = spec.split(":", 2)
    name = parts[1] if len(parts) > 1 else ""
    params = {}
    if len(parts) == 3 and parts[2]:
        for item in parts[2].split(","):
            key, sep, value = item.partition("=")
            if not sep or not key.strip():
                raise InputError(f"bad demo parameter {item!r}: expected key=value")
            if key.strip() in params:
                raise InputError(f"demo parameter {key.strip()!r} is given twice")
            params[key.strip()] = value.strip()
    return name, params


def load_input(spec, largest_component: bool = False, force: bool = False):
    """A ``Geometry`` for a mesh, point cloud or ``demo:NAME``; an (N, N) array for a matrix."""
    spec = str(spec)
    if spec.startswith("demo:"):
        from .synthetic import generate

        name, params = parse_demo_spec(spec)
        return generate(name, params, force=force)
    path = Path(spec)
    if path.suffix.lower() == ".npz":
        return load_sample_archive(path, force)
    if path.suffix.lower() == ".npy":
        arr = load_npy(path, force)
        if arr.ndim == 2 and arr.shape[0] == arr.shape[1] and arr.shape[1] != 3:
            return check_distance_matrix(arr, path.name, min_points=3, distinct=True)
        if arr.ndim == 2 and arr.shape[1] == 3 and arr.shape[0] != 3:
            return clean_mesh(arr, None, path.stem)
        if arr.shape == (3, 3):
            try:
                return check_distance_matrix(arr, path.name, min_points=3, distinct=True)
            except InputError as exc:
                reason = str(exc).split(": ", 1)[-1]
                raise InputError(f"{path.name}: a 3 x 3 array is neither a distance matrix ({reason}) nor "
                                 "enough points for a point cloud") from None
        raise InputError(f"{path.name}: expected an (n, 3) point cloud or an N x N distance matrix, got {arr.shape}")
    return load_geometry(path, largest_component=largest_component, force=force)


def describe_input(spec: str, force: bool = False) -> dict:
    """What ``shapecond info`` reports: counts, bounding box, components, problems.

    Mesh files are read raw (``read_mesh_arrays``) so that their problems are
    listed instead of raised; other inputs go through ``load_input`` (and raise
    ``InputError`` when unusable).  A distance matrix reports its size and
    diameter only.
    """
    spec = str(spec)
    path = Path(spec)
    if spec.startswith("demo:") or path.suffix.lower() not in MESH_SUFFIXES:
        loaded = load_input(spec, force=force)
        if not isinstance(loaded, Geometry):
            n = loaded.shape[0]
            return {"input": spec, "kind": "distance matrix", "n_vertices": n, "n_faces": None,
                    "bounding_box": None, "components": None, "boundary_edges": None,
                    "isolated_vertices": None, "diameter": float(loaded.max()), "problems": []}
        report = inspect_mesh(loaded.vertices, loaded.faces)
    else:  # read raw so that problems are reported instead of raised
        vertices, faces = read_mesh_arrays(path, force)
        report = inspect_mesh(vertices, faces)
    return {"input": spec, **report}


def load_npy(path: Path, force: bool = False) -> np.ndarray:
    """A real numeric array from a ``.npy`` file (checked before it is read whole)."""
    formats.check_file(path, force)
    try:
        arr = np.load(path, allow_pickle=False, mmap_mode="r")
    except Exception as exc:  # numpy raises several types for broken files
        raise InputError(f"{path.name}: not a readable .npy array ({exc.__class__.__name__})") from None
    if not isinstance(arr, np.ndarray):
        raise InputError(f"{path.name}: holds several arrays (an .npz archive?), expected one .npy array")
    if np.iscomplexobj(arr):
        raise InputError(f"{path.name}: the array holds complex numbers; expected real coordinates or distances")
    if not (np.issubdtype(arr.dtype, np.number) or arr.dtype == bool):
        raise InputError(f"{path.name}: the array does not hold numbers (dtype {arr.dtype})")
    return np.array(arr)


def load_sample_archive(path: Path, force: bool = False) -> np.ndarray:
    """The distance matrix ``D`` of an ``.npz`` written by ``shapecond sample`` (validated)."""
    formats.check_file(path, force)
    try:
        with np.load(path, allow_pickle=False) as z:
            if "D" not in z.files:
                raise InputError(f"{path.name}: an .npz input must hold a distance matrix 'D' "
                                 f"(as written by shapecond sample); it holds {', '.join(z.files) or 'nothing'}")
            D = z["D"]
    except InputError:
        raise
    except Exception as exc:  # a damaged archive fails in several ways
        raise InputError(f"{path.name}: not a readable .npz archive ({exc.__class__.__name__})") from None
    return check_distance_matrix(D, path.name, min_points=3, distinct=True)


def load_geometry(path, largest_component: bool = False, force: bool = False) -> Geometry:
    """Read a mesh or point cloud file into a validated ``Geometry``."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in (".vert", ".tri"):
        vertices, faces = _read_tosca(path, force)
    elif suffix in MESH_SUFFIXES:
        vertices, faces = read_mesh_arrays(path, force)
    elif suffix in CLOUD_SUFFIXES:
        vertices, faces = _read_text_cloud(path, force), None
    elif suffix == ".npy":
        arr = load_npy(path, force)
        if arr.ndim != 2 or arr.shape[1] != 3:
            raise InputError(f"{path.name}: expected an (n, 3) array of points, got {arr.shape}")
        vertices, faces = arr, None
    else:
        raise InputError(f"{path.name}: unknown file type {suffix or '(none)'}; "
                         "use OFF, OBJ, PLY, STL, .vert/.tri, .xyz, .txt or .npy")
    return clean_mesh(vertices, faces, path.stem, largest_component=largest_component)


def read_mesh_arrays(path, force: bool = False):
    """Raw (vertices, faces or None) of an OFF/OBJ/PLY/STL file, checked against its header.

    Truncated or over-long files are refused here; the mesh itself is not
    validated (``validate.inspect_mesh`` reports on it, ``clean_mesh`` refuses).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".off":
        return formats.read_off(path, force)
    if suffix == ".obj":
        return formats.read_obj(path, force)
    if suffix == ".ply":
        counts = formats.check_ply(path, force)
    else:
        formats.check_stl(path, force)
        counts = None
    import trimesh

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
        if faces.size == 0 and suffix == ".ply":
            faces = None
    if vertices.shape[0] == 0:
        raise InputError(f"{path.name}: no vertices found (empty, truncated or not a mesh)")
    if counts is not None and counts.get("vertex", vertices.shape[0]) != vertices.shape[0]:
        raise InputError(f"{path.name}: the header declares {counts['vertex']} vertices, "
                         f"{vertices.shape[0]} were read")
    if suffix == ".stl" and faces is not None:
        vertices, faces = _merge_stl_corners(vertices, faces)
    return vertices, faces


def _merge_stl_corners(vertices: np.ndarray, faces: np.ndarray):
    """STL stores three corners per triangle: merge equal corners, numbered by first use."""
    _, first, inverse = np.unique(vertices, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    return vertices[first[order]], rank[inverse.ravel()][faces]


def _table(path: Path, force: bool, what: str) -> np.ndarray:
    """A numeric text table (rows of equal length) with one-line errors."""
    text = formats.read_text(path, force)
    rows = [ln.split("#", 1)[0].replace(",", " ").split() for ln in text.splitlines()]
    rows = [r for r in rows if r]
    if not rows:
        raise InputError(f"{path.name}: no {what} found")
    width = len(rows[0])
    if any(len(r) != width for r in rows):
        k = next(i for i, r in enumerate(rows) if len(r) != width)
        raise InputError(f"{path.name}: row {k + 1} has {len(rows[k])} values, the first row {width}")
    try:
        return np.array(rows, dtype=np.float64)
    except ValueError:
        raise InputError(f"{path.name}: not a text file of numbers ({what})") from None


def _read_text_cloud(path: Path, force: bool = False) -> np.ndarray:
    arr = _table(path, force, "point coordinates")
    if arr.shape[1] < 3:
        raise InputError(f"{path.name}: expected at least 3 columns (x y z), got {arr.shape[1]}")
    return arr[:, :3]


def _read_tosca(path: Path, force: bool = False):
    vert, tri = path.with_suffix(".vert"), path.with_suffix(".tri")
    vertices = _table(vert, force, "vertices")
    faces = _table(tri, force, "triangles")
    if vertices.shape[1] != 3 or faces.shape[1] != 3:
        raise InputError(f"{path.stem}: .vert needs 3 columns and .tri 3 columns")
    if not np.all(np.isfinite(faces)) or np.any(faces != np.round(faces)):
        raise InputError(f"{path.stem}: .tri holds non-integer indices")
    return vertices, faces.astype(np.int64) - 1  # TOSCA faces are 1-based


def read_symmetry_map(path, force: bool = False) -> np.ndarray:
    """A ``.sym`` file: line i holds the 1-based id of the vertex symmetric to vertex i."""
    path = Path(path)
    sym = _table(path, force, "symmetry map")
    if sym.shape[1] != 1 or not np.all(np.isfinite(sym)) or np.any(sym != np.round(sym)) or sym.min() < 1 \
            or sym.max() > 2**62:
        raise InputError(f"{path.name}: a symmetry map holds 1-based integer vertex ids, one per line")
    return sym[:, 0].astype(np.int64) - 1


def write_mesh(path, vertices, faces, colors=None, file_type: str | None = None) -> None:
    """Write a mesh (or a point cloud when ``faces`` is None) with optional RGB(A) colours.

    The format follows the suffix (``file_type`` overrides it; PLY without one);
    vertex order is kept and the file is written atomically.  Text formats (OFF,
    OBJ) are written with fixed decimals, enough for 10 significant digits of the
    largest coordinate, so a tiny shape keeps its size (trimesh's default of 10
    decimals wrote a mesh scaled by 1e-25 as one point).
    """
    import trimesh

    path = Path(path)
    if faces is None:
        obj = trimesh.PointCloud(vertices, colors=colors)
    else:
        obj = trimesh.Trimesh(vertices, faces, vertex_colors=colors, process=False)
    kind = file_type or path.suffix.lstrip(".").lower() or "ply"
    options = {"digits": _decimals(vertices)} if kind in ("off", "obj") else {}
    with atomic_open(path) as fh:
        obj.export(file_obj=fh, file_type=kind, **options)


def _decimals(vertices) -> int:
    """Fixed decimals that keep 10 significant digits of the largest finite coordinate (at least 10)."""
    V = np.asarray(vertices, dtype=float)
    top = float(np.max(np.abs(V[np.isfinite(V)]), initial=0.0))
    return 10 if top == 0 or top >= 1 else min(10 + int(np.ceil(-np.log10(top))), 340)


__all__ = ["CLOUD_SUFFIXES", "MESH_SUFFIXES", "load_geometry", "load_input", "load_npy",
           "load_sample_archive", "parse_demo_spec", "read_mesh_arrays", "read_symmetry_map", "write_mesh"]
