"""The options objects of the Python interface and the rows of the landmark selections' tables.

Every public function of ``shapecond`` that samples a shape takes the options that turn an input into a
metric shape as keyword arguments (``seed=1, backend="fmm", ...``), checked by its table
(``params.check_keywords``: one ``InputError`` naming the parameter, an unknown keyword refused with the
nearest name, before any work); ``ShapeOptions.of`` gathers the checked values into the one object the
sampling takes.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from ..checks import check_flag
from ..selection import (CNBS_EXTRAS, COMMON_OPTIONS, METHODS, SCORES, LandmarkOptions, check_method_options,
                         own_options_class)
from ..shapes.metric import Sampling
from .params import EFFORT, EPSILON, MAX_POINTS, REQUIRED, SHAPE_PARAMS, Choice, Flag, IntRange, Param

# --- the options of a landmark selection (``scores.landmarks``, ``SymmetryProblem.landmarks``) ---
#: How many landmarks.
K = Param("k", IntRange(0, MAX_POINTS), REQUIRED, "Number of landmarks (method user: 0 = all given).", cli=("-k",))
#: The landmark method (``selection.METHODS``).
METHOD = Param("method", Choice(METHODS), "cnbs",
               "cnbs: condition number based sampling (the paper's σ); cnbs-scale: CNBS on the scale-aware score "
               "δ(ε); fps; pls (Tevs et al., reimplemented); hks (heat kernel signature extrema); user "
               "(--user-landmarks); cnbs-local.", cli=("--method",))
#: Also score the baselines after each landmark (``selection.LandmarkOptions.scores``).
SCORES_AFTER = Param("scores", Flag(none=True), None, "Compute the symmetry score after each landmark (always on for "
                     "cnbs; for the baselines it costs one witness search per landmark).", cli=("--scores/--no-scores",))
#: Which score follows each landmark (``selection.LandmarkOptions.score``; None: the method's own).
LANDMARK_SCORE = Param("score", Choice(SCORES, none=True), None,
                       "Score after each landmark: sigma (the paper's) or scale (δ(ε)).", cli=("--score",),
                       cli_default="scale for cnbs-scale, sigma otherwise")


@dataclass(frozen=True)
class ShapeOptions:
    """How an input becomes a metric shape (``inputs.metric_shape``).

    Attributes
    ----------
    metric : "geodesic" or "euclidean".
    backend : geodesic solver, "heat" (default), "fmm" or "exact" (``shapes.geodesics``).
    seed : seed of every random choice (farthest-point sampling's start, the searches).
    target : "dense" (maps may send samples to M = ``target_factor`` x N targets; default for
        meshes and point clouds) or "samples" (the paper's bijections; the only choice for a matrix).
    target_factor : M / N for dense targets.
    cache : read and write the on-disk cache (``shapecond.cache``).
    progress : progress bars on stderr.
    force : run work estimated beyond ``shapecond.limits`` (time or memory) anyway.
    largest_component : keep only the largest connected component of a mesh.
    symmetry_map : a ``.sym`` path or an array (mirror vertex id of each vertex id): sample in mirror pairs.
    """

    metric: str = "geodesic"
    backend: str = "heat"
    seed: int = 0
    target: str | None = None
    target_factor: int = 8
    cache: bool = True
    progress: bool = False
    force: bool = False
    largest_component: bool = False
    symmetry_map: object = None

    def __post_init__(self):
        for name in ("cache", "progress", "force", "largest_component"):
            object.__setattr__(self, name, check_flag(getattr(self, name), name))
        checked = self.sampling("samples")  # the sampling's own checks (shapes.metric.Sampling)
        object.__setattr__(self, "seed", checked.seed)
        object.__setattr__(self, "target_factor", checked.target_factor)

    def sampling(self, default_target: str) -> Sampling:
        """The ``Sampling`` of these options, ``default_target`` where ``target`` is None."""
        return Sampling(metric=self.metric, backend=self.backend, seed=self.seed,
                        target=self.target or default_target, target_factor=self.target_factor, cache=self.cache,
                        progress=self.progress, force=self.force)

    @classmethod
    def of(cls, values: dict) -> ShapeOptions:
        """The options among ``values`` (a function's keywords checked by its table, ``params.check_keywords``)."""
        return cls(**{p.name: values[p.name] for p in SHAPE_PARAMS})


def landmark_options(method: str, seed: int, options: dict) -> tuple[LandmarkOptions, dict]:
    """The ``selection.LandmarkOptions`` of ``select_landmarks`` from the flat keywords of ``landmarks``,
    each checked here (``InputError`` naming it), and CNBS's ``base`` and ``progress`` (a dict).

    ``options``: the keywords every method takes (``COMMON_OPTIONS``) and the method's own (the fields
    of ``selection.own_options_class(method)``; for CNBS also ``options``, a ``CNBSOptions`` whose
    fields the other keywords replace); a name the method does not take is refused.
    """
    check_method_options(method, options)
    kw = dict(options)
    runtime = {k: kw.pop(k) for k in CNBS_EXTRAS if k in kw}
    common = {k: kw.pop(k) for k in COMMON_OPTIONS if k in kw}
    for p in (EPSILON, LANDMARK_SCORE, EFFORT):  # every method takes them; a bad value is refused by all
        if p.name in common:
            common[p.name] = p.check(common[p.name])
    common["fixed"] = tuple(int(v) for v in common.get("fixed", ()))
    cls, start = own_options_class(method), runtime.pop("options", None)
    own = None if cls is None else replace(start, **kw) if isinstance(start, cls) else cls(**kw)
    return LandmarkOptions(seed=seed, own=own, **common), runtime
