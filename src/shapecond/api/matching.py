"""Landmark-guided matching of two shapes through the Python interface (``matching.pipeline``)."""

from __future__ import annotations

from dataclasses import fields
from functools import partial

import numpy as np

from ..checks import check_choice, check_flag, check_int, check_seed, parse_ids
from ..errors import InputError
from ..matching.error_bar import bar_and_samples
from ..matching.pipeline import MATCHERS, MatchOptions, match_samples, match_shapes
from ..matching.sampled import CachedSolver, sample_surface
from ..matching.seeded import FAQOptions
from ..matching.spectral import LH05Options
from ..matching.suggest import suggest_landmarks
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


def _match_options(matcher, n_points, dense, samples, options: dict):
    """``MatchOptions`` and the load settings from ``match``'s keywords (each checked once)."""
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
    for name, ids, D in (("source", ids_s, src), ("target", ids_t, tgt)):
        bad = [v for v in ids if v >= D.shape[0]]
        if bad:
            raise InputError(f"{name} landmark {bad[0]} is out of range (rows 0..{D.shape[0] - 1})")
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
    opts, flags = _match_options(matcher, n_points, dense, options.pop("samples", "fps"), options)
    ids_s, ids_t = parse_ids(landmarks_source, "landmarks_source"), parse_ids(landmarks_target, "landmarks_target")
    src, tgt = _inputs(source, target, ids_s, ids_t, flags)
    summary = {"matcher": matcher, "n_landmarks": len(ids_s), "direction": "source to target"}
    if isinstance(src, np.ndarray) or isinstance(tgt, np.ndarray):
        return _match_matrices(src, tgt, ids_s, ids_t, opts, summary)
    m = _match_pair(src, tgt, ids_s, ids_t, opts, flags["force"])
    lines = np.full(int(src.ids.max()) + 1, -1, dtype=np.int64)
    lines[src.ids] = tgt.ids[m.vertex_map]
    summary.update(n_points=opts.n_points, n_source_vertices=int(src.n_vertices),
                   n_target_vertices=int(tgt.n_vertices), backend=opts.backend, dense=opts.dense,
                   samples=opts.samples, matcher_info=m.sample_map.info if m.sample_map is not None else {})
    if opts.samples == "same-ids":
        summary.update(sample_error=m.info["sample_error"], exact=m.info["exact"])
    doubt, advice = None, None
    if flags["error_bar"]:
        bar, coarse, Dt = _error_bar(m, src, tgt, src.to_internal(ids_s), opts)
        summary["error_bar"] = bar.to_dict()
        doubt = np.full(lines.size, np.nan)
        doubt[src.ids] = bar.doubt[coarse.nearest]
        advice = partial(suggest_landmarks, coarse, Dt, bar, len(ids_s), m.vertex_map, tgt.ids, seed=opts.seed)
    result = MatchResult(lines, summary, (src, tgt, src.to_internal(ids_s), tgt.to_internal(ids_t)), doubt, advice)
    if flags["suggest"]:
        result.suggest(flags["suggest"])  # recorded in the summary
    return result


def _inputs(source, target, ids_s, ids_t, flags):
    """The two loaded inputs of a matching, once their landmark counts agree."""
    if len(ids_s) != len(ids_t):
        raise InputError(f"landmark counts differ: {len(ids_s)} on the source, {len(ids_t)} on the target")
    largest, force = flags["largest_component"], flags["force"]
    return load(source, largest_component=largest, force=force), load(target, largest_component=largest, force=force)


def _match_pair(src, tgt, ids_s, ids_t, opts, force):
    """``matching.pipeline.match_shapes`` of two loaded shapes, guarded (``guards.guard_match``)."""
    guard_match(max(src.n_vertices, tgt.n_vertices), opts.n_points, len(ids_s), opts, force)
    return match_shapes(src, tgt, src.to_internal(ids_s), tgt.to_internal(ids_t), opts)


def _bar_inputs(m, src, tgt, landmarks, opts):
    """The matcher's source samples (sampled here when it has none: the zoomout matcher with 3
    landmarks) and the target's distance solver: what ``matching.error_bar`` reads a map's distortion
    with."""
    source = m.source if m.source is not None else sample_surface(src, opts.n_points, opts.backend, opts.seed,
                                                                  landmarks, opts.cache)
    solver = m.target_solver if m.target_solver is not None else CachedSolver(tgt, opts.backend)
    if m.target is not None:
        solver.remember(m.target)
    return source, solver


def _error_bar(m, src, tgt, landmarks, opts):
    """``matching.error_bar.bar_and_samples`` on the matcher's samples."""
    source, solver = _bar_inputs(m, src, tgt, landmarks, opts)
    return bar_and_samples(source, tgt, m.vertex_map, len(landmarks), opts.seed, solver)


__all__ = ["match"]
