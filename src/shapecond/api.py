"""The Python interface: ``import shapecond as sc``.

Every function takes the shape the way a user has it and validates it as the
command line does (one :class:`~shapecond.errors.InputError` with a one-line
message for anything unusable):

* a path (mesh, point cloud, ``.npy`` matrix, the ``.npz`` of ``shapecond
  sample``) or ``"demo:NAME[:key=value,...]"``;
* a ``trimesh.Trimesh`` (or ``trimesh.PointCloud``);
* a ``(V, F)`` pair of arrays (``F = None``: a point cloud);
* an (n, 3) array of points, or an N x N distance matrix;
* a ``Geometry`` or (where a metric shape is needed) a ``MetricShape``.

Vertex ids, in and out, are the input's own: row indices of ``V`` or of the file
(unreferenced vertices are dropped internally and mapped back), rows for a
matrix.  Results have a readable ``repr``, a ``to_dict()`` that is valid JSON as
it is (``inf`` as ``"inf"``), and pictures are drawn onto a matplotlib Figure
(``result.plot(fig)``) without touching the global backend.

:class:`SymmetryProblem` keeps one metric shape and the searches already run on
it, so repeated queries (scores with several landmark sets, heat maps, CNBS)
share their work, as potpourri3d's solvers do.

Examples
--------
>>> import shapecond as sc
>>> result = sc.score("demo:sphere:subdivisions=2", n_points=20, cache=False)
>>> result.sigma
(inf, inf)
>>> result.verdict.startswith("exact symmetry")
True
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .checks import check_float, check_int, check_seed, parse_ids
from .errors import InputError
from .jsonable import jsonable
from .shapes.geometry import Geometry
from .shapes.metric import MetricShape

DEFAULT_POINTS = 400


# --- inputs --------------------------------------------------------------------------

def _from_array(arr, name: str):
    from .checks import check_distance_matrix
    from .shapes.validate import clean_mesh

    a = np.asarray(arr)
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
    """
    from .shapes.io import load_input, read_symmetry_map
    from .shapes.validate import clean_mesh

    if isinstance(x, (Geometry, MetricShape)):
        loaded = x
    elif isinstance(x, (str, Path)):
        loaded = load_input(str(x), largest_component=largest_component, force=force)
    elif type(x).__module__.startswith("trimesh"):
        faces = getattr(x, "faces", None)
        loaded = clean_mesh(np.asarray(x.vertices), None if faces is None else np.asarray(faces),
                            type(x).__name__.lower(), largest_component=largest_component)
    elif isinstance(x, (tuple, list)) and len(x) == 2 and np.ndim(x[0]) == 2:
        loaded = clean_mesh(x[0], x[1], "mesh", largest_component=largest_component)
    elif isinstance(x, np.ndarray) or isinstance(x, (list, tuple)):
        try:
            loaded = _from_array(np.asarray(x), "array")
        except (TypeError, ValueError) as exc:
            if isinstance(exc, InputError):
                raise
            raise InputError(f"cannot read a shape from a {type(x).__name__} of this shape") from None
    else:
        raise InputError(f"cannot read a shape from a {type(x).__name__}: give a path, a trimesh.Trimesh, "
                         "(V, F), an (n, 3) array or a distance matrix")
    if symmetry_map is not None:
        if not isinstance(loaded, Geometry):
            raise InputError("a symmetry map needs a mesh or point cloud input")
        sym = read_symmetry_map(symmetry_map) if isinstance(symmetry_map, (str, Path)) else symmetry_map
        loaded = loaded.with_symmetry(sym)
    return loaded


def metric_shape(x, n_points: int | None = None, *, landmarks=(), metric: str = "geodesic",
                 backend: str = "heat", seed: int = 0, target: str | None = None, target_factor: int = 8,
                 cache: bool = True, progress: bool = False, force: bool = False,
                 largest_component: bool = False, symmetry_map=None) -> MetricShape:
    """N farthest-point samples of ``x`` with their distance matrix (diameter 1).

    Parameters
    ----------
    n_points : N (default 400, or every vertex of a smaller shape); must be left
        out (or equal N) for a distance matrix, which is used whole.
    landmarks : input ids placed first among the samples.
    metric, backend : "geodesic" (``backend`` "heat", "fmm" or "exact") or "euclidean".
    target : "dense" (default for meshes and clouds: M = ``target_factor`` x N targets)
        or "samples" (the paper's bijections; the only choice for a matrix).
    cache : read and write the on-disk cache (``shapecond.cache``).
    force : run even when the estimated time or memory is beyond ``shapecond.limits``.
    """
    from .shapes.metric import from_distance_matrix, metric_shape as sample

    ids = parse_ids(landmarks)
    loaded = load(x, largest_component=largest_component, symmetry_map=symmetry_map, force=force)
    if isinstance(loaded, MetricShape):
        if ids and list(loaded.sample_ids[:len(ids)]) != ids:
            raise InputError("a MetricShape is used as it is: its first samples are not these landmarks")
        return loaded
    if n_points is not None:
        n_points = check_int(n_points, "n_points", lo=3)
    if isinstance(loaded, np.ndarray):
        n = loaded.shape[0]
        if n_points is not None and n_points != n:
            raise InputError(f"n_points does not apply to a distance matrix ({n} x {n}); it is used whole")
        if target == "dense":
            raise InputError("dense targets need a mesh or point cloud, not a distance matrix")
        bad = [v for v in ids if v >= n]
        if bad:
            raise InputError(f"landmark {bad[0]} is out of range for a {n} x {n} distance matrix (rows 0..{n - 1})")
        return from_distance_matrix(loaded, landmarks=ids, name=str(x) if isinstance(x, (str, Path)) else "matrix")
    n = min(DEFAULT_POINTS, loaded.n_vertices) if n_points is None else n_points
    return sample(loaded, n_points=n, metric=metric, backend=backend, seed=seed,
                  landmarks=loaded.to_internal(ids), target="dense" if target is None else target,
                  target_factor=target_factor, cache=cache, progress=progress, force=force)


_SHAPE_KEYS = ("metric", "backend", "seed", "target", "target_factor", "cache", "progress", "force",
               "largest_component", "symmetry_map")


def _split(kw: dict) -> tuple[dict, dict]:
    shape = {k: kw.pop(k) for k in _SHAPE_KEYS if k in kw}
    return shape, kw


# --- scores --------------------------------------------------------------------------

def score(x, n_points: int | None = None, *, landmarks=(), exact="auto", upper: bool = False,
          time_limit: float | None = 10.0, effort: str = "default", epsilon: float | None = None, **options):
    """How hard ``x`` is to match: the σ bracket (paper Eq. 5), κ bracket, witness, δ(ε) and verdict.

    Parameters
    ----------
    x : any input of ``load``, or a ``MetricShape``.
    n_points, landmarks : samples N and fixed landmarks (input ids); see ``metric_shape``.
    exact : "auto" (exact σ when enumeration is quick), True or False.
    upper : LP upper bound when σ is not exact (N <= 16 free samples).
    time_limit : seconds for each of the exact and LP solves.
    epsilon : distortion level of the scale-aware score δ(ε) (default: the median sample spacing).
    **options : ``seed``, ``force`` and the options of ``metric_shape``.

    Returns
    -------
    ScoreResult: ``.sigma``, ``.kappa``, ``.verdict``, ``.score`` (SymmetryScore),
    ``.scale`` (ScaleScore, δ(ε)), ``.witness_ids``, ``.to_dict()`` (the JSON of
    ``shapecond score --json``), ``.plot()``.
    """
    from .symmetry.report import score_shape
    from .symmetry.score import check_exact

    shape_kw, rest = _split(dict(options))
    if rest:
        raise InputError(f"score() got unknown options: {', '.join(rest)}")
    check_exact(exact)
    shape = metric_shape(x, n_points, landmarks=landmarks, **shape_kw)
    if time_limit is not None:
        time_limit = check_float(time_limit, "time_limit", lo=0.0, lo_open=True)
    if epsilon is not None:
        epsilon = check_float(epsilon, "epsilon", lo=0.0)
    return score_shape(shape, parse_ids(landmarks), exact=exact, upper=upper, time_limit=time_limit,
                       seed=check_seed(shape_kw.get("seed", 0)), effort=effort, force=shape_kw.get("force", False),
                       epsilon=epsilon)


def require_mesh(g):
    """``g`` if it is a triangle mesh; ``InputError`` for a point cloud or a distance matrix."""
    if not isinstance(g, Geometry) or not g.is_mesh:
        raise InputError("the local score needs a triangle mesh (a point cloud or distance matrix has "
                         "no surface to deform)")
    return g


def local_score(x, landmarks=(), *, alpha: float = 1.0, energy: str = "springs", zero_tol: float | None = None,
                force: bool = False):
    """Local symmetry score σ_∞ = sqrt(2/λ_min) of deformation-based matching (paper Section 5).

    ``x`` must be a triangle mesh; ``landmarks`` are vertex ids of the input.
    Returns a ``LocalScore`` (``.score``, ``.lambda_min``, ``.zero_modes``).
    """
    from .deformation.local_score import ZERO_TOL, local_score_of_geometry

    from dataclasses import replace

    g = require_mesh(load(x, force=force))
    zero_tol = ZERO_TOL if zero_tol is None else zero_tol
    result = local_score_of_geometry(g, parse_ids(landmarks), alpha=alpha, energy=energy, zero_tol=zero_tol)
    return replace(result, drawing=(g, dict(alpha=alpha, energy=energy, zero_tol=zero_tol)))


def landmarks(x, k: int, method: str = "cnbs", n_points: int | None = None, *, user_landmarks=None,
              scores: bool | None = None, effort: str = "default", **options):
    """``k`` landmarks chosen by ``method`` (cnbs, cnbs-scale, cnbs-local, fps, pls, hks, user), with the
    score after each (σ, or δ(ε) for cnbs-scale or ``score="scale"``).

    ``user_landmarks`` (input ids) are placed first among the samples and, for
    ``method="user"``, are the landmarks.  Other keyword arguments go to
    ``metric_shape`` (seed, force, ...) or to the method (see ``select_landmarks``).
    Returns a ``LandmarkResult`` whose ``landmarks`` are input ids.
    """
    from .landmarks import check_method_options, select_landmarks

    shape_kw, method_kw = _split(dict(options))
    check_method_options(method, method_kw)  # a misspelt option is refused before the geodesics
    ids = parse_ids(user_landmarks)
    if method == "user":
        if not ids:
            raise InputError("method 'user' needs user_landmarks")
        method_kw["ids"] = ids
    shape = metric_shape(x, n_points, landmarks=ids, **shape_kw)
    k = check_int(k, "k", lo=0)
    return select_landmarks(shape, k, method, seed=check_seed(shape_kw.get("seed", 0)), scores=scores,
                            effort=effort, **method_kw)


@dataclass(frozen=True, eq=False)
class HeatMapResult:
    """σ with each sample fixed as a landmark (paper Figures 1 and 4), in the input's ids.

    Attributes
    ----------
    samples : (N,) input ids of the samples; ``values[i]`` is the score with ``samples[i]``
        fixed (NaN for the landmarks already fixed).
    sigma_before : the score with only ``landmarks`` fixed.
    best, best_value : the best next landmark and the score with it fixed.
    score : "sigma" (σ, Eq. 5) or "scale" (δ(ε)).
    """

    samples: np.ndarray
    values: np.ndarray
    sigma_before: float
    best: int
    best_value: float
    landmarks: tuple
    seconds: float
    shape: MetricShape = field(repr=False)
    score: str = "sigma"

    def to_dict(self) -> dict:
        """The JSON object of ``shapecond heatmap --json``."""
        return jsonable({"landmarks": list(self.landmarks), "score": self.score,
                         "sigma_before": self.sigma_before, "samples": self.samples, "values": self.values,
                         "best": self.best, "best_value": self.best_value, "seconds": self.seconds})

    def __repr__(self) -> str:
        return (f"HeatMapResult(N={self.samples.size}, sigma_before={self.sigma_before:.4g}, best={self.best}, "
                f"best_value={self.best_value:.4g}, landmarks={list(self.landmarks)})")

    def plot_values(self) -> np.ndarray:
        """The values drawn: landmarks at ``sigma_before``, non-finite ones at the largest finite value."""
        vals = np.where(np.isnan(self.values), self.sigma_before, self.values)
        vals = np.where(np.isfinite(vals), vals, np.nan)
        return np.where(np.isnan(vals), np.nanmax(vals) if np.any(np.isfinite(vals)) else 1.0, vals)

    def plot(self, fig=None, **kw):
        """The heat map drawn on the shape, onto ``fig`` (or a new Figure); returns the Figure."""
        from .viz.heatmap import render_heatmap_png

        L = list(range(len(self.landmarks)))
        return render_heatmap_png(self.shape, self.plot_values(), None, landmarks=L, fig=fig, **kw)

    def to_html(self, path, **kw) -> str:
        """Write the heat map as a self-contained HTML page (``shapecond.viz.pages``); returns the path."""
        from .viz.pages import write_result

        return write_result(self, path, **kw)

    def _repr_html_(self):
        from .viz.pages import inline_result

        return inline_result(self)


def heatmap(x, landmarks=(), n_points: int | None = None, *, effort: str = "default",
            resolve_fraction: float | None = None, score: str = "sigma", epsilon: float | None = None,
            **options) -> HeatMapResult:
    """σ (or δ(ε), ``score="scale"``) with each sample fixed: where the next landmark helps most."""
    return SymmetryProblem(x, n_points, landmarks=landmarks, effort=effort, **options).heatmap(
        landmarks, resolve_fraction=resolve_fraction, score=score, epsilon=epsilon)


# --- matching and evaluation -----------------------------------------------------------

@dataclass(frozen=True, eq=False)
class MatchResult:
    """A dense map source -> target in input ids (``map[i]`` = target id of source id i, -1: dropped)."""

    map: np.ndarray
    summary: dict
    drawing: tuple = field(default=None, repr=False)  # (source, target Geometry, their landmarks) for to_html

    def to_dict(self) -> dict:
        """The summary of ``shapecond match --json`` plus the map itself."""
        return jsonable({**self.summary, "map": self.map})

    def to_html(self, path, truth=None, **kw) -> str:
        """Write the map as a self-contained HTML page (colour transfer, linked landmarks and, with
        ``truth`` (target id per source id, or "same-ids"), the error field); returns the path."""
        from .viz.pages import write_result

        return write_result(self, path, truth=truth, **kw)

    def _repr_html_(self):
        from .viz.pages import inline_result

        return inline_result(self)

    def __repr__(self) -> str:
        s = self.summary
        return (f"MatchResult({s.get('matcher')}, {self.map.size} source ids -> target ids, "
                f"{s.get('n_landmarks')} landmarks, N={s.get('n_points')})")


def _matcher_bytes(matcher: str, n_points: int, n_landmarks: int, options: dict, what: str) -> float:
    """Memory of the matcher itself (LH05's dense affinity matrix), checked before any geodesic:
    beyond ``spectral.MAX_AFFINITY_BYTES`` the matcher refuses whatever ``force`` says."""
    if matcher != "lh05":
        return 0.0
    from .errors import TooLargeError
    from .limits import human_bytes, lh05_affinity_bytes
    from .matching.nested import core_size
    from .matching.spectral import MAX_AFFINITY_BYTES, lh05_match

    k = options.get("k", inspect.signature(lh05_match).parameters["k"].default)
    nested = options.get("nested", True) and core_size(n_landmarks) is not None
    nbytes = lh05_affinity_bytes(n_points, core_size(n_landmarks) if nested else n_landmarks, check_int(k, "k", lo=1))
    if nbytes > MAX_AFFINITY_BYTES:
        raise TooLargeError(f"{what}: LH05's affinity matrix would need about {human_bytes(nbytes)}, more than the "
                            f"{human_bytes(MAX_AFFINITY_BYTES)} it allows; use fewer samples or a smaller k "
                            "(--k), or the faq matcher")
    return nbytes


def _matcher_options(matcher: str, options: dict) -> dict:
    """The sample matcher's own options, refused before any work when unknown."""
    from .matching.pipeline import MATCHERS
    from .matching.seeded import faq_match
    from .matching.spectral import lh05_match

    if matcher not in MATCHERS:
        raise InputError(f"unknown matcher {matcher!r} (choose from {', '.join(MATCHERS)})")
    known = set()
    if matcher != "zoomout":
        known = set(list(inspect.signature(lh05_match if matcher == "lh05" else faq_match).parameters)[4:]) - {"seed"}
    if set(options) - known:  # refused before the geodesics, not as a TypeError after them
        raise InputError(f"match() got unknown option {sorted(set(options) - known)[0]!r} for matcher "
                         f"{matcher!r} (its options: {', '.join(sorted(known)) or 'none'})")
    return options


def _match_matrices(src, tgt, ids_s, ids_t, matcher, samples, seed, options, summary) -> MatchResult:
    from .matching.pipeline import match_samples

    if not (isinstance(src, np.ndarray) and isinstance(tgt, np.ndarray)):
        raise InputError("match two meshes/point clouds or two distance matrices, not one of each")
    if samples != "fps":
        raise InputError("samples 'same-ids' needs two meshes or point clouds, not distance matrices")
    if matcher == "zoomout":
        raise InputError("the zoomout matcher needs two meshes or point clouds (a Laplace-Beltrami basis), "
                         "not distance matrices")
    for name, ids, D in (("source", ids_s, src), ("target", ids_t, tgt)):
        bad = [v for v in ids if v >= D.shape[0]]
        if bad:
            raise InputError(f"{name} landmark {bad[0]} is out of range (rows 0..{D.shape[0] - 1})")
    if tgt.shape[0] < src.shape[0]:
        raise InputError(f"the target matrix has fewer rows ({tgt.shape[0]}) than the source ({src.shape[0]})")
    sm = match_samples(src / src.max(), tgt / tgt.max(), ids_s, ids_t, matcher, seed=seed, **options)
    summary.update(n_points=int(src.shape[0]), matcher_info=sm.info)
    return MatchResult(np.asarray(sm.t, dtype=np.int64), summary)


def match(source, target, landmarks_source, landmarks_target, *, matcher: str = "lh05",
          n_points: int = DEFAULT_POINTS, seed: int = 0, backend: str = "heat", dense: str = "zoomout",
          samples: str = "fps", cache: bool = True, force: bool = False, largest_component: bool = False,
          **options) -> MatchResult:
    """Match ``source`` to ``target`` with corresponding landmarks fixed (input ids, same order).

    Parameters
    ----------
    source, target : two meshes/point clouds (any input of ``load``), or two distance matrices
        (then the map is between their rows).
    landmarks_source, landmarks_target : corresponding input vertex ids, same order.
    matcher : "lh05" (Leordeanu–Hebert on ``n_points`` FPS samples, the paper's), "faq" (seeded
        graph matching on the samples) or "zoomout" (from the landmarks alone; at least 3).
    dense : how the map reaches every vertex: "zoomout" (landmark-anchored ZoomOut on the
        Laplace–Beltrami bases, ``matching.zoomout``), or the plain extensions of the sample
        map "distances" and "nearest" (``matching.dense``).
    samples : "fps" (each shape its own samples) or "same-ids" (the target sampled at the
        source's sample vertices: shapes with one vertex order; the summary gives the error).
    **options : the sample matcher's own options (lh05: ``k``, ``rounding``, ``refine``...).

    Returns
    -------
    MatchResult: ``.map[i]`` the target id of source id i (-1: a vertex dropped on loading).
    """
    from .limits import check_cost, geodesic_seconds, metric_bytes
    from .matching.pipeline import MatchOptions, match_shapes

    options = _matcher_options(matcher, options)
    ids_s, ids_t = parse_ids(landmarks_source, "landmarks_source"), parse_ids(landmarks_target, "landmarks_target")
    if len(ids_s) != len(ids_t):
        raise InputError(f"landmark counts differ: {len(ids_s)} on the source, {len(ids_t)} on the target")
    seed = check_seed(seed)
    opts = MatchOptions(matcher=matcher, n_points=check_int(n_points, "n_points", lo=3), backend=backend, seed=seed,
                        dense=dense, samples=samples, cache=bool(cache), matcher_options=options)
    src = load(source, largest_component=largest_component, force=force)
    tgt = load(target, largest_component=largest_component, force=force)
    summary = {"matcher": matcher, "n_landmarks": len(ids_s), "direction": "source to target"}
    if isinstance(src, np.ndarray) or isinstance(tgt, np.ndarray):
        return _match_matrices(src, tgt, ids_s, ids_t, matcher, samples, seed, options, summary)
    n = max(src.n_vertices, tgt.n_vertices)
    what = f"matching with {n_points} samples on {n} vertices ({backend} distances)"
    matcher_bytes = _matcher_bytes(matcher, n_points, len(ids_s), options, what)
    check_cost(what, 2 * geodesic_seconds(n, n_points, backend), 2 * metric_bytes(n_points, n) + matcher_bytes,
               force)
    m = match_shapes(src, tgt, src.to_internal(ids_s), tgt.to_internal(ids_t), opts)
    lines = np.full(int(src.ids.max()) + 1, -1, dtype=np.int64)
    lines[src.ids] = tgt.ids[m.vertex_map]
    summary.update(n_points=n_points, n_source_vertices=int(src.n_vertices), n_target_vertices=int(tgt.n_vertices),
                   backend=backend, dense=dense, samples=samples,
                   matcher_info=m.sample_map.info if m.sample_map is not None else {})
    if samples == "same-ids":
        summary.update(sample_error=m.info["sample_error"], exact=m.info["exact"])
    return MatchResult(lines, summary, (src, tgt, src.to_internal(ids_s), tgt.to_internal(ids_t)))


def evaluate(dataset_dir, **options):
    """The paper's Figure 7 evaluation on class folders (``shapecond.evaluation``).

    Parameters
    ----------
    dataset_dir : a folder of class folders: meshes with one vertex order (TOSCA), or
        ``shapes/`` + ``corres/*.vts`` folders (the remeshed releases), or one such class.
    **options : fields of ``shapecond.evaluation.EvaluationOptions`` (classes, methods,
        matchers, protocol, counts, n_points, seed, backend, cache, dense, n_jobs,
        scheduler, quick, max_targets, progress, force); an unknown name is refused.

    Returns
    -------
    Evaluation; write its report with ``shapecond.evaluation.report.write_report``.
    """
    from .evaluation import evaluate_dataset, evaluation_options

    opts = evaluation_options(**options)
    return evaluate_dataset(Path(dataset_dir), opts)


# --- the stateful problem ------------------------------------------------------------

class SymmetryProblem:
    """One shape's metric space with the searches already run on it, for repeated queries.

    The metric shape is built once; the witness search with each landmark set is
    run once and kept, and its best maps warm-start the CNBS heat map and landmark
    selection (the landmark-independent starts are shared).

    Parameters
    ----------
    x : any input of ``load``, or a ``MetricShape``.
    n_points, landmarks : see ``metric_shape``; ``landmarks`` (input ids) are made
        samples so that they can be fixed later.
    seed, effort : for every search.
    **options : the other options of ``metric_shape`` (metric, backend, target, cache, force...).

    Examples
    --------
    >>> import shapecond as sc
    >>> problem = sc.SymmetryProblem("demo:animal:delta=0.1", n_points=40, target="samples", cache=False)
    >>> first = problem.heatmap().best
    >>> problem.score(landmarks=[first]).sigma[0] <= problem.score().sigma[0]
    True
    """

    def __init__(self, x, n_points: int | None = None, *, landmarks=(), seed: int = 0, effort: str = "default",
                 **options):
        self.seed = check_seed(seed)
        self.effort = effort
        self.force = bool(options.get("force", False))
        self.shape = metric_shape(x, n_points, landmarks=landmarks, seed=self.seed, **options)
        self._searches: dict = {}

    def __repr__(self) -> str:
        s = self.shape
        name = s.geometry.name if s.geometry is not None else "matrix"
        return (f"SymmetryProblem({name}, N={s.n_samples}, M={s.n_targets}, {s.metric}, "
                f"{len(self._searches)} searches kept)")

    @property
    def sample_ids(self) -> np.ndarray:
        """Input ids of the samples (the candidates for landmarks)."""
        return self.shape.sample_ids

    def _indices(self, landmarks) -> tuple:
        ids = parse_ids(landmarks)
        return tuple(int(i) for i in self.shape.landmark_indices(ids))

    def search(self, landmarks=()):
        """The witness search (lower bound of σ with its maps) with ``landmarks`` fixed, kept."""
        from .symmetry.search import witness_search

        key = tuple(sorted(self._indices(landmarks)))
        if key not in self._searches:
            self._searches[key] = witness_search(self.shape.D, self.shape.n_samples, list(key), seed=self.seed,
                                                 effort=self.effort)
        return self._searches[key]

    def score(self, landmarks=(), *, exact="auto", upper: bool = False, time_limit: float | None = 10.0,
              epsilon: float | None = None):
        """``ScoreResult`` with ``landmarks`` (input ids of samples) fixed; reuses a kept search."""
        from .symmetry.report import score_shape

        ids = parse_ids(landmarks)
        return score_shape(self.shape, ids, exact=exact, upper=upper, time_limit=time_limit, seed=self.seed,
                           effort=self.effort, force=self.force, epsilon=epsilon, search=self.search(ids))

    def heatmap(self, landmarks=(), *, resolve_fraction: float | None = None, score: str = "sigma",
                epsilon: float | None = None) -> HeatMapResult:
        """σ (``score="sigma"``, warm-started from the kept search) or δ(ε) (``score="scale"``)
        with each sample fixed, ``landmarks`` fixed already."""
        import math
        import time

        from .landmarks.cnbs import RESOLVE_FRACTION, heat_map
        from .symmetry.scale import budget_of, default_epsilon

        t0 = time.perf_counter()
        ids = parse_ids(landmarks)
        L = list(self._indices(ids))
        frac = RESOLVE_FRACTION if resolve_fraction is None else resolve_fraction
        frac = check_float(frac, "resolve_fraction", lo=0.0, hi=1.0)
        n = self.shape.n_samples
        if score not in ("sigma", "scale"):
            raise InputError(f"unknown score {score!r}; choose sigma or scale")
        budget, base, unit = None, self.search(ids), 1.0
        if score == "scale":
            eps = default_epsilon(self.shape.D, n) if epsilon is None else check_float(epsilon, "epsilon", lo=0.0)
            budget, base, unit = budget_of(eps, n, self.shape.D), None, 1.0 / math.sqrt(n)
        hm = heat_map(self.shape.D, n, landmarks=L, base=base, seed=self.seed, effort=self.effort,
                      resolve_fraction=frac, budget=budget)
        best = hm.argmin()  # values in the score's units: δ = sqrt(d²) / sqrt(N)
        return HeatMapResult(np.asarray(self.shape.sample_ids), hm.values * unit, float(hm.sigma_before) * unit,
                             int(self.shape.sample_ids[best]), float(hm.values[best]) * unit, tuple(ids),
                             time.perf_counter() - t0, self.shape, score)

    def landmarks(self, k: int, method: str = "cnbs", *, fixed=(), scores: bool | None = None, **options):
        """``k`` new landmarks after ``fixed`` (input ids of samples); CNBS starts from the kept search."""
        from .landmarks import select_landmarks

        ids = parse_ids(fixed)
        L = list(self._indices(ids))
        if method == "cnbs":
            options.setdefault("base", self.search(ids))
        return select_landmarks(self.shape, check_int(k, "k", lo=0), method, seed=self.seed, scores=scores,
                                effort=self.effort, fixed=L, **options)


__all__ = ["HeatMapResult", "MatchResult", "SymmetryProblem", "evaluate", "heatmap", "landmarks", "load",
           "local_score", "match", "metric_shape", "score"]
