"""Time of one matching and of CNBS-scale on differently meshed shapes, beside baselines of the same run.

Usage:
    python benchmarks/bench_match_time.py [DATA] [--cls cat] [--target cat1] [--baseline REV]
                                          [--cnbs-shape PATH ...]

``DATA`` is a remeshed dataset (``make_remeshed.py``'s output).  On the class's
null shape and one target (each remeshed on its own, 5-8k vertices):

* ``sc.match`` with and without its error bar (``error_bar=False``), 6 landmarks
  (farthest-point samples of the null shape and their
  images through the ``.vts`` ground truth), each matcher, **warm** (its geodesics and
  Laplace-Beltrami bases cached by a first call) and on **one core** (one BLAS and one
  numba thread); the baseline is the pyFM peer of ``bench_remeshed.py`` (functional
  maps + ZoomOut) on the same pair and landmarks, in the same run, if pyFM is installed;
* ``sc.landmarks(shape, 6, "cnbs-scale")`` with the command line's defaults (dense targets),
  geodesics cached, on one core, on each ``--cnbs-shape`` (default: the class's null shape;
  without ``DATA`` only these rows run); the baseline is the same call in the package at
  ``--baseline`` (default: the merge base with ``main``), in the same run, and each row gives
  the landmarks chosen and δ after each (what ``shapecond landmarks`` reports).

Every figure is wall and CPU seconds of a fresh interpreter, with the 1-minute load
average before it; ``benchmarks/RESULTS.md`` sections ``match-time`` (the matchings, when
``DATA`` is given) and ``cnbs-scale-time``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from _results import baseline_src, command_line, git, machine, run_variant, write_section  # noqa: E402

ONE_CORE = {k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")}

MATCH = r"""
import json, time
import numpy as np
import shapecond as sc
null, target, lm_s, lm_t, matcher, bar = {null!r}, {target!r}, {lm_s!r}, {lm_t!r}, {matcher!r}, {bar!r}
sc.match(null, target, lm_s, lm_t, matcher=matcher, error_bar=bar)  # warm: geodesics and bases cached
w, c = time.perf_counter(), time.process_time()
r = sc.match(null, target, lm_s, lm_t, matcher=matcher, error_bar=bar)
print(json.dumps(dict(wall=time.perf_counter() - w, cpu=time.process_time() - c)))
"""

PEER = r"""
import json, time, warnings
import numpy as np
warnings.filterwarnings("ignore")
from pyFM.functional import FunctionalMapping
from pyFM.mesh import TriMesh
import shapecond as sc
null, target, lm_s, lm_t = sc.load({null!r}), sc.load({target!r}), {lm_s!r}, {lm_t!r}
w, c = time.perf_counter(), time.process_time()
m_t = TriMesh(np.asarray(target.vertices), np.asarray(target.faces)).process(200)
m_s = TriMesh(np.asarray(null.vertices), np.asarray(null.faces)).process(200)
model = FunctionalMapping(m_t, m_s)
model.preprocess(n_descr=100, descr_type="WKS", landmarks=np.column_stack([lm_t, lm_s]), subsample_step=5, k_process=200)
model.fit(K=(35, 35), w_descr=1e0, w_lap=1e-2, w_dcomm=1e-1, w_orient=0)
model.get_p2p(FM=model.zoomout_refine(nit=15, step=1))
print(json.dumps(dict(wall=time.perf_counter() - w, cpu=time.process_time() - c)))
"""

CNBS_SCALE = r"""
import json, time
import numpy as np
import shapecond as sc
path = {null!r}
sc.metric_shape(path)                                             # geodesics cached before the timing
P = np.random.default_rng(0).normal(size=(30, 3))
sc.landmarks(np.linalg.norm(P[:, None] - P[None], axis=2), 1, "cnbs-scale", effort="quick")  # numba compiled
w, c = time.perf_counter(), time.process_time()
r = sc.landmarks(path, 6, "cnbs-scale")
print(json.dumps(dict(wall=time.perf_counter() - w, cpu=time.process_time() - c,
                      landmarks=[int(v) for v in r.landmarks], scores=[float(v) for v in r.scores])))
"""


def landmark_pairs(cls_dir: Path, target: str, k: int = 6) -> tuple[str, str, list, list]:
    """The null shape's first ``k`` FPS samples and their images through the ground truth."""
    import shapecond as sc
    from shapecond.evaluation.datasets import read_class
    from shapecond.evaluation.protocols import _reference_ids, landmark_images
    from shapecond.matching.sampled import CachedSolver

    cls = read_class(cls_dir)
    tp = next(p for p in cls.targets if p.stem == target)
    null, g = sc.load(cls.null), sc.load(tp)
    ref_s, ref_t = _reference_ids(cls, cls.null, null), _reference_ids(cls, tp, g)
    lm = [int(v) for v in null.to_internal(sc.landmarks(null, k, "fps", n_points=400, target="samples").landmarks)]
    images = landmark_images(lm, ref_s, ref_t, CachedSolver(null))
    return str(cls.null), str(tp), [int(null.ids[v]) for v in lm], [int(g.ids[v]) for v in images]


def timed(code: str, src=None, env: dict | None = None, cache: Path | None = None) -> dict:
    saved = dict(os.environ)
    os.environ.update(env or {})
    try:
        r = run_variant(code, src=src, cache=cache)
    finally:
        os.environ.clear()
        os.environ.update(saved)
    out = json.loads(r["stdout"].strip().splitlines()[-1])
    return dict(out, load=r["load"])


def match_rows(data: Path, cls: str, target: str | None, cache: Path) -> tuple[list, str]:
    """The matching rows of the class's pair (and the pyFM peer), with the pair's description."""
    cls_dir = data / cls
    target = target or sorted(p.stem for p in (cls_dir / "shapes").glob("*.off"))[1]
    null, tgt, lm_s, lm_t = landmark_pairs(cls_dir, target)
    rows = []
    for matcher in ("lh05", "faq", "zoomout"):
        for bar in (True, False):
            r = timed(MATCH.format(null=null, target=tgt, lm_s=lm_s, lm_t=lm_t, matcher=matcher, bar=bar),
                      env=ONE_CORE, cache=cache)
            rows.append((f"match, {matcher} (warm, one core{'' if bar else ', --no-error-bar'})",
                         "≤ 10 s" if bar else "error bar ≤ 30 % of this", r))
    try:
        r = timed(PEER.format(null=null, target=tgt, lm_s=lm_s, lm_t=lm_t), env=ONE_CORE, cache=cache)
        rows.append(("pyFM + ZoomOut, same pair and landmarks (one core)", "peer", r))
    except RuntimeError as exc:
        print(f"peer not run: {exc}", file=sys.stderr)
    pair = (f"Pair: {Path(null).name} → {Path(tgt).name} (remeshed, 6 landmarks: FPS on the null shape and "
            "their ground-truth images).")
    return rows, pair


def cnbs_rows(shapes: list, sha: str, src: Path, cache: Path) -> list:
    """(shape, variant, run) of ``sc.landmarks(shape, 6, "cnbs-scale")``, ours then the baseline's, one core."""
    rows = []
    for path in shapes:
        for which, s in (("ours", None), (f"baseline {sha[:10]}", src)):
            rows.append((Path(path).name, which, timed(CNBS_SCALE.format(null=str(path)), src=s, env=ONE_CORE,
                                                       cache=cache)))
    return rows


def cnbs_table(rows: list) -> list:
    """Markdown rows of ``cnbs_rows``: landmarks, δ after each, times, and whether ours chose the same
    landmarks as the baseline (the row after it) and reached the same or a lower δ at every step."""
    out = ["| shape | variant | landmarks (vertex ids) | δ after each landmark | wall s | CPU s | load before |",
           "|---|---|---|---|---|---|---|"]
    for i, (name, which, r) in enumerate(rows):
        note = ""
        if which == "ours" and i + 1 < len(rows) and rows[i + 1][0] == name:
            b = rows[i + 1][2]
            same = r["landmarks"] == b["landmarks"]
            lower = all(x <= y for x, y in zip(r["scores"], b["scores"]))
            note = " (same landmarks)" if same else (" (δ same or lower at every step)" if lower else
                                                     " (δ higher at some step)")
        out.append(f"| {name} | {which}{note} | {', '.join(map(str, r['landmarks']))} | "
                   f"{', '.join(f'{v:.4g}' for v in r['scores'])} | {r['wall']:.1f} | {r['cpu']:.1f} | "
                   f"{r['load']:.1f} |")
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("data", type=Path, nargs="?", default=None)
    ap.add_argument("--cls", default="cat")
    ap.add_argument("--target", default=None, help="target shape (default: the class's second shape)")
    ap.add_argument("--baseline", default=None)
    ap.add_argument("--cnbs-shape", action="append", default=None, type=Path,
                    help="shape of the CNBS-scale rows (repeat for several; default: the class's null shape)")
    a = ap.parse_args(argv)
    if a.data is None and not a.cnbs_shape:
        ap.error("give DATA, --cnbs-shape, or both")
    rev = a.baseline or git("merge-base", "HEAD", "main")
    sha, src = baseline_src(rev)
    head = f"Machine: {machine()}. Command: `{command_line()}`."
    with tempfile.TemporaryDirectory() as tmp:
        cache = Path(tmp)
        if a.data is not None:
            rows, pair = match_rows(a.data, a.cls, a.target, cache)
            lines = ["## Matching time on remeshed shapes (bench_match_time.py)", "",
                     f"{head} {pair} Each row is a fresh interpreter; one core = one BLAS and one numba thread.",
                     "", "| what | target | wall s | CPU s | load before |", "|---|---|---|---|---|"]
            lines += [f"| {name} | {goal} | {r['wall']:.1f} | {r['cpu']:.1f} | {r['load']:.1f} |"
                      for name, goal, r in rows]
            write_section("match-time", "\n".join(lines))
            print("\n".join(lines))
        shapes = a.cnbs_shape or [min((a.data / a.cls / "shapes").glob("*.off"))]
        lines = ["## CNBS-scale time: landmarks -k 6 --method cnbs-scale, geodesics cached (bench_match_time.py)",
                 "", (f"{head} Each row is a fresh interpreter on one core (one BLAS and one numba thread), "
                      "with the command line's defaults (N = 400 samples, dense targets); target ≤ 30 s (issue 35). "
                      "δ after each landmark as `shapecond landmarks` reports it (lower bounds, made "
                      "non-increasing)."),
                 ""] + cnbs_table(cnbs_rows(shapes, sha, src, cache))
    write_section("cnbs-scale-time", "\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
