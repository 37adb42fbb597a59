"""``shapecond match SOURCE TARGET --landmarks-source IDS --landmarks-target IDS -o MAP.txt``.

Landmark-guided matching of one pair, **source to target**.
"""

from __future__ import annotations

import time
from pathlib import Path

import click
import numpy as np

from ..errors import InputError
from ..matching.pipeline import MATCHERS, SAMPLINGS, match_samples, match_shapes
from ..shapes.geometry import Geometry
from ..shapes.io import atomic_write, load_input
from .common import emit_json, info, json_option, parse_ids


@click.command("match")
@click.argument("source", metavar="SOURCE")
@click.argument("target", metavar="TARGET")
@click.option("--landmarks-source", required=True,
              help="Landmark vertex ids on SOURCE (comma-separated, or a file of ids).")
@click.option("--landmarks-target", required=True,
              help="The corresponding vertex ids on TARGET, in the same order.")
@click.option("--matcher", type=click.Choice(MATCHERS), default="lh05", show_default=True,
              help="lh05: Leordeanu-Hebert spectral matching (the paper); faq: seeded graph matching.")
@click.option("--points", "-n", type=int, default=400, show_default=True,
              help="Farthest-point samples per shape.")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of every random choice.")
@click.option("--geodesic-backend", type=click.Choice(["heat", "fmm", "exact"]), default="heat",
              show_default=True, help="Geodesic solver.")
@click.option("--k", "k", type=int, default=20, show_default=True,
              help="lh05: candidate target samples per source sample.")
@click.option("--rounding", type=click.Choice(["greedy", "assignment"]), default="assignment",
              show_default=True, help="lh05: a linear assignment or the paper's greedy discretisation.")
@click.option("--refine/--no-refine", default=True, show_default=True,
              help="lh05: refine the rounded map on its own objective, with spectral rounds on candidates "
                   "iterated from it (--no-refine --rounding greedy: the paper's plain LH05).")
@click.option("--samples", type=click.Choice(SAMPLINGS), default="fps", show_default=True,
              help="fps: each shape gets its own farthest-point samples; same-ids: the target is sampled "
                   "at the source's sample vertices (shapes with a common vertex order; the evaluation's "
                   "corresponding protocol) and the summary reports the sample map's error.")
@click.option("--dense", type=click.Choice(["distances", "nearest"]), default="distances",
              show_default=True, help="How the sample map is extended to every source vertex.")
@click.option("--largest-component", is_flag=True, help="Keep only the largest connected component.")
@click.option("--no-cache", is_flag=True, help="Do not read or write the distance cache.")
@click.option("-o", "--output", required=True, type=click.Path(dir_okay=False),
              help="Map file: line i holds the TARGET vertex id matched to SOURCE vertex i.")
@json_option
def command(source, target, landmarks_source, landmarks_target, matcher, points, seed,
            geodesic_backend, k, rounding, refine, samples, dense, largest_component, no_cache, output,
            as_json):
    """Match SOURCE to TARGET with corresponding landmarks fixed; write the dense map.

    The map file has one line per SOURCE vertex id (0 .. largest id): the id of
    the TARGET vertex it is matched to, or -1 for a vertex dropped on loading
    (unreferenced by any face).  For two N x N distance matrices (.npy) the map
    is between their rows.  With --json a summary goes to stdout.
    """
    t0 = time.perf_counter()
    ids_s, ids_t = parse_ids(landmarks_source), parse_ids(landmarks_target)
    if len(ids_s) != len(ids_t):
        raise InputError(f"landmark counts differ: {len(ids_s)} on the source, {len(ids_t)} on the target")
    src = load_input(source, largest_component=largest_component)
    tgt = load_input(target, largest_component=largest_component)
    options = {"k": k, "rounding": rounding, "refine": refine} if matcher == "lh05" else {}
    if isinstance(src, np.ndarray) or isinstance(tgt, np.ndarray):
        if samples != "fps":
            raise InputError("--samples same-ids needs two meshes or point clouds, not distance matrices")
        lines, summary = _match_matrices(src, tgt, ids_s, ids_t, matcher, seed, options)
    else:
        lines, summary = _match_geometries(src, tgt, ids_s, ids_t, matcher, points, seed,
                                           geodesic_backend, dense, not no_cache, options, samples)
    out = Path(output)
    with atomic_write(out) as tmp:
        np.savetxt(tmp, lines, fmt="%d")
    summary.update(source=str(source), target=str(target), matcher=matcher, output=str(out),
                   direction="source to target", n_landmarks=len(ids_s),
                   seconds=time.perf_counter() - t0)
    if as_json:
        emit_json(summary)
    else:
        info(f"wrote {out}: {len(lines)} source vertices matched to {target} ({matcher}, "
             f"{len(ids_s)} landmarks, {summary['seconds']:.1f} s)")


def _match_matrices(Ds, Dt, ids_s, ids_t, matcher, seed, options):
    if not (isinstance(Ds, np.ndarray) and isinstance(Dt, np.ndarray)):
        raise InputError("match two meshes/point clouds or two distance matrices, not one of each")
    for name, ids, D in (("source", ids_s, Ds), ("target", ids_t, Dt)):
        bad = [v for v in ids if v >= D.shape[0]]
        if bad:
            raise InputError(f"{name} landmark {bad[0]} is out of range (rows 0..{D.shape[0] - 1})")
    if Dt.shape[0] < Ds.shape[0]:
        raise InputError(f"the target matrix has fewer rows ({Dt.shape[0]}) than the source ({Ds.shape[0]})")
    sm = match_samples(Ds / Ds.max(), Dt / Dt.max(), ids_s, ids_t, matcher, seed=seed, **options)
    return sm.t, {"n_points": int(Ds.shape[0]), "matcher_info": sm.info}


def _match_geometries(src: Geometry, tgt: Geometry, ids_s, ids_t, matcher, points, seed, backend,
                      dense, cache, options, samples="fps"):
    ls, lt = src.to_internal(ids_s), tgt.to_internal(ids_t)
    m = match_shapes(src, tgt, ls, lt, matcher=matcher, n_points=points, backend=backend,
                     seed=seed, dense=dense, cache=cache, samples=samples, **options)
    n_file = int(src.ids.max()) + 1
    lines = np.full(n_file, -1, dtype=np.int64)
    lines[src.ids] = tgt.ids[m.vertex_map]
    summary = {"n_points": points, "n_source_vertices": int(src.n_vertices),
               "n_target_vertices": int(tgt.n_vertices), "backend": backend, "dense": dense,
               "samples": samples, "matcher_info": m.sample_map.info}
    if samples == "same-ids":
        summary.update(sample_error=m.info["sample_error"], exact=m.info["exact"])
    return lines, summary
