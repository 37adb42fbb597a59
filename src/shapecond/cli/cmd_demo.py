"""``shapecond demo``: the whole pipeline on the built-in four-legged animal.

1. the metric shape: N = 400 geodesic farthest-point samples, taken in mirror pairs;
2. the global symmetry score (paper Eq. 5) with its witness map: ∞ for the exactly
   symmetric animal (``--delta 0``), the mirror map as witness;
3. CNBS (paper Section 6): the heat map (σ with each sample fixed) and three
   landmarks with the score after each, on the first ``--landmark-points`` samples
   (CNBS re-solves the score per candidate; N = 100 keeps the demo to seconds).

Pictures: witness.png, heatmap.png and landmarks.png, and demo.html (the same three
scenes in a self-contained page to turn in a browser, ``viz.pages.demo_page``).
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import click
import numpy as np

from ..api import landmarks, load, metric_shape, score
from ..errors import InputError
from ..jsonable import fmt
from ..output import write_text
from .common import SEED, Command, Float, Int, emit_json, force_option, info, json_option, progress_enabled


def _pictures(out: Path, shape, score, small, heat, chosen) -> dict:
    from ..viz.heatmap import render_heatmap_png
    from ..viz.pages import demo_page
    from ..viz.render import Look, render_png
    from ..viz.scene import HeatMapStyle, Place
    from ..viz.witness import render_witness_png

    paths = {"witness": out / "witness.png", "heatmap": out / "heatmap.png", "landmarks": out / "landmarks.png",
             "html": out / "demo.html"}
    render_witness_png(shape, score.witness, paths["witness"], place=Place("y"))
    values = np.where(np.isfinite(heat.values), heat.values, np.nan)
    values = np.where(np.isnan(values), np.nanmax(values) if np.any(np.isfinite(values)) else 1.0, values)
    render_heatmap_png(small, values, paths["heatmap"],
                       style=HeatMapStyle("y", title=f"sigma with each point fixed (before: {fmt(heat.sigma_before)})"))
    g = small.geometry
    render_png(paths["landmarks"], g.vertices, g.faces, None, [int(small.samples[i]) for i in chosen.sample_indices],
               look=Look(up="y", title="three CNBS landmarks (red)"))
    write_text(paths["html"], demo_page(shape, score, small, values, chosen))  # the same scenes, to turn
    return {k: str(v) for k, v in paths.items()}


@click.command("demo", cls=Command)
@click.option("--points", "-n", type=Int(3, 5000), default=400, show_default=True, help="Number of samples N.")
@click.option("--landmark-points", type=Int(3, 5000), default=100, show_default=True,
              help="Samples used by CNBS (the first ones of the same sampling).")
@click.option("--delta", type=Float(-0.5, 1.0), default=0.0, show_default=True,
              help="Asymmetry of the generated animal (0 = exactly mirror-symmetric).")
@click.option("--out", type=click.Path(file_okay=False), default="shapecond-demo", show_default=True,
              help="Folder for the pictures.")
@click.option("--seed", type=SEED, default=0, show_default=True)
@force_option
@json_option
def command(points, landmark_points, delta, out, seed, force, as_json):
    """Score the generated animal, show its witness map, and pick three CNBS landmarks."""
    if not landmark_points <= points:
        raise InputError("--landmark-points must lie between 3 and --points")
    t0 = time.perf_counter()
    out = Path(out)
    geometry = load(f"demo:animal:delta={delta}")
    shape = metric_shape(geometry, points, seed=seed, target="samples", progress=progress_enabled(), force=force)
    result = score(shape, seed=seed, force=force)
    sc = result.score
    inverse = {int(v): k for k, v in enumerate(shape.samples)}
    mirror = np.array([inverse.get(int(geometry.symmetry[v]), -1) for v in shape.samples])
    small = metric_shape(geometry, landmark_points, seed=seed, target="samples")
    chosen = landmarks(small, 3, "cnbs", seed=seed, keep_heat_maps=True)
    heat = chosen.heat_maps[0]  # sigma with each sample fixed, before any landmark
    pictures = _pictures(out, shape, sc, small, heat, chosen)
    summary = {
        "shape": f"demo:animal:delta={delta}",
        "n_vertices": geometry.n_vertices,
        "n_points": shape.n_points,
        "metric": shape.metric,
        "backend": shape.backend,
        "diameter": shape.scale,
        "covering_radius": shape.covering_radius,
        "sigma": sc.to_dict()["sigma"],
        "sigma_hat": sc.to_dict()["sigma_hat"],
        "kappa": sc.to_dict()["kappa"],
        "witness_is_mirror_map": bool(np.array_equal(sc.witness, mirror)),
        "delta": result.scale.displacement,
        "verdict": result.verdict,
        "landmark_points": small.n_points,
        "landmarks": [int(v) for v in chosen.landmarks],
        "scores": list(chosen.scores),
        "initial_score": heat.sigma_before,
        "pictures": pictures,
        "seconds": time.perf_counter() - t0,
    }
    if as_json:
        emit_json(summary)
        return
    sig = summary["sigma"]
    click.echo(f"shape        demo:animal, delta = {delta} ({geometry.n_vertices} vertices)")
    click.echo(f"samples      N = {shape.n_points} {shape.metric} FPS samples ({shape.backend} method), "
               f"taken in mirror pairs")
    click.echo(f"sigma        [{fmt(sig['lower'])}, {fmt(sig['upper'])}]   kappa in "
               f"[{fmt(summary['kappa']['lower'])}, {fmt(summary['kappa']['upper'])}]")
    what = "the mirror map" if summary["witness_is_mirror_map"] else "a non-mirror map"
    ambiguity = "an exact symmetry: matching cannot tell left from right" if math.isinf(sc.sigma_lower) else \
        "a near-isometry that makes matching ambiguous"
    click.echo(f"witness      {what}: {ambiguity}")
    click.echo(f"verdict      {summary['verdict']}")
    steps = ", ".join(f"{v} (sigma {fmt(s)})" for v, s in zip(summary["landmarks"], summary["scores"]))
    click.echo(f"CNBS         N = {small.n_points}, sigma {fmt(heat.sigma_before)} before; landmarks: {steps}")
    click.echo(f"pictures     {', '.join(pictures.values())}")
    info(f"done in {summary['seconds']:.1f} s")
