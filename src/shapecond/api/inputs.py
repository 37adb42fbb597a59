"""Inputs: the one way a user's shape becomes a ``Geometry``, a distance matrix or a ``MetricShape``.

Every function of ``shapecond`` takes the shape the way a user has it and
validates it as the command line does (one :class:`~shapecond.errors.InputError`
with a one-line message for anything unusable):

* a path (mesh, point cloud, ``.npy`` matrix, the ``.npz`` of ``shapecond
  sample``) or ``"demo:NAME[:key=value,...]"``;
* a ``trimesh.Trimesh`` (or ``trimesh.PointCloud``);
* a ``(V, F)`` pair of arrays (``F = None``: a point cloud);
* an (n, 3) array of points (a NumPy array, a trimesh ``TrackedArray``, nested
  lists), or an N x N distance matrix;
* a ``Geometry`` or (where a metric shape is needed) a ``MetricShape``.

Vertex ids, in and out, are the input's own: row indices of ``V`` or of the
file (unreferenced vertices are dropped internally and mapped back), rows for
a matrix.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..checks import check_distance_matrix, check_int, parse_ids
from ..errors import InputError
from ..shapes.geometry import Geometry
from ..shapes.io import describe_input, load_input, read_symmetry_map
from ..shapes.metric import MetricShape, build_metric_shape, from_distance_matrix
from ..shapes.validate import clean_mesh
from .options import ShapeOptions
from .params import DEFAULT_POINTS, FIRST_LANDMARKS, POINTS, SHAPE_PARAMS, check_keywords

#: The options of ``metric_shape``, each declared once (``params``): N, the landmarks sampled first and
#: the shape options (``options.ShapeOptions``).
METRIC_SHAPE_PARAMS = (POINTS, FIRST_LANDMARKS, *SHAPE_PARAMS)


def _from_array(a: np.ndarray, name: str):
    if a.ndim == 2 and a.shape[0] == a.shape[1] and a.shape[1] != 3:
        return check_distance_matrix(a, name, min_points=3, distinct=True)
    if a.ndim == 2 and a.shape == (3, 3):
        try:
            return check_distance_matrix(a, name, min_points=3, distinct=True)
        except InputError as exc:
            raise InputError(f"{name}: a 3 x 3 array is neither a distance matrix "
                             f"({str(exc).split(': ', 1)[-1]}) nor enough points for a point cloud") from None
    if a.ndim == 2 and a.shape[1] == 3:
        return clean_mesh(a, None, name)
    raise InputError(f"{name}: expected an (n, 3) point cloud or an N x N distance matrix, got shape {a.shape}")


def _is_trimesh_object(x) -> bool:
    """A ``trimesh.Trimesh`` or ``PointCloud`` (not any object of the trimesh package: a
    ``TrackedArray`` of vertices is an array)."""
    return type(x).__module__.startswith("trimesh") and hasattr(x, "vertices") and not isinstance(x, np.ndarray)


def _loaded(x, largest_component: bool, force: bool):
    if isinstance(x, (Geometry, MetricShape)):
        return x
    if isinstance(x, (str, Path)):
        return load_input(str(x), largest_component=largest_component, force=force)
    if _is_trimesh_object(x):
        faces = getattr(x, "faces", None)
        return clean_mesh(np.asarray(x.vertices), None if faces is None else np.asarray(faces),
                          type(x).__name__.lower(), largest_component=largest_component)
    if isinstance(x, (tuple, list)) and len(x) == 2 and np.ndim(x[0]) == 2:
        return clean_mesh(x[0], x[1], "mesh", largest_component=largest_component)
    if isinstance(x, (np.ndarray, list, tuple)):
        try:
            a = np.asarray(x)
        except (TypeError, ValueError):
            raise InputError(f"cannot read a shape from a {type(x).__name__} of this shape") from None
        return _from_array(a, "array")
    raise InputError(f"cannot read a shape from a {type(x).__name__}: give a path, a trimesh.Trimesh, "
                     "(V, F), an (n, 3) array or a distance matrix")


def load(x, *, largest_component: bool = False, symmetry_map=None, force: bool = False):
    """The input ``x`` as a validated ``Geometry`` (mesh or point cloud) or distance matrix.

    Parameters
    ----------
    x : path, ``"demo:NAME"``, trimesh object, ``(V, F)``, (n, 3) points, N x N matrix or Geometry
    largest_component : keep only the largest connected component of a mesh.
    symmetry_map : a ``.sym`` path or an array (mirror vertex id of each vertex id).
    force : read files beyond the size limit (``shapes.formats.MAX_INPUT_BYTES``).

    Returns
    -------
    Geometry, or a read-only (N, N) float64 array for a distance matrix.

    Examples
    --------
    >>> import numpy as np, shapecond as sc
    >>> sc.load(np.random.default_rng(0).random((50, 3))).n_vertices
    50
    """
    loaded = _loaded(x, largest_component, force)
    if symmetry_map is not None:
        if not isinstance(loaded, Geometry):
            raise InputError("a symmetry map needs a mesh or point cloud input")
        sym = read_symmetry_map(symmetry_map) if isinstance(symmetry_map, (str, Path)) else symmetry_map
        loaded = loaded.with_symmetry(sym)
    return loaded


def info(x) -> dict:
    """What is in the file ``x`` and what is wrong with it (what ``shapecond info --json`` prints).

    Keys: input, kind, n_vertices, n_faces, components, boundary_edges,
    isolated_vertices, bounding_box, problems (a list of one-line strings).

    Examples
    --------
    >>> import shapecond as sc
    >>> report = sc.info("demo:animal")
    >>> report["kind"], report["problems"]
    ('mesh', [])
    """
    if not isinstance(x, (str, Path)):
        raise InputError("info() describes a file: give its path (or a demo:NAME specification)")
    return describe_input(str(x))


def metric_shape(x, n_points: int | None = None, *, landmarks=(), **options) -> MetricShape:
    """N farthest-point samples of ``x`` with their distance matrix (diameter 1).

    Parameters
    ----------
    x : any input of ``load``, or a ``MetricShape`` (returned as it is).
    n_points : N (default 400, or every vertex of a smaller shape); must be left
        out (or equal N) for a distance matrix, which is used whole.
    landmarks : input ids placed first among the samples.
    **options : the fields of ``ShapeOptions``: ``metric``, ``backend``, ``seed``, ``target``
        ("dense": M = ``target_factor`` x N targets, the default for meshes and clouds;
        "samples": the paper's bijections), ``target_factor``, ``cache``, ``progress``,
        ``force``, ``largest_component``, ``symmetry_map``.  Every keyword, its constraint and
        default: ``METRIC_SHAPE_PARAMS``; a bad value or an unknown keyword is refused before any work.

    Examples
    --------
    >>> import shapecond as sc
    >>> shape = sc.metric_shape("demo:sphere:subdivisions=2", 20, target="samples", cache=False)
    >>> shape.n_samples, float(shape.D.max())
    (20, 1.0)
    """
    v = check_keywords(METRIC_SHAPE_PARAMS, dict(options, n_points=n_points, landmarks=landmarks), "metric_shape")
    return shape_of(x, v["n_points"], v["landmarks"], ShapeOptions.of(v))


def shape_of(x, n_points, landmarks, opts: ShapeOptions) -> MetricShape:
    """``metric_shape`` with its options already validated (what the other functions call)."""
    ids = parse_ids(landmarks)
    loaded = load(x, largest_component=opts.largest_component, symmetry_map=opts.symmetry_map, force=opts.force)
    if isinstance(loaded, MetricShape):
        if ids and list(loaded.sample_ids[:len(ids)]) != ids:
            raise InputError("a MetricShape is used as it is: its first samples are not these landmarks")
        return loaded
    if n_points is not None:
        n_points = check_int(n_points, "n_points", lo=3)
    if isinstance(loaded, np.ndarray):
        return _matrix_shape(loaded, n_points, ids, opts, str(x) if isinstance(x, (str, Path)) else "matrix")
    n = min(DEFAULT_POINTS, loaded.n_vertices) if n_points is None else n_points
    return build_metric_shape(loaded, n, loaded.to_internal(ids), opts.sampling("dense"))


def _matrix_shape(D: np.ndarray, n_points, ids, opts: ShapeOptions, name: str) -> MetricShape:
    n = D.shape[0]
    if n_points is not None and n_points != n:
        raise InputError(f"n_points does not apply to a distance matrix ({n} x {n}); it is used whole")
    if opts.target == "dense":
        raise InputError("dense targets need a mesh or point cloud, not a distance matrix")
    bad = [v for v in ids if v >= n]
    if bad:
        raise InputError(f"landmark {bad[0]} is out of range for a {n} x {n} distance matrix (rows 0..{n - 1})")
    return from_distance_matrix(D, landmarks=ids, name=name)


def require_mesh(g):
    """``g`` if it is a triangle mesh; ``InputError`` for a point cloud or a distance matrix."""
    if not isinstance(g, Geometry) or not g.is_mesh:
        raise InputError("the local score needs a triangle mesh (a point cloud or distance matrix has "
                         "no surface to deform)")
    return g


__all__ = ["METRIC_SHAPE_PARAMS", "info", "load", "metric_shape", "require_mesh", "shape_of"]
