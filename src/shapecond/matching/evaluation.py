"""Evaluation of landmark methods by matching a class of shapes (paper Section 7, Figure 7).

A *class folder* holds shapes with the same vertex count and vertex order, so
the ground-truth correspondence is the identity on vertex ids (TOSCA).  For
each landmark method:

1. the **null shape** (lowest number in the file name) gets ``L`` landmarks
   (the paper's counts ``PAPER_LANDMARKS``) on its metric shape (N samples);
2. its symmetry score after 1, 3 and ``L`` landmarks is recorded (Figure 7a);
3. the null shape is matched to every other shape of the class with the first
   3 and with all ``L`` landmarks, target landmarks being the same vertex ids,
   by each matcher, and the error is measured (Figure 7b; ``metrics.py``).

Two protocols (``PROTOCOLS``) say which samples the target has:

``"corresponding"`` (default) — the κ setting of the paper (Eq. 4 compares a
    shape with a perturbation of *the same points*): the null shape's N
    samples (landmarks first) are carried to the target by vertex id
    (``sampled.carry_samples``, in a shuffled order), the matcher maps source
    samples to these target samples, and the error of sample ``x`` is the
    target's geodesic distance between ``T(x)`` and ``x``'s own vertex.  Also
    recorded: the fraction of samples mapped exactly, and for LH05 the recall of
    its candidates and its objective against the true map's.
``"independent"`` — each target gets its own farthest-point samples, so no
    target sample is the true image of a source sample and every map errs by
    up to a covering radius whatever its landmarks; the sample map is
    extended to a dense map (``pipeline.match_surfaces``) and its error is
    measured at the target's N samples ``g`` (the source vertex with the same
    id goes to ``p``; ``d_t(p, g)`` is read from the target's distance rows).

Per-target work is a joblib task (``run_tasks``): ``n_jobs`` local processes,
or, given a Dask scheduler address, joblib's ``"dask"`` backend on that cluster
(needs ``dask[distributed]``; every worker must see the dataset path and
should share the cache folder ``$SHAPECOND_CACHE``).
"""

from __future__ import annotations

import math
import re
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from shapecond.jsonable import jsonable
from shapecond.errors import InputError
from shapecond.matching import refine
from shapecond.matching.candidates import recall
from shapecond.matching.metrics import errors_from_rows, normalise
from shapecond.matching.pipeline import match_samples, match_surfaces
from shapecond.matching.sampled import (CachedSolver, carry_samples, insert_landmarks,
                                        sample_surface, surface_at)
from shapecond.matching.spectral import fine_kernel
from shapecond.parallel import run_tasks

#: Landmark counts of the paper's Figure 7 per TOSCA class.
PAPER_LANDMARKS = {"horse": 14, "victoria": 13, "michael": 16, "david": 15, "dog": 12,
                   "centaur": 7, "cat": 7, "wolf": 5}
DEFAULT_LANDMARKS = 10
#: Which samples a target has (module docstring).
PROTOCOLS = ("corresponding", "independent")
#: bump when the landmark methods change, to invalidate cached selections
LANDMARK_CACHE_VERSION = "7"  # 7: CNBS heat-map kicks of at most 12 swaps; 6: cnbs-scale near-ties to the farthest, fresh base per step; 5: δ(ε) scores, cnbs-scale
MESH_SUFFIXES = (".off", ".obj", ".ply")
#: Relative cost of the landmark methods on TOSCA at N = 400, for ordering the tasks only.
LANDMARK_COST = {"cnbs-scale": 4, "cnbs": 3, "cnbs-local": 2, "hks": 1}


# --- landmark methods and scores ---------------------------------------------------

def landmark_method(name: str):
    """Callable ``(shape, k, seed) -> dict(sample_indices, scores)`` for a method name."""
    from shapecond.landmarks import METHODS, select_landmarks

    if name not in METHODS:
        raise InputError(f"unknown landmark method {name!r} (choose from {', '.join(METHODS)})")

    def select(shape, k, seed=0):
        res = select_landmarks(shape, k, name, seed=seed)
        return dict(sample_indices=[int(i) for i in res.sample_indices], scores=res.scores)

    return select


def symmetry_score(D, n_samples, landmarks, seed=0, quick=False) -> float:
    """σ with the given sample indices fixed (Eq. 5): the lower bound with witness.

    ``shapecond.symmetry.score.symmetry_score`` without exact solve or LP (at
    N = 400 only the witness search's lower bound is affordable), with
    ``effort="quick"`` when ``quick``.
    """
    from shapecond.symmetry.score import symmetry_score as score

    res = score(D, n_samples, list(landmarks), exact=False, upper=False, seed=seed,
                effort="quick" if quick else "default")
    return float(res.sigma_lower)


def swap_floor(D, n_samples, landmarks) -> float:
    """σ of the best single swap avoiding the landmarks."""
    from shapecond.symmetry.search import best_single_swap

    return float(best_single_swap(D, n_samples, list(landmarks))[0])


# --- class folders -----------------------------------------------------------------

def class_shapes(folder) -> list[Path]:
    """Mesh files of a class folder, null shape first (sorted by the number in the name)."""
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(f"{folder}: not a folder")
    files = [p for p in folder.iterdir() if p.suffix.lower() in MESH_SUFFIXES]
    if len(files) < 2:
        raise InputError(f"{folder}: a class needs at least two shapes, found {len(files)}")

    def key(p):
        m = re.search(r"(\d+)$", p.stem)
        return (int(m.group(1)) if m else math.inf, p.stem)

    return sorted(files, key=key)


def find_classes(dataset_dir, classes=None) -> dict[str, Path]:
    """Class name -> folder; ``classes`` restricts (InputError for unknown names)."""
    root = Path(dataset_dir)
    if not root.is_dir():
        raise InputError(f"{root}: not a folder")
    found = {p.name: p for p in sorted(root.iterdir())
             if p.is_dir() and any(q.suffix.lower() in MESH_SUFFIXES for q in p.iterdir())}
    if classes:
        missing = [c for c in classes if c not in found]
        if missing:
            raise InputError(f"class {missing[0]!r} not found in {root} "
                             f"(found: {', '.join(found) or 'none'})")
        found = {c: found[c] for c in classes}
    if not found:
        raise InputError(f"{root}: no class folders with meshes")
    return found


def check_compatible(null, other) -> None:
    """InputError unless two shapes of a class have the same vertices (count and ids)."""
    if null.n_vertices != other.n_vertices:
        raise InputError(f"{other.name} has {other.n_vertices} vertices but {null.name} has "
                         f"{null.n_vertices}: shapes of a class need the same vertex count and order")
    if not np.array_equal(null.ids, other.ids):
        raise InputError(f"{other.name} and {null.name} do not use the same vertex ids (unreferenced "
                         "vertices differ): shapes of a class need the same vertex count and order")


# --- per-target task ---------------------------------------------------------------

@dataclass(frozen=True)
class MatchRecord:
    """One matching of the null shape to a target (one row of the evaluation)."""

    cls: str
    target: str
    method: str
    n_landmarks: int
    matcher: str
    error: float            # mean error, % of half the target's geodesic diameter
    error_area: float       # mean error / sqrt(area)
    sample_error: float     # mean sample-map error, % of half diameter
    seconds: float
    errors: np.ndarray = field(repr=False)  # per-evaluation-point errors (% half diam.)
    protocol: str = "independent"
    exact: float = math.nan          # corresponding: fraction of samples mapped exactly
    recall: float = math.nan         # corresponding, LH05: candidates holding the true match
    objective_ratio: float = math.nan  # corresponding, LH05: objective of the map / of the truth

    FIELDS = ("cls", "target", "method", "n_landmarks", "matcher", "protocol", "error", "error_area",
              "sample_error", "exact", "recall", "objective_ratio", "seconds")

    def to_dict(self) -> dict:
        return jsonable({k: getattr(self, k) for k in self.FIELDS})


def target_task(cls, null_path, target_path, landmark_sets, counts, matchers, n_points, seed,
                backend, cache, load=None, protocol="corresponding"):
    """Match the sampled null shape to one target for every setting (module docstring).

    Parameters
    ----------
    landmark_sets : dict method -> internal vertex ids (null shape) in order.
    counts : landmark counts to use (prefixes).
    load : optional callable path -> Geometry (tests); default ``load_geometry``.
    protocol : one of ``PROTOCOLS``.
    """
    from shapecond.shapes.io import load_geometry

    if protocol not in PROTOCOLS:
        raise InputError(f"unknown protocol {protocol!r} ({' or '.join(PROTOCOLS)})")
    load = load or load_geometry
    source = sample_surface(load(null_path), n_points, backend, seed, cache=cache)
    g = load(target_path)
    check_compatible(source.geometry, g)
    if protocol == "corresponding":
        tgt = surface_at(g, source.samples, backend, cache)
        solvers = (CachedSolver(source.geometry, backend, source), CachedSolver(g, backend, tgt))
    else:
        tgt = sample_surface(g, n_points, backend, seed, cache=cache)
        solvers = (CachedSolver(source.geometry, backend), CachedSolver(g, backend))
    half = 0.5 * tgt.diameter
    area = tgt.unit ** 2 if g.faces is not None else None
    out = []
    for method, lm in landmark_sets.items():
        for c in counts:
            c = min(c, len(lm))
            for matcher in matchers:
                t0 = time.perf_counter()
                extra = {}
                if protocol == "corresponding":
                    src, ls = insert_landmarks(source, lm[:c], solvers[0])
                    carried, truth = carry_samples(src, g, solvers[1], seed)
                    sm = match_samples(src.D, carried.D, ls, truth[ls], matcher, seed=seed)
                    raw = errors_from_rows(carried.rows[truth], carried.samples[sm.t])
                    raw_s = raw
                    extra["exact"] = float(np.mean(sm.t == truth))
                    if sm.candidates is not None:
                        extra["recall"] = recall(sm.candidates, truth)
                    if "h" in sm.info:
                        kern = fine_kernel(sm.info["h"])
                        extra["objective_ratio"] = sm.info["objective"] / refine.objective(
                            src.D, carried.D, truth, kern)
                else:
                    m = match_surfaces(source, tgt, lm[:c], lm[:c], matcher=matcher, seed=seed,
                                       source_solver=solvers[0], target_solver=solvers[1])
                    # evaluation points: the target's own samples (same ids on the source)
                    raw = errors_from_rows(tgt.rows, m.vertex_map[tgt.samples])
                    raw_s = errors_from_rows(m.target.rows[m.sample_map.t], m.source.samples)
                err = normalise(raw, 2 * half)
                out.append(MatchRecord(
                    cls, g.name, method, c, matcher, float(err.mean()),
                    float(normalise(raw, 2 * half, area, "sqrt_area").mean()) if area else math.nan,
                    float(normalise(raw_s, 2 * half).mean()), time.perf_counter() - t0,
                    err.astype(np.float32), protocol, **extra))
    return out


# --- orchestration -----------------------------------------------------------------

def off_vertex_count(path: Path) -> int | None:
    """Vertex count from an OFF header without reading the mesh (None if not OFF)."""
    from shapecond.shapes.formats import check_file, off_header

    if path.suffix.lower() != ".off":
        return None
    check_file(path)
    with open(path, "rb") as fh:
        head = fh.read(4096).decode("latin-1")
    lines = [ln.split("#", 1)[0].split() for ln in head.splitlines()[:-1] or head.splitlines()]
    return off_header([ln for ln in lines if ln], path.name)[0]


def prepare_task(path, n_points, seed, backend, cache, with_metric=False, null_path=None,
                 protocols=("independent",)):
    """Geodesics of one shape (warms the caches).

    The null shape (``with_metric``) gets its FPS rows and metric shape; a target
    gets its own FPS rows (``"independent"``) and/or the rows at the null shape's
    sample vertices (``"corresponding"``, needs ``null_path``).
    """
    from shapecond.shapes.io import load_geometry
    from shapecond.shapes.metric import metric_shape

    g = load_geometry(path)
    if with_metric or "independent" in protocols:
        sample_surface(g, n_points, backend, seed, cache=cache)
    if with_metric:
        metric_shape(g, n_points, backend=backend, seed=seed, cache=cache)
    if null_path is not None and "corresponding" in protocols:
        null = sample_surface(load_geometry(null_path), n_points, backend, seed, cache=cache)
        check_compatible(null.geometry, g)
        surface_at(g, null.samples, backend, cache)
    return str(path)


def landmark_task(cls, null_path, method, k, n_points, seed, backend, cache, quick):
    """Landmarks of one method on the null shape and the score after 1, 3 and k of them.

    Cached (JSON in the cache folder, keyed by the file, its size and mtime, and
    every parameter): CNBS at N = 400 takes minutes per class.

    Scores: ``symmetry_score`` (quick witness search) for every method alike, so
    that Figure 7a compares one estimator: CNBS's own heat-map values are lower
    bounds from warm starts and would not be comparable with the baselines'.
    ``floor``: the best single swap with the same landmarks, to show when a score
    is only that.  ``scale``: the scale-aware score δ(ε) (``symmetry.scale``, quick
    search, default ε) after 1, 3 and k landmarks, made non-increasing (a map
    fixing more landmarks is feasible with fewer).
    """
    from shapecond import cache as disk
    from shapecond.shapes.io import load_geometry
    from shapecond.shapes.metric import metric_shape

    st = Path(null_path).stat()
    key = disk.key_of(LANDMARK_CACHE_VERSION, str(Path(null_path).resolve()), st.st_size, st.st_mtime_ns,
                      method, k, n_points, seed, backend, quick)
    d = disk.load_json("landmarks", key, _check_landmark_entry) if cache else None
    if d is not None:
        for name in ("scores", "floor", "scale"):
            d[name] = {int(c): float(v) for c, v in d[name].items()}
        return d
    t0 = time.perf_counter()
    shape = metric_shape(load_geometry(null_path), n_points, backend=backend, seed=seed, cache=cache)
    sel = landmark_method(method)(shape, k, seed)
    idx = [int(i) for i in sel["sample_indices"]][:k]
    seconds = time.perf_counter() - t0
    from shapecond.landmarks import monotone
    from shapecond.symmetry.scale import scale_score

    scores, floor, scale = {}, {}, {}
    counts = sorted({1, min(3, len(idx)), len(idx)})
    for c in counts:
        scores[c] = symmetry_score(shape.D, shape.n_samples, idx[:c], seed, True)
        floor[c] = swap_floor(shape.D, shape.n_samples, idx[:c])
        scale[c] = scale_score(shape.D, shape.n_samples, idx[:c], seed=seed, effort="quick").displacement
    scale = dict(zip(counts, monotone([scale[c] for c in counts])))
    out = dict(cls=cls, method=method, vertices=[int(shape.samples[i]) for i in idx],
               ids=[int(v) for v in shape.sample_ids[idx]], scores=scores, floor=floor, scale=scale,
               seconds=seconds, score_source="search")
    if cache:
        disk.save_json("landmarks", key, {**out, "scores": {c: _json_float(v) for c, v in scores.items()},
                                          "floor": {c: _json_float(v) for c, v in floor.items()}})
    return out


def _json_float(v: float):
    return "inf" if v == math.inf else v


def _check_landmark_entry(d) -> None:
    """Refuse a cached landmark selection that does not have the expected fields."""
    for name in ("cls", "method", "vertices", "ids", "scores", "floor", "scale", "seconds"):
        if name not in d:
            raise InputError(f"field {name!r} is missing")
    if len(d["vertices"]) != len(d["ids"]) or not all(isinstance(v, int) and v >= 0 for v in d["vertices"]):
        raise InputError("its landmark vertices are not vertex indices")


def _check_evaluation_cost(plan, n_points, backend, methods, matchers, n_jobs, force) -> None:
    """Refuse (or warn about) an evaluation estimated beyond ``shapecond.limits``.

    Per shape: its geodesics; per class and method: about 4 witness searches per
    CNBS landmark and 3 searches for the scores; per matching about one second at
    N = 400, growing like N³ (measured on TOSCA by the project's benchmarks).
    """
    from shapecond.limits import cap_jobs, check_cost, geodesic_seconds, search_seconds

    total, n_shapes, n_matchings = 0.0, 0, 0
    for null, targets, k in plan.values():
        n = off_vertex_count(null) or 50_000
        total += (1 + len(targets)) * geodesic_seconds(n, 2 * n_points, backend)
        for m in methods:
            total += search_seconds(n_points, n_points, 3 + (4 * k if m == "cnbs" else 0))
        n_shapes += 1 + len(targets)
        n_matchings += len(targets) * len(methods) * 2 * len(matchers)
    total += n_matchings * (n_points / 400.0) ** 3
    jobs = cap_jobs(n_jobs, n_shapes)
    check_cost(f"the evaluation ({n_shapes} shapes, {n_matchings} matchings, N = {n_points}, {jobs} jobs)",
               total / jobs, force=force)


@dataclass
class Evaluation:
    """Everything ``evaluate_dataset`` measured (``report.py`` turns it into Markdown)."""

    landmarks: list            # dicts of landmark_task
    records: list              # MatchRecord
    settings: dict
    seconds: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """Settings, timings, landmarks and one row per matching, as JSON-ready values."""
        return jsonable(dict(settings=self.settings, seconds=self.seconds, landmarks=self.landmarks,
                             records=[r.to_dict() for r in self.records]))

    def __repr__(self) -> str:
        return (f"Evaluation({len(self.settings.get('classes', []))} classes, {len(self.records)} matchings, "
                f"methods {self.settings.get('methods')}, matchers {self.settings.get('matchers')})")


def evaluate_dataset(dataset_dir, classes=None, methods=("fps", "pls", "hks", "cnbs", "cnbs-scale"),
                     matchers=("lh05", "faq"), n_jobs=1, scheduler=None, quick=False,
                     n_points=None, seed=0, backend="heat", cache=True, progress=False,
                     max_targets=None, protocol="corresponding", force=False) -> Evaluation:
    """Run the Figure 7 evaluation on every class folder of ``dataset_dir``.

    ``protocol``: ``"corresponding"``, ``"independent"`` (module docstring) or
    ``"both"``.  ``quick``: classes default to wolf and centaur (or the first
    two), at most 2 targets per class, N = 200 and the quick score search.
    ``force``: run even when the estimated time is beyond ``shapecond.limits``.

    Phases: the null shapes' geodesics; then the targets' geodesics together
    with the landmark selections (they depend only on the null shapes); then
    the matchings together with each class's own deformation level and the δ
    scores at it (``class_scale_task``; corresponding protocol only).  Within a
    phase the longest tasks go first.
    """
    if protocol not in PROTOCOLS + ("both",):
        raise InputError(f"unknown protocol {protocol!r} (corresponding, independent or both)")
    protocols = PROTOCOLS if protocol == "both" else (protocol,)
    if quick and not classes:
        names = list(find_classes(dataset_dir))
        classes = [c for c in ("wolf", "centaur") if c in names] or names[:2]
    found = find_classes(dataset_dir, classes)
    n_points = n_points or (200 if quick else 400)
    max_targets = max_targets or (2 if quick else None)
    for m in methods:
        landmark_method(m)  # unknown methods fail before any work
    plan = {}
    for cls, folder in found.items():
        paths = class_shapes(folder)
        counts = {p.name: off_vertex_count(p) for p in paths}
        known = {c for c in counts.values() if c is not None}
        if len(known) > 1:
            raise InputError(f"class {cls}: shapes have different vertex counts "
                             f"({', '.join(f'{k}: {v}' for k, v in counts.items())})")
        plan[cls] = (paths[0], paths[1:][:max_targets] if max_targets else paths[1:],
                     PAPER_LANDMARKS.get(cls, DEFAULT_LANDMARKS))
    _check_evaluation_cost(plan, n_points, backend, methods, matchers, n_jobs, force)
    common = (n_points, seed, backend, cache)
    timing = {}
    t0 = time.perf_counter()
    run_tasks([(prepare_task, (null, *common), dict(with_metric=True)) for null, _, _ in plan.values()],
              n_jobs, scheduler, progress)
    timing["null shapes"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    # the longest tasks first (CNBS-scale runs a δ search per landmark, CNBS a heat map per
    # landmark), so that the pool's last tasks are short ones rather than one long selection
    # that every later phase waits for
    by_cost = sorted(methods, key=lambda m: -LANDMARK_COST.get(m, 0))
    tasks = [(landmark_task, (cls, null, m, k, *common, quick), {})
             for m in by_cost for cls, (null, _, k) in plan.items()]
    tasks += [(prepare_task, (p, *common), dict(null_path=null, protocols=protocols))
              for null, targets, _ in plan.values() for p in targets]
    landmarks = [d for d in run_tasks(tasks, n_jobs, scheduler, progress) if isinstance(d, dict)]
    order = {(c, m): i for i, (c, m) in enumerate((c, m) for c in plan for m in methods)}
    landmarks.sort(key=lambda d: order[(d["cls"], d["method"])])  # class by class, whatever finished first
    timing["landmarks and targets"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    # each class's deformation level and the δ scores at it, as tasks beside the matchings
    # (the level reads every target's rows: seconds per class, which the parent would
    # otherwise spend alone while the workers wait)
    match_tasks = []
    if "corresponding" in protocols:
        match_tasks = [(class_scale_task, (cls, null, targets,
                                           {d["method"]: (d["vertices"], sorted(d["scale"]))
                                            for d in landmarks if d["cls"] == cls}, *common), {})
                       for cls, (null, targets, _) in plan.items()]
    for cls, (null, targets, k) in plan.items():
        sets = {d["method"]: d["vertices"] for d in landmarks if d["cls"] == cls}
        sets = {m: sets[m] for m in methods}
        counts = sorted({min(3, k), k})
        for tp in targets:
            for prot in protocols:
                match_tasks.append((target_task, (cls, null, tp, sets, counts, tuple(matchers), *common),
                                    dict(protocol=prot)))
    records, by_set, eps = [], {(d["cls"], d["method"]): d for d in landmarks}, {}
    for res in run_tasks(match_tasks, n_jobs, scheduler, progress):
        if isinstance(res, dict):  # a class_scale_task
            eps[res["cls"]] = res["epsilon"]
            for method, sc in res["scale_class"].items():
                by_set[(res["cls"], method)]["scale_class"] = sc
        else:
            records += res
    eps = {cls: eps[cls] for cls in plan if cls in eps}
    timing["matching"] = time.perf_counter() - t0
    settings = dict(dataset=str(dataset_dir), classes=list(plan), methods=list(methods),
                    protocols=list(protocols),
                    matchers=list(matchers), n_points=n_points, seed=seed, backend=backend,
                    quick=quick, n_jobs=n_jobs, scheduler=None if scheduler is None else str(scheduler),
                    landmark_counts={c: v[2] for c, v in plan.items()},
                    targets={c: [p.stem for p in v[1]] for c, v in plan.items()}, class_epsilon=eps)
    return Evaluation(landmarks, records, settings, timing)


def class_epsilon(null_path, targets, n_points, seed, backend, cache) -> float:
    """A class's own deformation level: the median over its targets of the RMS distortion of
    the ground-truth map between the null shape's samples and the same vertices of the target,
    in units of the null shape's metric shape (diameter 1).  The ε at which δ(ε) predicts how
    badly this class's poses will be matched; an evaluation knows it from the ground truth,
    a user who knows their data's non-isometry passes it as ``--epsilon``."""
    from shapecond.shapes.io import load_geometry
    from shapecond.shapes.metric import metric_shape

    g = load_geometry(null_path)
    null = sample_surface(g, n_points, backend, seed, cache=cache)
    scale = metric_shape(g, n_points, backend=backend, seed=seed, cache=cache).scale
    iu = np.triu_indices(null.n_samples, 1)
    rms = [float(np.sqrt(np.mean((null.D - surface_at(load_geometry(p), null.samples, backend, cache).D)[iu] ** 2)))
           for p in targets]
    return float(np.median(rms)) * null.unit / scale


def class_scale_task(cls, null_path, targets, sets, n_points, seed, backend, cache) -> dict:
    """A class's deformation level ε (``class_epsilon``) and, at it, δ(ε) (quick search) of each
    landmark set ``sets[method] = (vertices, counts)`` after each count, non-increasing in the count
    (``landmarks.monotone``)."""
    from shapecond.landmarks import monotone
    from shapecond.shapes.io import load_geometry
    from shapecond.shapes.metric import metric_shape
    from shapecond.symmetry.scale import scale_score

    epsilon = class_epsilon(null_path, targets, n_points, seed, backend, cache)
    shape = metric_shape(load_geometry(null_path), n_points, backend=backend, seed=seed, cache=cache)
    where = {int(v): i for i, v in enumerate(shape.samples[:shape.n_samples])}
    out = {}
    for method, (vertices, counts) in sets.items():
        idx = [where[int(v)] for v in vertices]
        vals = [scale_score(shape.D, shape.n_samples, idx[:c], epsilon, seed=seed, effort="quick").displacement
                for c in counts]
        out[method] = dict(zip(counts, monotone(vals)))
    return dict(cls=cls, epsilon=epsilon, scale_class=out)
