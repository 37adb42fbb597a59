"""One shape, one row: the per-shape task of batch scoring (runs on a worker).

``shape_row`` fills the columns of ``schema.COLUMNS`` through the Python
interface (``shapecond.api``) that the single-shape commands call, so that a row
holds what ``shapecond info``, ``score --json``, ``local --json`` and
``landmarks --json`` print for that shape with the same options.  It never raises for a bad shape: the row's ``error``
column gets the one-line message, and the columns computed before the failure
are kept.
"""

from __future__ import annotations

import json
import math
import os
import time
from dataclasses import dataclass

import numpy as np

from .. import api
from .._version import __version__
from ..api import DEFAULT_POINTS
from ..api.collection import collection_settings, match_both_ways, match_to_template
from ..api.params import EFFORT, EPSILON, SHAPE_OPTIONS, SHAPE_PARAMS, cli_defaults, from_cli_keys
from ..checks import check_float
from ..errors import InputError, ShapecondError
from ..parallel import PeakMemory, worker_name
from ..selection import METHODS
from ..symmetry import objective
from . import schema
from .inputs import content_hash

#: The options of ``shapecond score`` a batch takes (``api.params``), with the command line's defaults.
#: They are held, and stored in the ``params`` column, under the command line's names (``params.cli_key``:
#: ``points``, ``geodesic_backend``, ``no_cache``), which the tables written so far hold; ``shape_keywords``
#: gives the Python keywords.
DEFAULT_OPTIONS = {**cli_defaults((*SHAPE_OPTIONS, EFFORT, EPSILON)), "what": ["score"], "matcher": None,
                   "landmark_table": None, "pairs": None, "both_directions": False}
#: ``epsilon`` read off the collection itself (``api.level.collection_level``) rather than given.
COLLECTION = "collection"
#: Options of matching (``--what match:TEMPLATE``): left out of the parameters of a batch without it.
MATCH_OPTIONS = ("matcher", "landmark_table", "pairs", "both_directions")
#: Options that shape the results (``no_cache`` and ``force`` do not).
KEY_OPTIONS = tuple(k for k in DEFAULT_OPTIONS if k not in ("no_cache", "force"))


@dataclass(frozen=True)
class What:
    """What to compute beyond ``info``: the global score, the local score, K landmarks of a method,
    the map from a template (its absolute path), or the maps of listed pairs (``pairs``: ``match`` alone,
    the pairs in the ``pairs`` option)."""

    score: bool = True
    local: bool = False
    landmarks: tuple | None = None   # (K, METHOD)
    match: str | None = None
    pairs: bool = False

    @property
    def matching(self) -> bool:
        """Whether shapes are matched (to a template or in listed pairs)."""
        return self.match is not None or self.pairs

    def items(self) -> list[str]:
        """The canonical ``--what`` list (the form stored in the ``params`` column)."""
        out = (["score"] if self.score else []) + (["local"] if self.local else [])
        out += [f"landmarks:{self.landmarks[0]}:{self.landmarks[1]}"] if self.landmarks else []
        return out + ([f"match:{self.match}"] if self.match else []) + (["match"] if self.pairs else [])


def parse_what(items) -> What:
    """``["score", "local", "landmarks:5:fps", "match:T.off"]`` (or one comma-separated string) -> ``What``;
    ``match`` alone: the pairs of the ``pairs`` option."""
    if isinstance(items, str):
        items = [items]
    parts = [p.strip() for item in items for p in str(item).split(",") if p.strip()] or ["score"]
    score = local = False
    landmarks = match = None
    pairs = False
    for p in parts:
        if p == "score":
            score = True
        elif p == "local":
            local = True
        elif p.startswith("landmarks"):
            bits = p.split(":")
            if len(bits) != 3 or not bits[1].isdigit() or int(bits[1]) < 1:
                raise InputError(f"--what {p!r}: expected landmarks:K:METHOD, e.g. landmarks:5:fps")
            if bits[2] not in METHODS or bits[2] == "user":
                raise InputError(f"--what {p!r}: unknown method {bits[2]!r} "
                                 f"(choose from {', '.join(m for m in METHODS if m != 'user')})")
            if landmarks is not None:
                raise InputError("--what: one landmarks:K:METHOD per batch")
            landmarks = (int(bits[1]), bits[2])
        elif (p.startswith("match:") and p[6:]) or p == "match":
            if match is not None or pairs:
                raise InputError("--what: one match:TEMPLATE (or one match, with --pairs) per batch")
            t = p[6:]
            match, pairs = ((t if t.startswith("demo:") else os.path.abspath(t)), False) if p != "match" else (None, True)
        else:
            raise InputError(f"--what {p!r}: choose score, local, landmarks:K:METHOD, match:TEMPLATE or match "
                             "(with --pairs)")
    return What(score, local, landmarks, match, pairs)


def with_defaults(options: dict) -> dict:
    """``options`` completed with ``DEFAULT_OPTIONS`` (None counts as not given); unknown keys refused."""
    unknown = set(options) - set(DEFAULT_OPTIONS)
    if unknown:
        raise InputError(f"unknown batch option {sorted(unknown)[0]!r}")
    out = {**DEFAULT_OPTIONS, **{k: v for k, v in options.items() if v is not None}}
    what = parse_what(out["what"])
    out["what"] = what.items()
    if what.pairs != (out["pairs"] is not None):
        raise InputError("--pairs FILE matches the pairs it lists: give it with --what match (not match:TEMPLATE)"
                         if out["pairs"] is not None else "--what match needs --pairs FILE (or use match:TEMPLATE)")
    if out["both_directions"] and not what.matching:
        raise InputError("--both-directions needs --what match:TEMPLATE or --pairs FILE")
    if out["epsilon"] is not None and out["epsilon"] != COLLECTION:
        out["epsilon"] = check_float(out["epsilon"], "epsilon", lo=0.0)
    return out


def params_key(options: dict) -> str:
    """The ``params`` column: the result-shaping options as sorted compact JSON.

    Options not given take their defaults, so that the key does not depend on
    how the batch was started; a symmetry map enters by its content hash, so
    that it does not depend on where the file lies.
    """
    key = {k: v for k, v in with_defaults(options).items() if k in KEY_OPTIONS}
    if key["epsilon"] is None:  # the default level: the key of the tables written before there was a choice
        del key["epsilon"]
    what = parse_what(key["what"])
    if not what.matching:  # the key of the tables written before there was matching
        key = {k: v for k, v in key.items() if k not in MATCH_OPTIONS}
    else:
        del key["pairs"]  # each row's params name its pair (matches.MatchPlan.params), not the list
        if not key["both_directions"]:  # the key of the tables written before there were two directions
            del key["both_directions"]
        if what.match:
            key["template"] = content_hash(what.match)
        if key["landmark_table"]:
            key["landmark_table"] = content_hash(str(key["landmark_table"]))
    if key.get("symmetry_map"):
        key["symmetry_map"] = content_hash(str(key["symmetry_map"]))
    return json.dumps(key, sort_keys=True, separators=(",", ":"))


def shape_row(spec: str, expected_hash: str | None, options: dict, params: str, match=None) -> dict:
    """The row of one shape (see ``schema.COLUMNS``); failures go to its ``error`` column.

    ``match``: when matching, the shape's ``matches.MatchJob`` (what it is matched with, both sets of
    landmarks, the directions); the map is returned under the key ``"_map"``, and the second direction's
    match columns and map under ``"_reverse"`` (the caller writes the maps and splits the row,
    ``matches.MatchPlan.rows_of``, before the rows are stored).
    """
    row = schema.empty_row()
    row.update(file=spec, content_hash=expected_hash, params=params, version=__version__, worker=worker_name())
    t0, c0 = time.perf_counter(), time.process_time()
    with PeakMemory() as mem:
        try:
            _check_file(spec, expected_hash)
            _fill(row, spec, options, match)
        except ShapecondError as exc:
            row["error"] = _one_line(exc) or "bad input"
        except MemoryError:
            row["error"] = "out of memory; try fewer --points"
        except Exception as exc:  # noqa: BLE001 - an internal failure is one shape's error too
            row["error"] = f"internal failure: {exc.__class__.__name__}: {_one_line(exc)}"
    row["seconds"], row["cpu_seconds"] = time.perf_counter() - t0, time.process_time() - c0
    row["peak_memory_mib"] = mem.mib
    return row


def _one_line(exc) -> str:
    text = str(exc)
    return text.splitlines()[0] if text else ""


def _check_file(spec: str, expected_hash: str | None) -> None:
    """InputError if this worker cannot see the file, or sees other bytes than the client hashed."""
    if spec.startswith("demo:"):
        return
    if not os.path.exists(spec):
        raise InputError(f"no such file on worker {worker_name()} (every worker must see the input paths)")
    try:
        digest = content_hash(spec)
    except InputError as exc:
        raise InputError(f"on worker {worker_name()}: {exc}") from None
    if expected_hash is not None and digest != expected_hash:
        raise InputError(f"the file on worker {worker_name()} differs from the one the batch hashed "
                         "(changed since, or another file at the same path)")


def _fill(row: dict, spec: str, options: dict, match=None) -> None:
    what = parse_what(options.get("what") or ["score"])
    info = api.info(spec)
    row.update(kind=info["kind"], vertices=info["n_vertices"], faces=info["n_faces"],
               components=info["components"], problems="; ".join(info["problems"]) or None)
    kw = shape_keywords(options)
    effort = options.get("effort") or EFFORT.default
    force = kw["force"]
    loaded = api.load(spec, largest_component=kw["largest_component"], symmetry_map=kw["symmetry_map"], force=force)
    shape = None
    if what.score or what.landmarks:
        shape = api.metric_shape(loaded, options.get("points"), **kw)
        row.update(n_points=shape.n_points, n_targets=shape.n_targets, covering_radius=shape.covering_radius)
    eps = options.get("epsilon")
    if what.score:
        _score_columns(row, api.score(shape, effort=effort, epsilon=eps, **kw))
    if what.local:
        if isinstance(loaded, np.ndarray):
            raise InputError("a distance matrix has no surface to deform: the local score needs a triangle mesh")
        res = api.local_score(loaded, force=force)
        row.update(local_score=res.score, local_lambda_min=res.lambda_min,
                   local_zero_modes="; ".join(res.zero_modes) or None)
    if what.landmarks:
        k, method = what.landmarks
        level = {"epsilon": eps} if eps is not None and method == "cnbs-scale" else {}
        res = api.landmarks(shape, k, method, scores=True, effort=effort, **kw, **level)
        row.update(landmark_method=method, landmarks=[int(v) for v in res.landmarks],
                   landmark_scores=[math.nan if s is None else float(s) for s in res.scores])
    if what.matching:
        _match_columns(row, match, loaded, {**kw, "points": options.get("points"), "matcher": options.get("matcher")})


def shape_keywords(options: dict) -> dict:
    """The keywords of ``api.metric_shape`` (``params.SHAPE_PARAMS``) from a batch's ``options``, held
    under the command line's names (missing or None: the default)."""
    return from_cli_keys(SHAPE_PARAMS, options)


def _match_columns(row: dict, job, shape, kw: dict) -> None:
    """The match columns (``schema.MATCH_COLUMNS``) and ``"_map"`` of ``job.reference`` matched to ``shape``;
    with a second direction, ``"_reverse"``: its columns and map (``"_map"``)."""
    if job is None:
        raise InputError("matching needs the landmarks of both shapes")
    row.update(match_template=job.template, match_direction=job.directions[0], match_source=job.reference,
               match_target=row["file"])
    settings = collection_settings(dict(matcher=kw["matcher"] or "lh05", n_points=kw["points"] or DEFAULT_POINTS,
                                        seed=kw["seed"], backend=kw["backend"], cache=kw["cache"], force=kw["force"],
                                        largest_component=kw["largest_component"]), "batch")
    heads = (job.reference, shape, job.reference_lm, job.shape_lm, settings)
    if len(job.directions) == 1:
        fields, vertex_map = match_to_template(*heads, reference=job.reference_words, view=True)
        row.update(fields, _map=vertex_map)
        return
    (fields, vertex_map), (back, back_map) = match_both_ways(*heads, reference=job.reference_words, view=True)
    row.update(fields, _map=vertex_map)
    row["_reverse"] = {**back, "match_direction": job.directions[1], "match_source": row["file"],
                       "match_target": job.reference, "_map": back_map}


def _score_columns(row: dict, result) -> None:
    """The global score's columns, from the report ``shapecond score --json`` prints."""
    report, sc = result.to_dict(), result.score
    n = sc.n_points
    moved = np.asarray(sc.witness) != np.arange(n)
    row.update(sigma_lower=sc.sigma_lower, sigma_upper=sc.sigma_upper, sigma_hat=sc.sigma_hat_lower,
               swap_floor=float(sc.swap_floor),
               resolution=None if report["resolution"] is None else report["resolution"]["flag"],
               witness_moved=float(moved.mean()),
               witness_displacement=math.sqrt(objective.d2(result.shape.D, sc.witness) / n))
    row.update(scale_aware_values(report))


def scale_aware_values(report: dict) -> dict:
    """Columns of the scale-aware score (``schema.SCALE_AWARE_COLUMNS``) from a score report."""
    d = report.get("scale")
    if d is None:
        return {}
    return {"delta": d["displacement"], "delta_epsilon": d["epsilon"], "delta_moved": d["moved"]}
