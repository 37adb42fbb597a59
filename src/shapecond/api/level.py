"""The deformation level ε of a user's shapes, read off matched maps without ground truth.

The scale-aware score δ(ε) (``symmetry.scale``) predicts how far a matcher may
go wrong when ε is the distortion the user's deformations actually cause; at
the default ε (the sample spacing) it predicts far less well.  What a user has
is other shapes of the same kind.  The RMS distortion ε̂ of the map a
distortion-minimising matcher finds between two of them reads their level from
below (it finds a map at least as isometric as the true one;
``matching.error_bar``), so δ at ε̂ is the score at the user's own level.

No landmarks are needed: a map that is wrong by a symmetry of the shape
distorts distances as little as the right one, so the level of a pair is read
even where the map is not the right one, and a map wrong in any other way
distorts more, which reads the level higher, never lower.  With several other
shapes the level is the median over the pairs.  ``score``, ``landmarks`` and
``heatmap`` take ``epsilon=level.epsilon``; the command line's
``--epsilon-from`` does the same and says so in its output.
"""

from __future__ import annotations

import statistics
import time
from dataclasses import dataclass

import numpy as np

from ..checks import parse_ids
from ..errors import InputError
from ..jsonable import jsonable
from .inputs import load
from .matching import load_pair, match_options, pair_problem
from .params import DEFAULT_POINTS


#: Shapes matched to the first one of a collection to read its level (``collection_level``).
COLLECTION_PAIRS = 4


@dataclass(frozen=True)
class DeformationLevel:
    """ε̂ of a shape against others (module docstring).

    Attributes
    ----------
    epsilon : the level in units of the shape's geodesic diameter (the unit of ``score``'s ε).
    epsilon_area : the same in units of the shape's sqrt(area) (the median of ``pairs``).
    pairs : ε̂ of each matched pair, sqrt(area) units, in the order of the other shapes.
    matcher : the matcher whose maps were read.
    seconds : time of the matchings and distortions.
    """

    epsilon: float
    epsilon_area: float
    pairs: tuple
    matcher: str
    seconds: float

    def __repr__(self) -> str:
        return (f"DeformationLevel(epsilon={self.epsilon:.4g} diameters ({self.epsilon_area:.4g} sqrt(area)), "
                f"median of {len(self.pairs)} {self.matcher} maps, {self.seconds:.1f} s)")

    def sentence(self) -> str:
        """Where the level comes from, in words (the ``epsilon_source`` of the command line's JSON)."""
        return (f"read off {len(self.pairs)} matched map(s) ({self.matcher}): the median RMS distortion, "
                f"{self.epsilon_area:.3g} sqrt(area)")

    def to_dict(self) -> dict:
        return jsonable({"epsilon": self.epsilon, "epsilon_area": self.epsilon_area, "pairs": list(self.pairs),
                         "matcher": self.matcher, "seconds": self.seconds, "text": self.sentence()})


def deformation_level(x, others, *, landmarks=(), landmarks_others=None, matcher: str = "faq",
                      n_points: int = DEFAULT_POINTS, **options) -> DeformationLevel:
    """The deformation level ε̂ of ``x`` against ``others``, read off the maps a matcher finds.

    Parameters
    ----------
    x : a mesh or point cloud (any input of ``load`` but a distance matrix).
    others : other shapes of the same kind: a list of inputs, or one input.
    landmarks, landmarks_others : optional corresponding landmarks (input ids): on ``x``, and one
        list per other shape, in the same order (default: none; the level does not need them).
    matcher : "faq" (default: seeded graph matching, which minimises distortion directly) or "lh05".
    n_points : samples of each shape for the matcher.
    **options : ``seed``, ``backend``, ``cache``, ``force``, ``largest_component`` and the
        matcher's own options, as for ``match``.

    Returns
    -------
    DeformationLevel: ``.epsilon`` in diameters of ``x`` (pass it as ``epsilon``), ``.pairs``.

    Examples
    --------
    >>> import shapecond as sc
    >>> level = sc.deformation_level("demo:animal", ["demo:animal:delta=0.1"], n_points=40, cache=False)
    >>> 0 < level.epsilon < 1
    True
    """
    t0 = time.perf_counter()
    refused = [k for k in options if k in ("error_bar", "dense", "samples", "suggest")
               or k.startswith("zoomout_")]  # match's, meaningless here (the level reads the sample map)
    if refused:
        raise InputError(f"deformation_level() got unknown option {refused[0]!r}")
    if matcher == "zoomout":
        raise InputError("the level is read off a sample matcher's map: matcher 'faq' or 'lh05', not 'zoomout'")
    opts, flags = match_options(dict(options, matcher=matcher, n_points=n_points, dense="nearest"), "deformation_level")
    others = list(others) if isinstance(others, list) else [others]
    if not others:
        raise InputError("deformation_level needs at least one other shape")
    ids_s = parse_ids(landmarks, "landmarks")
    lms = [()] * len(others) if landmarks_others is None else list(landmarks_others)
    if len(lms) != len(others):
        raise InputError(f"{len(lms)} landmark lists for {len(others)} other shapes")
    return _level([_pair_level(x, y, ids_s, parse_ids(lm, "landmarks_others"), opts, flags)
                   for y, lm in zip(others, lms)], matcher, time.perf_counter() - t0)


def collection_level(shapes: list, *, n_points: int = DEFAULT_POINTS, seed: int = 0, backend: str = "heat",
                     cache: bool = True, force: bool = False, largest_component: bool = False) -> DeformationLevel:
    """The level of a collection: its first readable shape against the next ``COLLECTION_PAIRS`` readable
    ones (``deformation_level`` with its default matcher, in diameters of the first; the keywords as there).

    A class level needs a few pairs, not all of them: each pair reads the same kind of pose change
    from below, and the median of a few discards a pair whose map went wrong (which reads the level
    higher).  A shape that cannot be read (or is a distance matrix) is passed over with a warning.
    """
    import warnings

    readable = []
    for x in shapes:
        if len(readable) > COLLECTION_PAIRS:
            break
        try:
            shape = load(x, largest_component=largest_component, force=force)
            if isinstance(shape, np.ndarray):
                raise InputError("a distance matrix, not a mesh or point cloud")
        except InputError as exc:
            warnings.warn(f"{x}: not used for the collection's level ({str(exc).splitlines()[0]})")
            continue
        readable.append(shape)
    if len(readable) < 2:
        raise InputError("the level of a collection needs at least two readable shapes")
    return deformation_level(readable[0], readable[1:], n_points=n_points, seed=seed, backend=backend, cache=cache,
                             force=force, largest_component=largest_component)


def _pair_level(x, y, ids_s, ids_t, opts, flags) -> tuple[float, float]:
    """(ε̂ in sqrt(area) units, the geodesic diameter of ``x`` in the same units) of one matched pair
    (``matching.problem.MatchProblem.epsilon_hat``, on the samples the matcher used)."""
    src, tgt = load_pair(x, y, flags)
    if isinstance(src, np.ndarray) or isinstance(tgt, np.ndarray):
        raise InputError("the deformation level is read off meshes or point clouds, not distance matrices")
    problem = pair_problem(src, tgt, ids_s, ids_t, opts, flags["force"])
    return problem.epsilon_hat, problem.source.diameter / problem.source.unit


def _level(pairs, matcher: str, seconds: float) -> DeformationLevel:
    eps = statistics.median(e for e, _ in pairs)
    diameter = pairs[0][1]
    return DeformationLevel(eps / diameter if diameter > 0 else 0.0, eps, tuple(e for e, _ in pairs), matcher, seconds)


__all__ = ["COLLECTION_PAIRS", "DeformationLevel", "collection_level", "deformation_level"]
