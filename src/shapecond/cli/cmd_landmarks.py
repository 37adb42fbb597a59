"""``shapecond landmarks INPUT -k K --method ...``: where to put landmarks (paper Sections 6-7)."""

from __future__ import annotations

import click

from ..landmarks import METHODS, SCORES, select_landmarks
from ..limits import check_cost, search_seconds
from .common import (IDS_HELP, Float, Int, build_shape, emit_json, fmt, info, json_option, load_geometry_or_matrix,
                     parse_ids, pop_shape_options, progress_enabled, shape_options)


def guess_up(shape, up):
    """Vertical axis for pictures: --up, else ``viz.render.guess_up`` (animal y, TOSCA z)."""
    from ..viz.render import guess_up as guess

    return up or guess(shape.geometry)


def draw_landmarks(shape, result, png, ply, up, title):
    """Landmark pictures (Figure 6 colours) as PNG and/or PLY; matrices are drawn by MDS."""
    from ..viz.ply import write_ply
    from ..viz.render import render_png
    from ..symmetry.starts import classical_mds

    if shape.geometry is not None:
        V, F, verts = shape.geometry.vertices, shape.geometry.faces, list(result.vertices)
    else:
        V, F, verts = classical_mds(shape.D), None, list(result.sample_indices)
    if png:
        render_png(png, V, F, None, verts, up=up, title=title,
                   point_size=6.0 if F is not None or len(V) > 2000 else 30.0)
        info(f"wrote {png}")
    if ply:
        write_ply(ply, V, F, None, verts)
        info(f"wrote {ply}")


@click.command("landmarks")
@click.argument("input_spec", metavar="INPUT")
@shape_options
@click.option("-k", "k", type=Int(0, 100_000), required=True, help="Number of landmarks (method user: 0 = all given).")
@click.option("--method", type=click.Choice(METHODS), default="cnbs", show_default=True,
              help="cnbs: condition number based sampling (the paper's σ); cnbs-scale: CNBS on the "
                   "scale-aware score δ(ε); fps; pls (Tevs et al., reimplemented); hks (heat kernel "
                   "signature extrema); user (--user-landmarks); cnbs-local.")
@click.option("--user-landmarks", default=None, help="For --method user: vertex ids, " + IDS_HELP + ".")
@click.option("--scores/--no-scores", default=None,
              help="Compute the symmetry score after each landmark (always on for cnbs; for the "
                   "baselines it costs one witness search per landmark).")
@click.option("--effort", type=click.Choice(["quick", "default", "thorough"]), default="default",
              show_default=True, help="Effort of the witness searches.")
@click.option("--score", "score", type=click.Choice(SCORES), default=None,
              help="Score after each landmark: sigma (the paper's) or scale (δ(ε)) "
                   "[default: scale for cnbs-scale, sigma otherwise].")
@click.option("--epsilon", type=Float(0.0), default=None,
              help="Distortion level ε of the scale-aware score [default: the median sample spacing].")
@click.option("--png", type=click.Path(dir_okay=False), default=None, help="Picture of the landmarks (PNG).")
@click.option("--ply", type=click.Path(dir_okay=False), default=None, help="Mesh with landmarks painted (PLY).")
@click.option("--html", type=click.Path(dir_okay=False), default=None,
              help="Self-contained HTML page of the landmarks in order with their scores.")
@click.option("--up", type=click.Choice(["x", "y", "z"]), default=None, help="Vertical axis of the pictures.")
@json_option
def command(input_spec, k, method, user_landmarks, scores, effort, score, epsilon, png, ply, html, up, as_json,
            **kwargs):
    """Choose K landmarks and report the symmetry score after each one.

    Landmarks are vertex ids of INPUT (rows for a distance matrix), in order; scores
    are the global symmetry score (lower bound with witness) with the first 1, 2, ...
    landmarks fixed: the paper's "vector of symmetry scores".
    """
    shape_kw = pop_shape_options(kwargs)
    user_ids = parse_ids(user_landmarks, "--user-landmarks") if user_landmarks else []
    if method == "user" and not user_ids:
        raise click.UsageError("--method user needs --user-landmarks")
    loaded = load_geometry_or_matrix(input_spec, shape_kw.get("largest_component", False),
                                     shape_kw.get("symmetry_map"), shape_kw.get("force", False))
    shape = build_shape(input_spec, landmarks=user_ids, loaded=loaded, **shape_kw)
    seed = shape_kw.get("seed", 0)
    cnbs = method in ("cnbs", "cnbs-scale")
    if cnbs or scores:  # CNBS: about 4 searches' worth per landmark (measured on TOSCA)
        check_cost(f"{method} with {k} landmarks at N = {shape.n_samples}",
                   search_seconds(shape.n_samples, shape.n_targets, (4 if cnbs else 1) * max(k, 1)),
                   force=shape_kw.get("force", False))
    kw = {}
    if method == "user":
        kw["ids"] = user_ids
    if method in ("cnbs", "cnbs-scale") and progress_enabled():
        kw["progress"] = lambda step, done, total: click.echo(
            f"\rlandmark {step + 1}/{k}: heat map {done}/{total}", err=True, nl=done == total)
    result = select_landmarks(shape, k, method, seed=seed, scores=scores, effort=effort, score=score,
                              epsilon=epsilon, **kw)
    title = f"{method}: " + ", ".join(f"{v}" for v in result.landmarks)
    if png or ply:
        draw_landmarks(shape, result, png, ply, guess_up(shape, up), title)
    if html:
        info(f"wrote {result.to_html(html, up=guess_up(shape, up), title=title)}")
    d = result.to_dict()
    if as_json:
        emit_json({key: d[key] for key in ("landmarks", "scores", "method", "seconds", "score")})
    else:
        name = "delta" if result.score == "scale" else "sigma"
        if result.initial_score is not None:
            click.echo(f"{name} without landmarks: {fmt(result.initial_score)}")
        for i, (v, s) in enumerate(zip(result.landmarks, result.scores), 1):
            click.echo(f"{i:3d}  vertex {v:>8d}  {name} after: {fmt(s)}")
        click.echo(f"{method}, {shape.n_samples} samples, {result.seconds:.2f} s")
