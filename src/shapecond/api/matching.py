"""Landmark-guided matching of two shapes through the Python interface (``matching.problem.MatchProblem``)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..checks import parse_ids
from ..errors import InputError
from ..matching.candidates import check_landmarks
from ..matching.pipeline import DENSE_STAGES, MATCHERS, SAMPLE_MATCHERS, SAMPLINGS, MatchOptions, match_samples
from ..matching.problem import MatchProblem
from ..matching.seeded import FAQ_OBJECTIVES, FAQOptions
from ..matching.spectral import LH05Options
from ..matching.zoomout import ZoomOutOptions
from .guards import guard_match
from .inputs import load
from .params import (BACKEND, CACHE, DEFAULT_POINTS, FORCE, LARGEST_COMPONENT, POINTS, SEED, Choice, Flag, FloatRange,
                     IntRange, Param, check_keywords, grouped)
from .results import MatchResult

_ZOOMOUT = "The ZoomOut dense stage (--dense zoomout, --matcher zoomout): "
_POSITIVE = FloatRange(0, lo_open=True)
_POSITIVE_OR_NONE = FloatRange(0, lo_open=True, none=True)

#: FAQ's objective (``matching.seeded``): a row of ``MATCH_PARAMS``, and ``evaluate``'s ``--faq-objective``.
FAQ_OBJECTIVE = Param("objective", Choice(FAQ_OBJECTIVES), "distance",
                      "faq: the objective: distance (the distortion of every sample distance, Eq. 3), gaussian "
                      "(near pairs only), or local (near pairs, the width read off the landmark pairs' distortion; "
                      "for different species whose landmarks leave the extremities free).", ("faq", None),
                      ("--faq-objective",))

#: The options of ``match``, each declared once (``params``): the command line's ``shapecond match``
#: options and ``match``'s keywords are made from it.  Feeds: "match" ``MatchOptions``, "zoomout" its
#: ``ZoomOutOptions`` (the dense stage; prefixed ``zoomout_`` since ``k`` and ``sigma`` are LH05's),
#: "lh05" ``LH05Options`` and "faq" ``FAQOptions`` (the sample matcher's: with that matcher only),
#: "call" the call's own settings.
MATCH_PARAMS = (
    Param("matcher", Choice(MATCHERS), "lh05",
          "lh05: Leordeanu-Hebert spectral matching of the samples (the paper); faq: seeded graph matching of the "
          "samples; zoomout: from the landmarks alone (at least 3), by the dense stage.", ("match", None),
          ("--matcher",)),
    POINTS.with_default(DEFAULT_POINTS), SEED, BACKEND,
    Param("k", IntRange(1, 10_000), 20, "lh05: candidate target samples per source sample.", ("lh05", None), ("--k",)),
    Param("rounding", Choice(("greedy", "assignment")), "assignment",
          "lh05: a linear assignment or the paper's greedy discretisation.", ("lh05", None), ("--rounding",)),
    Param("refine", Flag(), True, "lh05: refine the rounded map on its own objective, with spectral rounds on "
          "candidates iterated from it (--no-refine --rounding greedy: the paper's plain LH05).", ("lh05", None),
          ("--refine/--no-refine",)),
    Param("samples", Choice(SAMPLINGS), "fps",
          "fps: each shape gets its own farthest-point samples; same-ids: the target is sampled at the source's "
          "sample vertices (shapes with a common vertex order; the evaluation's corresponding protocol) and the "
          "summary reports the sample map's error.", ("match", None), ("--samples",)),
    Param("dense", Choice(DENSE_STAGES), "zoomout",
          "How the map reaches every source vertex: zoomout (the sample map extended, then refined by ZoomOut on "
          "the Laplace-Beltrami bases with the landmarks as anchors), or the plain extensions of the sample map "
          "(distances: local distance matching; nearest: nearest sample).", ("match", None), ("--dense",)),
    Param("zoomout_k_start", IntRange(1, 10_000), 20, _ZOOMOUT + "basis functions of its first functional map.",
          ("zoomout", "k_start"), ("--zoomout-k-start",)),
    Param("zoomout_k_end", IntRange(1, 10_000, none=True), None,
          _ZOOMOUT + "basis functions of its last functional map.", ("zoomout", "k_end"), ("--zoomout-k-end",),
          "the whole basis"),
    Param("zoomout_step", IntRange(1, 10_000), 10, _ZOOMOUT + "growth of the basis per iteration.",
          ("zoomout", "step"), ("--zoomout-step",)),
    Param("zoomout_subsample_factor", IntRange(1, 10_000), 10,
          _ZOOMOUT + "source points per basis function in its iterations.", ("zoomout", "subsample_factor"),
          ("--zoomout-subsample-factor",)),
    Param("zoomout_sigma", _POSITIVE_OR_NONE, None,
          _ZOOMOUT + "width of the landmark anchors, in units of sqrt(area).", ("zoomout", "sigma"),
          ("--zoomout-sigma",), "pi / sqrt(eigenvalue) of the last basis function"),
    Param("error_bar", Flag(), True,
          "Estimate the map's error without ground truth: δ(ε̂) on SOURCE with the landmarks fixed, ε̂ the map's own "
          "RMS distortion (in the summary; the doubt field with --doubt-ply, --doubt-png).", cli=("--error-bar/--no-error-bar",)),
    LARGEST_COMPONENT, CACHE,
    Param("suggest", IntRange(0, 1000), 0,
          "Suggest this many next landmarks, read off the map and its error bar (each with its provisional image and "
          "the bar expected after it): click them, add them to the landmarks, re-run.", cli=("--suggest",)),
    FORCE,
    # the sample matchers' other options: Python only
    Param("sigma", _POSITIVE_OR_NONE, None,
          "lh05: width of the first round's affinity [default: sigma_factor x h].", ("lh05", None)),
    Param("sigma_factor", _POSITIVE, 2.0, "lh05: see sigma.", ("lh05", None)),
    Param("rounds", IntRange(1, 1000), 3, "lh05: at most this many spectral rounds of the refinement.", ("lh05", None)),
    Param("quantile_weight", FloatRange(0), 0.5, "lh05: weight of the descriptors' intrinsic part.", ("lh05", None)),
    Param("tol", _POSITIVE, 1e-7, "lh05: tolerance of the first round's power iteration.", ("lh05", None)),
    Param("max_iter", IntRange(1, 100_000), 500, "lh05: iterations of the first round's power iteration.",
          ("lh05", None)),
    Param("nested", Flag(), True, "lh05: with more than 3 landmarks, also match with the first 3; keep the better.",
          ("lh05", None)),
    FAQ_OBJECTIVE,
    Param("init", Choice(("descriptor", "barycenter")), "descriptor", "faq: the start.", ("faq", None)),
    Param("sigma", _POSITIVE_OR_NONE, None,
          "faq: kernel width of the gaussian objective [default: from sigma_factor].", ("faq", None)),
    Param("sigma_factor", _POSITIVE, 3.0, "faq: see sigma.", ("faq", None)),
    Param("quantile_weight", FloatRange(0), 0.5, "faq: weight of the descriptors' intrinsic part.", ("faq", None)),
    Param("maxiter", IntRange(1, 100_000), 60, "faq: Frank-Wolfe iterations.", ("faq", None)),
    Param("nested", Flag(), True, "faq: with more than 3 landmarks, also solve with the first 3; keep the better.",
          ("faq", None)),
)
#: The options object of each sample matcher (the "lh05" and "faq" rows of ``MATCH_PARAMS``).
_DECLARED = {"lh05": LH05Options, "faq": FAQOptions}


def inapplicable(matcher: str) -> list:
    """The rows of ``MATCH_PARAMS`` that do not apply with ``matcher`` (its ``feeds``): the other sample
    matchers' options."""
    return [m for m in SAMPLE_MATCHERS if m != matcher]


class MatchSettings(NamedTuple):
    """The keywords of ``match`` checked (``match_options``): the ``MatchOptions`` of the matching and the
    call's own settings ``flags`` (``force``, ``largest_component``, ``error_bar``, ``suggest``)."""

    options: MatchOptions
    flags: dict


def match_options(keywords: dict, caller: str = "match") -> MatchSettings:
    """``MatchOptions`` and the call's settings (``force``, ``largest_component``, ``error_bar``, ``suggest``)
    from the keywords of ``match`` (``MATCH_PARAMS``), each checked once before any work; a keyword of
    no row, or of another matcher's row, refused."""
    matcher = MATCH_PARAMS[0].check(keywords.get("matcher", "lh05"))
    values = check_keywords(MATCH_PARAMS, keywords, caller, inapplicable(matcher), f" for matcher {matcher!r}")
    groups = grouped(MATCH_PARAMS, values)
    flags = groups["call"]
    if flags["suggest"] and not flags["error_bar"]:
        raise InputError("suggesting landmarks reads the error bar: it needs error_bar=True")
    own = None if matcher not in _DECLARED else _DECLARED[matcher](
        **groups[matcher], **({"seed": values["seed"]} if matcher == "faq" else {}))  # FAQ is seeded by match's seed
    return MatchSettings(MatchOptions(**groups["match"], zoomout=ZoomOutOptions(**groups["zoomout"]),
                                      matcher_options=own), flags)


def _match_matrices(src, tgt, ids_s, ids_t, opts, summary) -> MatchResult:
    if not (isinstance(src, np.ndarray) and isinstance(tgt, np.ndarray)):
        raise InputError("match two meshes/point clouds or two distance matrices, not one of each")
    if opts.samples != "fps":
        raise InputError("samples 'same-ids' needs two meshes or point clouds, not distance matrices")
    if opts.matcher == "zoomout":
        raise InputError("the zoomout matcher needs two meshes or point clouds (a Laplace-Beltrami basis), "
                         "not distance matrices")
    check_landmarks(src.shape[0], tgt.shape[0], ids_s, ids_t)
    if tgt.shape[0] < src.shape[0]:
        raise InputError(f"the target matrix has fewer rows ({tgt.shape[0]}) than the source ({src.shape[0]})")
    sm = match_samples(src / src.max(), tgt / tgt.max(), ids_s, ids_t, opts.matcher_options)
    summary.update(n_points=int(src.shape[0]), matcher_info=sm.info)
    return MatchResult(np.asarray(sm.t, dtype=np.int64), summary)


def match(source, target, landmarks_source, landmarks_target, *, matcher: str = "lh05",
          n_points: int = DEFAULT_POINTS, dense: str = "zoomout", **options) -> MatchResult:
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
    **options : ``samples`` ("fps", the default: each shape its own samples; or "same-ids": the target
        sampled at the source's sample vertices, for shapes with one vertex order; the summary gives the
        error), ``seed``, ``backend`` (geodesics), ``cache``, ``force``, ``largest_component``,
        ``error_bar`` (default True: also estimate the map's error without ground truth,
        ``matching.error_bar``: the mean displacement of δ(ε̂)'s witness on the source, ε̂ the
        map's own distortion), ``suggest`` (how many next landmarks to suggest, ``matching.suggest``; needs
        the error bar; in the summary as ``"suggestions"``, and ``.suggest(k)`` later), the dense
        stage's ``zoomout_k_start``, ``zoomout_k_end``, ``zoomout_step``, ``zoomout_subsample_factor``
        and ``zoomout_sigma`` (``matching.zoomout.ZoomOutOptions``; used with ``dense="zoomout"`` or
        ``matcher="zoomout"``) and the sample matcher's own options (lh05: ``k``, ``rounding``,
        ``refine``...; faq: ``objective``, ``init``...).  Every keyword, its constraint and default:
        ``MATCH_PARAMS``; a bad value or an unknown keyword is refused before any work.

    Returns
    -------
    MatchResult: ``.map[i]`` the target id of source id i (-1: a vertex dropped on loading),
    ``.summary`` (with ``"error_bar"``), ``.doubt[i]`` (the error bar's doubt field at source id i,
    sqrt(area) units; NaN for a dropped vertex; None without ``error_bar``), ``.to_html()``.

    Examples
    --------
    >>> import shapecond as sc
    >>> shape = "demo:animal:resolution=0.08"   # a coarse animal (942 vertices): a quick example
    >>> r = sc.match(shape, shape, [0, 100, 200], [0, 100, 200], n_points=40, cache=False)
    >>> r.map.shape[0] == sc.load(shape).n_vertices
    True
    """
    settings = match_options(dict(options, matcher=matcher, n_points=n_points, dense=dense))
    return checked_match(source, target, landmarks_source, landmarks_target, settings)


def checked_match(source, target, landmarks_source, landmarks_target, settings: MatchSettings) -> MatchResult:
    """``match`` with its keywords checked already (``match_options``): for a caller that checks them once
    for many matchings (``collection.match_collection``, batch matching)."""
    opts, flags = settings
    ids_s, ids_t = parse_ids(landmarks_source, "landmarks_source"), parse_ids(landmarks_target, "landmarks_target")
    src, tgt = load_pair(source, target, flags)
    summary = {"matcher": opts.matcher, "n_landmarks": len(ids_s), "direction": "source to target"}
    if isinstance(src, np.ndarray) or isinstance(tgt, np.ndarray):
        return _match_matrices(src, tgt, ids_s, ids_t, opts, summary)
    problem = pair_problem(src, tgt, ids_s, ids_t, opts, flags["force"])
    m = problem.dense_match
    lines = np.full(int(src.ids.max()) + 1, -1, dtype=np.int64)
    lines[src.ids] = tgt.ids[m.vertex_map]
    summary.update(n_points=opts.n_points, n_source_vertices=int(src.n_vertices),
                   n_target_vertices=int(tgt.n_vertices), backend=opts.backend, dense=opts.dense,
                   samples=opts.samples, matcher_info=m.sample_map.info if m.sample_map is not None else {})
    if opts.samples == "same-ids":
        summary.update(sample_error=m.info["sample_error"], exact=m.info["exact"])
    doubt = None
    if flags["error_bar"]:
        summary["error_bar"] = problem.error_bar.to_dict()
        doubt = np.full(lines.size, np.nan)
        doubt[src.ids] = problem.doubt
    result = MatchResult(lines, summary, (src, tgt, problem.landmarks_source, problem.landmarks_target), doubt,
                         problem.suggest if flags["error_bar"] else None, problem)
    if flags["suggest"]:
        result.suggest(flags["suggest"])  # recorded in the summary
    return result


def load_pair(source, target, flags: dict) -> tuple:
    """The two inputs of a matching, loaded with ``match``'s load settings (``match_options``)."""
    largest, force = flags["largest_component"], flags["force"]
    return load(source, largest_component=largest, force=force), load(target, largest_component=largest, force=force)


def pair_problem(src, tgt, ids_s, ids_t, opts: MatchOptions, force: bool) -> MatchProblem:
    """The ``matching.problem.MatchProblem`` of two loaded shapes and their landmarks (input ids), its
    landmark pairs checked, then its cost (``guards.guard_match``), before any work."""
    problem = MatchProblem(src, tgt, src.to_internal(ids_s), tgt.to_internal(ids_t), opts)
    guard_match(max(src.n_vertices, tgt.n_vertices), opts.n_points, len(ids_s), opts, force)
    return problem


__all__ = ["MATCH_PARAMS", "MatchSettings", "checked_match", "match", "match_options"]
