"""Time of one matching and of CNBS-scale on differently meshed shapes, beside baselines of the same run.

Usage:
    python benchmarks/bench_match_time.py DATA [--cls cat] [--target cat1] [--baseline REV]

``DATA`` is a remeshed dataset (``make_remeshed.py``'s output).  On the class's
null shape and one target (each remeshed on its own, 5-8k vertices):

* ``sc.match`` with and without its error bar (``error_bar=False``), 6 landmarks
  (farthest-point samples of the null shape and their
  images through the ``.vts`` ground truth), each matcher, **warm** (its geodesics and
  Laplace-Beltrami bases cached by a first call) and on **one core** (one BLAS and one
  numba thread); the baseline is the pyFM peer of ``bench_remeshed.py`` (functional
  maps + ZoomOut) on the same pair and landmarks, in the same run, if pyFM is installed;
* ``sc.landmarks(null, 6, "cnbs-scale")`` with the command line's defaults (dense targets),
  geodesics cached, on 2 cores; the baseline is the same call in the package at
  ``--baseline`` (default: the merge base with ``main``), in the same run.

Every figure is wall and CPU seconds of a fresh interpreter, with the 1-minute load
average before it; ``benchmarks/RESULTS.md`` section ``match-time``.
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
import shapecond as sc
path = {null!r}
sc.metric_shape(path)                                             # geodesics cached before the timing
w, c = time.perf_counter(), time.process_time()
r = sc.landmarks(path, 6, "cnbs-scale")
print(json.dumps(dict(wall=time.perf_counter() - w, cpu=time.process_time() - c,
                      landmarks=[int(v) for v in r.landmarks])))
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


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("data", type=Path)
    ap.add_argument("--cls", default="cat")
    ap.add_argument("--target", default=None, help="target shape (default: the class's second shape)")
    ap.add_argument("--baseline", default=None)
    a = ap.parse_args(argv)
    cls_dir = a.data / a.cls
    target = a.target or sorted(p.stem for p in (cls_dir / "shapes").glob("*.off"))[1]
    null, tgt, lm_s, lm_t = landmark_pairs(cls_dir, target)
    rev = a.baseline or git("merge-base", "HEAD", "main")
    sha, src = baseline_src(rev)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        cache = Path(tmp)
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
        for which, s in (("ours", None), (f"baseline {sha[:10]}", src)):
            r = timed(CNBS_SCALE.format(null=null), src=s, cache=cache)
            rows.append((f"landmarks -k 6 --method cnbs-scale, geodesics cached ({which})", "≤ 30 s", r))
    lines = ["## Matching and CNBS-scale time on remeshed shapes (bench_match_time.py)", "",
             f"Machine: {machine()}. Command: `{command_line()}`. Pair: {Path(null).name} → {Path(tgt).name} "
             f"(remeshed, 6 landmarks: FPS on the null shape and their ground-truth images). Each row is a fresh "
             "interpreter; one core = one BLAS and one numba thread.", "",
             "| what | target | wall s | CPU s | load before |", "|---|---|---|---|---|"]
    lines += [f"| {name} | {goal} | {r['wall']:.1f} | {r['cpu']:.1f} | {r['load']:.1f} |" for name, goal, r in rows]
    text = "\n".join(lines)
    write_section("match-time", text)
    print(text)


if __name__ == "__main__":
    main()
