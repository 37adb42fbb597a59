"""Landmark-guided matching of two shapes through the Python interface (``matching.problem.MatchProblem``)."""

from __future__ import annotations

from dataclasses import fields

import numpy as np

from ..checks import check_choice, check_flag, check_int, check_seed, parse_ids
from ..errors import InputError
from ..matching.candidates import check_landmarks
from ..matching.pipeline import MATCHERS, MatchOptions, match_samples
from ..matching.problem import MatchProblem
from ..matching.seeded import FAQOptions
from ..matching.spectral import LH05Options
from .guards import guard_match
from .inputs import DEFAULT_POINTS, load
from .options import BACKENDS
from .results import MatchResult

#: Keywords of ``match`` besides the matcher's own options.
_SETTINGS = {"seed": 0, "backend": "heat", "cache": True, "force": False, "largest_component": False,
             "error_bar": True, "suggest": 0}


#: The options dataclass each sample matcher declares its options in.
_DECLARED = {"lh05": LH05Options, "faq": FAQOptions}


def _matcher_options(matcher: str, options: dict, seed: int):
    """The sample matcher's options object (``LH05Options`` or ``FAQOptions``, FAQ's seeded by ``seed``;
    None for zoomout) from ``match``'s other keywords, an unknown one refused before any work."""
    check_choice(matcher, "matcher", MATCHERS)
    declared = _DECLARED.get(matcher)  # zoomout declares none
    known = set() if declared is None else {f.name for f in fields(declared)} - {"seed"}  # seed: match's own
    if set(options) - known:  # refused before the geodesics, not as a TypeError after them
        raise InputError(f"match() got unknown option {sorted(set(options) - known)[0]!r} for matcher "
                         f"{matcher!r} (its options: {', '.join(sorted(known)) or 'none'})")
    if declared is None:
        return None
    return declared(**options, **({"seed": seed} if declared is FAQOptions else {}))


def match_options(matcher, n_points, dense, samples, options: dict):
    """``MatchOptions`` and the load settings from ``match``'s keywords (each checked once; ``options`` is
    emptied of them, and of the matcher's own options)."""
    settings = {k: options.pop(k, v) for k, v in _SETTINGS.items()}
    seed = check_seed(settings["seed"])
    if "k" in options:
        options["k"] = check_int(options["k"], "k", lo=1)
    opts = MatchOptions(matcher=matcher, n_points=check_int(n_points, "n_points", lo=3),
                        backend=check_choice(settings["backend"], "backend", BACKENDS),
                        seed=seed, dense=dense, samples=samples,
                        cache=check_flag(settings["cache"], "cache"),
                        matcher_options=_matcher_options(matcher, options, seed))
    flags = {k: check_flag(settings[k], k) for k in ("largest_component", "force", "error_bar")}
    flags["suggest"] = check_int(settings["suggest"], "suggest", lo=0)
    if flags["suggest"] and not flags["error_bar"]:
        raise InputError("suggesting landmarks reads the error bar: it needs error_bar=True")
    return opts, flags


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
        the error bar; in the summary as ``"suggestions"``, and ``.suggest(k)`` later) and the sample
        matcher's own options (lh05: ``k``, ``rounding``,
        ``refine``...).
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
    options = dict(options)
    opts, flags = match_options(matcher, n_points, dense, options.pop("samples", "fps"), options)
    ids_s, ids_t = parse_ids(landmarks_source, "landmarks_source"), parse_ids(landmarks_target, "landmarks_target")
    src, tgt = load_pair(source, target, flags)
    summary = {"matcher": matcher, "n_landmarks": len(ids_s), "direction": "source to target"}
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


__all__ = ["match"]
