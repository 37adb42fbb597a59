"""The paper's evaluation of landmark methods (Section 7, Figure 7) on class folders, end to end.

For each class (``datasets``) and landmark method: landmarks on the null shape
(``landmark_sets``; the paper's counts ``PAPER_LANDMARKS``), the symmetry scores
after 1, 3 and all of them (Figure 7a), and the null shape matched to every
other shape of the class with the first 3 (and, optionally, more) and with all
the landmarks by each matcher, the error measured per protocol (``protocols``,
Figure 7b).  The protocol follows the class folder: the remeshed protocol for a
folder with ``.vts`` ground truth, the corresponding (κ) protocol otherwise.

Per-shape work is a joblib task (``parallel.run_tasks``): ``n_jobs`` local
processes, or, given a Dask scheduler address, joblib's ``"dask"`` backend on
that cluster (needs ``dask[distributed]``; every worker must see the dataset
path and should share the cache folder ``$SHAPECOND_CACHE``).
"""

from __future__ import annotations

import math
import statistics
import time
from dataclasses import dataclass
from pathlib import Path

from ..api import load
from ..errors import InputError
from ..limits import check_cost, geodesic_seconds, search_seconds
from ..matching.pipeline import DENSE_STAGES, MATCHERS
from ..matching.sampled import sample_surface, surface_at
from ..matching.seeded import FAQOptions
from ..parallel import cap_jobs, run_tasks
from ..shapes.pairs_list import read_pairs
from .datasets import ClassFolder, check_layout, find_classes, off_vertex_count, pair_groups
from .deformation_level import class_scale_task, hat_scale_task, matched_level_task
from .landmark_sets import (AT_CLASS_LEVEL, DEFAULT_LANDMARKS, LANDMARK_COST, PAPER_LANDMARKS, ShapeSetup, check_method,
                            landmark_task)
from .protocols import PROTOCOLS, MatchingSetup, target_task
from .records import Evaluation

#: ``protocol`` values: one protocol, both shared-order ones, or "auto" (remeshed where there are .vts files).
PROTOCOL_CHOICES = ("auto",) + PROTOCOLS + ("both",)
DEFAULT_METHODS = ("fps", "pls", "hks", "cnbs", "cnbs-scale")
#: Matchers of an evaluation unless told: every one (the corresponding protocol runs the sample matchers).
DEFAULT_MATCHERS = ("lh05", "faq", "zoomout")


@dataclass(frozen=True)
class EvaluationOptions:
    """Every knob of ``evaluate_dataset``.

    Attributes
    ----------
    classes : class names (None: every class folder).
    methods : landmark methods (``shapecond.selection``).
    matchers : matchers (``matching.pipeline.MATCHERS``).
    protocol : one of ``PROTOCOL_CHOICES`` ("auto": remeshed for classes with ``.vts`` files,
        corresponding otherwise; "both": corresponding and independent).
    counts : landmark counts matched besides all of them (default: 3).
    n_points, seed, backend, cache : how shapes are sampled (None n_points: 400, or 200 when quick).
    dense : how maps reach every vertex (``matching.pipeline.DENSE_STAGES``).
    n_jobs, scheduler : local processes, or a Dask scheduler address or client.
    quick : wolf and centaur (or the first two classes), 2 targets each, N = 200, quick scores.
    max_targets : at most this many targets per class.
    progress : progress bars on stderr.
    force : run even when the estimate is beyond ``shapecond.limits``.
    error_bars : give every matching its error bar (from δ(ε̂), ``matching.error_bar``; one δ search each).
    pairs : the pairs to match, ((source, target) names, ...) (``shapes.pairs_list.read_pairs``; None: each class's
        null shape to the rest of its class).  Each source is then a group of its own.
    n_landmarks : landmarks per source, the largest count matched (None: the paper's count for its
        TOSCA classes, ``DEFAULT_LANDMARKS`` otherwise).
    scores : the symmetry scores of every landmark set (Figure 7a: σ and δ after 1, 3 and all
        landmarks, δ at the class's levels); False: the matchings alone (a release's pairs list).
    faq_objective : FAQ's objective (``matching.seeded.FAQ_OBJECTIVES``), checked by ``FAQOptions``.
    """

    classes: tuple | None = None
    methods: tuple = DEFAULT_METHODS
    matchers: tuple = DEFAULT_MATCHERS
    protocol: str = "auto"
    counts: tuple = (3,)
    n_points: int | None = None
    seed: int = 0
    backend: str = "heat"
    cache: bool = True
    dense: str = "zoomout"
    n_jobs: int = 1
    scheduler: object = None
    quick: bool = False
    max_targets: int | None = None
    progress: bool = False
    force: bool = False
    error_bars: bool = True
    pairs: tuple | None = None
    n_landmarks: int | None = None
    scores: bool = True
    faq_objective: str = "distance"

    def __post_init__(self):
        if self.protocol not in PROTOCOL_CHOICES:
            raise InputError(f"unknown protocol {self.protocol!r} (choose from {', '.join(PROTOCOL_CHOICES)})")
        for m in self.methods:
            check_method(m)
        bad = [m for m in self.matchers if m not in MATCHERS]
        if bad or not self.matchers:
            raise InputError(f"unknown matcher {bad[0] if bad else ''!r} (choose from {', '.join(MATCHERS)})")
        FAQOptions(objective=self.faq_objective)  # its one check of the name
        if self.dense not in DENSE_STAGES:
            raise InputError(f"unknown dense stage {self.dense!r} (choose from {', '.join(DENSE_STAGES)})")
        if not all(isinstance(c, int) and c >= 1 for c in self.counts):
            raise InputError("landmark counts must be positive integers")
        if not (isinstance(self.n_jobs, int) and self.n_jobs >= 1):
            raise InputError(f"n_jobs must be a positive integer, got {self.n_jobs!r}")
        if self.n_landmarks is not None and not (isinstance(self.n_landmarks, int) and self.n_landmarks >= 1):
            raise InputError(f"n_landmarks must be a positive integer, got {self.n_landmarks!r}")
        if self.pairs is not None and self.classes:
            raise InputError("give either classes or a pairs list, not both")

    @property
    def shape(self) -> ShapeSetup:
        return ShapeSetup(self.n_points or (200 if self.quick else 400), self.seed, self.backend, self.cache)


@dataclass(frozen=True)
class ClassPlan:
    """One class of the run: its folder, the targets matched, its landmark count and protocols."""

    folder: ClassFolder
    targets: tuple
    k: int
    protocols: tuple

    @property
    def name(self) -> str:
        return self.folder.name


def _protocols(folder: ClassFolder, choice: str) -> tuple:
    if folder.layout == "remeshed":
        if choice not in ("auto", "remeshed"):
            raise InputError(f"class {folder.name} has .vts ground truth (a remeshed class): protocol "
                             f"{choice!r} needs shapes with one vertex order")
        return ("remeshed",)
    if choice == "remeshed":
        raise InputError(f"class {folder.name} has no corres/ folder of .vts files: the remeshed protocol "
                         "needs them")
    return {"auto": ("corresponding",), "both": ("corresponding", "independent")}.get(choice, (choice,))


def plan_classes(dataset_dir, opts: EvaluationOptions) -> dict[str, ClassPlan]:
    """Every class of the run with its targets and protocols, checked before any work."""
    classes = opts.classes
    if opts.pairs is not None:
        found = pair_groups(dataset_dir, opts.pairs)
        found = dict(list(found.items())[:2]) if opts.quick else found
    else:
        if opts.quick and not classes:
            names = list(find_classes(dataset_dir))
            classes = [c for c in ("wolf", "centaur") if c in names] or names[:2]
        found = find_classes(dataset_dir, classes)
    plan = {}
    for name, folder in found.items():
        check_layout(folder)
        max_targets = opts.max_targets or (2 if opts.quick else None)
        targets = folder.targets[:max_targets] if max_targets else folder.targets
        k = opts.n_landmarks or PAPER_LANDMARKS.get(name, DEFAULT_LANDMARKS)
        plan[name] = ClassPlan(folder, targets, k, _protocols(folder, opts.protocol))
    return plan


def _check_cost(plan: dict, opts: EvaluationOptions) -> None:
    """Refuse (or warn about) an evaluation estimated beyond ``shapecond.limits``.

    Per shape: its geodesics; per class and method: about 4 witness searches per
    CNBS landmark and 3 searches for the scores; per matching about one second at
    N = 400, growing like N³ (measured on TOSCA by the project's benchmarks).
    """
    n = opts.shape.n_points
    total, n_shapes, n_matchings = 0.0, 0, 0
    for p in plan.values():
        nv = off_vertex_count(p.folder.null) or 50_000
        total += (1 + len(p.targets)) * geodesic_seconds(nv, 2 * n, opts.backend)
        total += sum(search_seconds(n, n, 3 + (4 * p.k if m == "cnbs" else 0)) for m in opts.methods)
        n_shapes += 1 + len(p.targets)
        n_matchings += len(p.targets) * len(opts.methods) * (1 + len(opts.counts)) * len(opts.matchers)
    total += n_matchings * (n / 400.0) ** 3
    jobs = cap_jobs(opts.n_jobs, n_shapes)
    check_cost(f"the evaluation ({n_shapes} shapes, {n_matchings} matchings, N = {n}, {jobs} jobs)",
               total / jobs, force=opts.force)


def prepare_task(path, setup: ShapeSetup, with_metric: bool = False, null_path=None,
                 protocols=("independent",)) -> str:
    """Geodesics of one shape (warms the caches).

    The null shape (``with_metric``) gets its FPS rows and metric shape; a target
    gets its own FPS rows (independent and remeshed protocols) and/or the rows at
    the null shape's sample vertices (corresponding, needs ``null_path``).
    """
    g = load(path)
    s = setup
    if with_metric or set(protocols) & {"independent", "remeshed"}:
        sample_surface(g, s.n_points, s.backend, s.seed, cache=s.cache)
    if with_metric:
        s.metric_shape(g)
    if null_path is not None and "corresponding" in protocols:
        null = sample_surface(load(null_path), s.n_points, s.backend, s.seed, cache=s.cache)
        surface_at(g, null.samples, s.backend, s.cache)
    return str(path)


def _run(tasks, opts: EvaluationOptions) -> list:
    return run_tasks(tasks, opts.n_jobs, opts.scheduler, opts.progress)


def _landmark_phase(plan: dict, opts: EvaluationOptions) -> list:
    """The landmark selections, and the targets' geodesics beside them; longest tasks first."""
    setup = opts.shape
    levels = {}
    if any(m in AT_CLASS_LEVEL for m in opts.methods):  # the class levels their landmarks need, first
        levels = {d["cls"]: d["epsilon"] for d in _run([(matched_level_task, (p.name, p.folder.null, p.targets, setup),
                                                         {}) for p in plan.values()], opts)}
    by_cost = sorted(opts.methods, key=lambda m: -LANDMARK_COST.get(m, 0))
    tasks = [(landmark_task, (p.name, p.folder.null, m, p.k, setup, opts.quick),
              dict(scores=opts.scores, **(dict(epsilon=levels[p.name]) if m in AT_CLASS_LEVEL else {})))
             for m in by_cost for p in plan.values()]
    tasks += [(prepare_task, (t, setup), dict(null_path=p.folder.null, protocols=p.protocols))
              for p in plan.values() for t in p.targets]
    landmarks = [d for d in _run(tasks, opts) if isinstance(d, dict)]
    order = {(p.name, m): i for i, (p, m) in enumerate((p, m) for p in plan.values() for m in opts.methods)}
    return sorted(landmarks, key=lambda d: order[(d["cls"], d["method"])])  # class by class


def _matching_phase(plan: dict, landmarks: list, opts: EvaluationOptions):
    """Every matching, with each shared-order class's deformation level and δ at it beside them."""
    setup = opts.shape
    tasks = []
    for p in plan.values():
        done = [d for d in landmarks if d["cls"] == p.name]
        if "corresponding" in p.protocols and opts.scores:  # the level is read from a shared vertex order
            sets = {d["method"]: (d["vertices"], sorted(d["scale"])) for d in done}
            tasks.append((class_scale_task, (p.name, p.folder.null, p.targets, sets, setup), {}))
        sets = {d["method"]: d["vertices"] for d in done}
        counts = tuple(sorted({min(c, p.k) for c in opts.counts} | {p.k}))
        ms = MatchingSetup(counts, tuple(opts.matchers), opts.dense, setup, opts.error_bars, opts.faq_objective)
        tasks += [(target_task, (p.folder, t, {m: sets[m] for m in opts.methods}, ms), dict(protocol=prot))
                  for t in p.targets for prot in p.protocols]
    records, eps, by_set = [], {}, {(d["cls"], d["method"]): d for d in landmarks}
    for res in _run(tasks, opts):
        if isinstance(res, dict):  # a class_scale_task
            eps[res["cls"]] = res["epsilon"]
            for method, sc in res["scale_class"].items():
                by_set[(res["cls"], method)]["scale_class"] = sc
        else:
            records += res
    return records, {c: eps[c] for c in plan if c in eps}


def evaluate_dataset(dataset_dir, options: EvaluationOptions = EvaluationOptions()) -> Evaluation:
    """Run the Figure 7 evaluation on every class folder of ``dataset_dir``.

    Parameters
    ----------
    dataset_dir : a folder of class folders (or one remeshed class folder).
    options : EvaluationOptions (``evaluation_options`` makes one of ``sc.evaluate``'s keywords).

    Phases: the null shapes' geodesics; the landmark selections with the targets'
    geodesics (they depend only on the null shapes); the matchings with each
    class's own deformation level (shared vertex order only).
    """
    opts = options
    plan = plan_classes(dataset_dir, opts)
    _check_cost(plan, opts)
    timing, t0 = {}, time.perf_counter()
    _run([(prepare_task, (p.folder.null, opts.shape), dict(with_metric=True)) for p in plan.values()], opts)
    timing["null shapes"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    landmarks = _landmark_phase(plan, opts)
    timing["landmarks and targets"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    records, eps = _matching_phase(plan, landmarks, opts)
    timing["matching"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    eps_hat = _hat_phase(plan, landmarks, records, opts) if opts.scores else {}
    if eps_hat:
        timing["delta at the matched level"] = time.perf_counter() - t0
    return Evaluation(landmarks, records, _settings(dataset_dir, plan, opts, eps, eps_hat), timing)


def _hat_phase(plan: dict, landmarks: list, records: list, opts: EvaluationOptions) -> dict:
    """Each class's level read off its matched maps (the median ε̂ of its matchings, which have one only
    with error bars) and δ of every landmark set at it (``deformation_level.hat_scale_task``)."""
    tasks = []
    for p in plan.values():
        eh = [r.epsilon_hat for r in records if r.cls == p.name and math.isfinite(r.epsilon_hat)]
        done = [d for d in landmarks if d["cls"] == p.name]
        if eh and done:
            sets = {d["method"]: (d["vertices"], sorted(d["scale"])) for d in done}
            tasks.append((hat_scale_task, (p.name, p.folder.null, sets, opts.shape, float(statistics.median(eh))), {}))
    out, by_set = {}, {(d["cls"], d["method"]): d for d in landmarks}
    for res in _run(tasks, opts):
        out[res["cls"]] = res["epsilon_hat"]
        for method, sc in res["scale_hat"].items():
            by_set[(res["cls"], method)]["scale_hat"] = sc
    return {c: out[c] for c in plan if c in out}


def _settings(dataset_dir, plan: dict, opts: EvaluationOptions, eps: dict, eps_hat: dict) -> dict:
    protocols = [p for p in PROTOCOLS if any(p in c.protocols for c in plan.values())]
    s = {k: getattr(opts, k) for k in opts.__dataclass_fields__ if k not in ("scheduler", "classes", "progress", "force")}
    s.update(dataset=str(dataset_dir), classes=list(plan), protocols=protocols, n_points=opts.shape.n_points,
             methods=list(opts.methods), matchers=list(opts.matchers), counts=list(opts.counts),
             scheduler=None if opts.scheduler is None else str(opts.scheduler),
             pairs=None if opts.pairs is None else [list(p) for p in opts.pairs],
             nulls={c: str(p.folder.null) for c, p in plan.items()},
             landmark_counts={c: p.k for c, p in plan.items()},
             targets={c: [t.stem for t in p.targets] for c, p in plan.items()}, class_epsilon=eps,
             class_epsilon_hat=eps_hat,
             layouts={c: p.folder.layout for c, p in plan.items()})
    return s


def evaluation_options(kw: dict) -> EvaluationOptions:
    """``EvaluationOptions`` of the keywords ``kw`` of ``evaluate``, lists turned into tuples; unknown names
    refused in one line."""
    known = set(EvaluationOptions.__dataclass_fields__)
    bad = sorted(set(kw) - known)
    if bad:
        raise InputError(f"evaluate() got unknown option {bad[0]!r} (its options: {', '.join(sorted(known))})")
    kw = {k: tuple(v) if isinstance(v, list) else v for k, v in kw.items()}
    if kw.get("pairs") is not None:
        pairs = kw["pairs"]
        pairs = read_pairs(pairs) if isinstance(pairs, (str, Path)) else pairs
        if not all(isinstance(p, (tuple, list)) and len(p) == 2 and all(isinstance(n, str) for n in p)
                   for p in pairs) or not pairs:
            raise InputError("pairs: a pairs file, or a list of (source, target) shape names")
        kw["pairs"] = tuple((str(a), str(b)) for a, b in pairs)
    return EvaluationOptions(**kw)


def evaluate(dataset_dir, **options) -> Evaluation:
    """The paper's Figure 7 evaluation on class folders (``sc.evaluate``).

    Parameters
    ----------
    dataset_dir : a folder of class folders: meshes with one vertex order (TOSCA), or
        ``shapes/`` + ``corres/*.vts`` folders, or a release as it ships (flat or split layout,
        ``datasets``), or one such class.
    **options : fields of ``EvaluationOptions`` (classes, methods, matchers, protocol, counts,
        n_points, seed, backend, cache, dense, n_jobs, scheduler, quick, max_targets, progress,
        force, error_bars, pairs (a pairs file or a list of name pairs), n_landmarks, scores,
        faq_objective); an unknown name is refused before any work.

    Returns
    -------
    Evaluation; write its report with ``shapecond.evaluation.report.write_report``.

    Examples
    --------
    A class of three bent copies of a plane (one vertex order, so the ground truth is the identity):

    >>> import pathlib, tempfile, shapecond as sc
    >>> from shapecond.shapes.io import write_mesh
    >>> root = pathlib.Path(tempfile.mkdtemp()); (root / "plane").mkdir()
    >>> g = sc.load("demo:plane")
    >>> for i, bend in enumerate((0.0, 0.2, 0.4)):
    ...     V = g.vertices.copy(); V[:, 2] += bend * V[:, 0] ** 2
    ...     write_mesh(root / "plane" / f"plane{i}.off", V, g.faces)
    >>> ev = sc.evaluate(root, methods=("fps",), matchers=("faq",), n_points=20, cache=False)
    >>> len(ev.records), max(r.error for r in ev.records) < 1.0   # 2 targets x (3 and all landmarks)
    (4, True)
    """
    return evaluate_dataset(Path(dataset_dir), evaluation_options(options))


__all__ = ["ClassPlan", "EvaluationOptions", "PROTOCOL_CHOICES", "evaluate", "evaluate_dataset",
           "evaluation_options", "plan_classes"]
