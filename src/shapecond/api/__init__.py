"""The Python interface, ``import shapecond as sc``: the one front door to the library.

The command line, batch scoring and the evaluation call these functions; none
of them turns an input into a shape or a result on its own, so the validation
(``params``: each option declared once), the cost guards (``guards``) and the numbers are the same from
every door.

* ``inputs``: ``load`` (a path, ``"demo:NAME"``, trimesh object, ``(V, F)``,
  points or distance matrix → a validated ``Geometry`` or matrix), ``info``,
  ``metric_shape`` (N farthest-point samples and their distances, diameter 1);
* ``scores``: ``score`` (σ bracket, Eq. 5; κ bracket, Theorem 4.1; δ(ε);
  verdict), ``local_score`` (Section 5), ``landmarks`` (CNBS and baselines,
  Section 6), ``heatmap`` (Figures 1 and 4), ``kappa`` (probes of Eq. 4); the
  tables ``SCORE_PARAMS``, ``LANDMARK_PARAMS``, ``HEATMAP_PARAMS`` and ``KAPPA_PARAMS`` of their options
  (``inputs.METRIC_SHAPE_PARAMS``: ``metric_shape``'s, ``problem.PROBLEM_PARAMS``: ``SymmetryProblem``'s);
* ``problem``: ``SymmetryProblem``, one shape whose searches are kept for
  repeated queries;
* ``settings``: ``score_settings``, the checked settings of both kinds of score;
* ``matching``: ``match``, a dense map between two shapes guided by landmarks, and its options'
  table ``MATCH_PARAMS`` (``params``: each option declared once, with its constraint);
* ``collection``: ``match_collection``, one template matched to every shape of a collection with the
  landmarks named in files (``shapes.landmark_files``);
* ``level``: ``deformation_level``, the distortion level ε̂ of a shape against
  others, read off matched maps (the ε of ``score``, ``landmarks``, ``heatmap``);
* ``results``: what they return (frozen dataclasses with ``to_dict()``,
  ``plot()``, ``to_html()``, short reprs).

Vertex ids, in and out, are the input's own (file vertex ids; matrix rows).
Every function raises :class:`~shapecond.errors.InputError` (a ``ValueError``)
with a one-line message for unusable input, an unknown keyword or work beyond
``shapecond.limits`` without ``force=True`` (``TooLargeError``), and
:class:`~shapecond.errors.OutputError` (an ``OSError``) for a file it cannot write.
"""

import importlib

#: Where each public name lives; a module is imported when one of its names is first used, so
#: ``import shapecond`` (and ``shapecond info``) does not load the searches' compiled kernels.
_HOME = {"DEFAULT_POINTS": "params", "info": "inputs", "load": "inputs", "metric_shape": "inputs",
         "require_mesh": "inputs", "match": "matching", "ShapeOptions": "options", "SymmetryProblem": "problem",
         "HeatMapResult": "results", "KappaResult": "results", "LandmarkResult": "results", "LocalResult": "results",
         "MatchResult": "results", "ScoreResult": "results", "heatmap": "scores", "kappa": "scores",
         "landmarks": "scores", "local_score": "scores", "score": "scores", "DeformationLevel": "level",
         "deformation_level": "level", "match_collection": "collection"}

__all__ = sorted(_HOME)


def __getattr__(name):
    if name not in _HOME:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{_HOME[name]}"), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_HOME))
