"""``shapecond kappa INPUT --trials K``: empirical probes of the condition number κ.

Paper Section 4, Eq. 4 and Theorem 4.1 (``shapecond.symmetry.condition``):
perturbed copies of the shape's distance matrix, the exact optimal matching of
each, and the ratio d(T_opt, Id) / d(X, X̃).  Exact matching enumerates every
map, so N is small (at most ``MAX_PROBE_POINTS`` free samples).
"""

from __future__ import annotations

import click

from ..errors import InputError
from ..symmetry.condition import MAX_PROBE_POINTS, kappa_probes
from .common import (IDS_HELP, Float, Int, build_shape, emit_json, fmt, info, json_option, parse_ids, pop_shape_options,
                     progress_enabled, shape_options)

#: Samples taken from a mesh when --points is not given.
DEFAULT_KAPPA_POINTS = 8


@click.command("kappa")
@click.argument("input_spec", metavar="INPUT")
@shape_options
@click.option("--landmarks", default=None, help="Vertex ids (row indices for a matrix) fixed by every map: "
              + IDS_HELP + ".")
@click.option("--trials", type=Int(1), default=20, show_default=True, help="Number of perturbed copies probed.")
@click.option("--scale", type=Float(0.0, 10.0, lo_open=True), default=0.05, show_default=True,
              help="Random perturbation size, relative to the RMS distance.")
@click.option("--time-limit", type=Float(0.0, lo_open=True), default=None,
              help="Stop probing after this many seconds (the probes so far are reported).")
@json_option
def command(input_spec, landmarks, trials, scale, time_limit, as_json, **kwargs):
    """Probe κ (Eq. 4) with exact matchings of perturbed copies; report σ <= κ <= 2σ + 1.

    For meshes N defaults to 8 samples; at most 9 samples may be free of landmarks.
    """
    shape_kw = pop_shape_options(kwargs)
    if shape_kw.get("target") == "dense":
        raise InputError("kappa probes match samples to samples; --target dense does not apply")
    shape_kw["target"] = "samples"
    ids = parse_ids(landmarks)
    points = shape_kw.get("points")
    limit = MAX_PROBE_POINTS + len(ids)
    if points is not None and points > limit:
        raise InputError(f"kappa probes enumerate every map: at most {limit} points with "
                         f"{len(ids)} landmarks, got --points {points}")
    is_matrix = input_spec.endswith(".npy")
    if points is None and not is_matrix:
        shape_kw["points"] = min(DEFAULT_KAPPA_POINTS + len(ids), limit)
    shape = build_shape(input_spec, landmarks=ids, **shape_kw)
    if shape.n_points > limit:
        raise InputError(f"kappa probes enumerate every map: at most {limit} points with "
                         f"{len(ids)} landmarks, the input has {shape.n_points}")
    L = list(range(len(ids)))  # build_shape puts the landmarks first
    bar = None
    if progress_enabled():
        from tqdm import tqdm

        bar = tqdm(total=trials, desc="probes", unit="probe", leave=False)
    try:
        res = kappa_probes(shape.D, trials=trials, seed=shape_kw.get("seed", 0), landmarks=L, scale=scale,
                           time_limit=time_limit, force=shape_kw.get("force", False),
                           progress=None if bar is None else lambda done, total: bar.update(1))
    finally:
        if bar is not None:
            bar.close()
    lo, hi = res.kappa
    out = {
        "n_points": shape.n_points,
        "landmarks": ids,
        "samples": shape.sample_ids,
        "trials": trials,
        "probes": list(res.ratios),
        "probe_kinds": list(res.kinds),
        "kappa_probe_max": res.kappa_probe_max,
        "sigma": res.sigma,
        "witness": res.witness,
        "kappa": {"lower": lo, "upper": hi},
        "notes": list(res.notes),
        "seconds": res.seconds,
    }
    if as_json:
        emit_json(out)
        return
    click.echo(f"points             {shape.n_points} ({len(ids)} landmarks)")
    click.echo(f"sigma (exact)      {fmt(res.sigma)}")
    click.echo(f"kappa bracket      [{fmt(lo)}, {fmt(hi)}]   (Theorem 4.1: sigma <= kappa <= 2 sigma + 1)")
    click.echo(f"probes             {len(res.ratios)}, max {fmt(res.kappa_probe_max)}")
    for note in res.notes:
        info(f"note: {note}")
    info(f"{res.seconds:.2f} s")
