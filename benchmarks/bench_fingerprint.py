"""Same numbers before and after a change: σ, δ, flags, landmarks and maps on the TOSCA null shapes.

Usage:
    python benchmarks/bench_fingerprint.py ../shared/data/tosca_hires [--base REV] [--points 400]
        [--classes cat,dog] [--no-match]

For every class's null shape (and its second shape, for the matchers) the
working tree and the package at git revision ``--base`` (default ``HEAD``) each
compute, in a fresh interpreter with its own empty cache:

* ``sc.score``: the σ bracket, the resolution flag, δ(ε) and its ε, and a hash
  of the witness map;
* ``sc.landmarks`` with 3 landmarks by ``fps`` and ``cnbs``;
* ``sc.match`` null → second shape with the 3 FPS landmarks, each matcher
  (``lh05``, ``faq``, ``zoomout``): a hash of the dense map.

The script prints every value that differs and a line per side with its CPU
time; a refactoring that claims "the same numbers" must print no difference.
Exit status 1 when something differs.  Nothing is written to ``RESULTS.md``:
the comparison is the result.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from _results import baseline_src, run_variant  # noqa: E402

NULLS = {"cat": "cat0", "centaur": "centaur0", "david": "david0", "dog": "dog0", "horse": "horse0",
         "michael": "michael0", "victoria": "victoria0", "wolf": "wolf0"}

CODE = r'''
import hashlib, json, sys
import numpy as np
import shapecond as sc

def h(a):
    return hashlib.sha256(np.ascontiguousarray(np.asarray(a, dtype=np.int64)).tobytes()).hexdigest()[:16]

out = {}
for cls, null, second, n, match in json.loads(sys.argv[1]):
    r = sc.score(null, n_points=n).to_dict()
    f = {"sigma": r.get("sigma"), "flag": (r.get("resolution") or {}).get("flag"),
         "delta": (r.get("scale") or {}).get("delta"), "epsilon": (r.get("scale") or {}).get("epsilon"),
         "witness": h(r.get("witness_vertices") or []), "delta_witness": h((r.get("scale") or {}).get("witness") or [])}
    for method in ("fps", "cnbs"):
        f["landmarks_" + method] = [int(v) for v in sc.landmarks(null, 3, method, n_points=n).landmarks]
    if match:
        lm = f["landmarks_fps"]
        for matcher in ("lh05", "faq", "zoomout"):
            f["map_" + matcher] = h(sc.match(null, second, lm, lm, matcher=matcher, n_points=n).map)
    out[cls] = f
print(json.dumps(out))
'''


def jobs(root: Path, classes, n: int, match: bool) -> list:
    out = []
    for cls in classes:
        folder = root / cls
        shapes = sorted(folder.glob("*.off"), key=lambda p: (len(p.stem), p.stem))
        null = folder / f"{NULLS[cls]}.off"
        second = next(p for p in shapes if p != null)
        out.append([cls, str(null), str(second), n, match])
    return out


def side(src, args_json: str) -> tuple[dict, float]:
    with tempfile.TemporaryDirectory() as cache:
        r = run_variant(CODE.replace("json.loads(sys.argv[1])", f"json.loads({args_json!r})"), src=src,
                        cache=Path(cache))
    return json.loads(r["stdout"].strip().splitlines()[-1]), r["cpu"]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("data", type=Path, help="folder of TOSCA class folders")
    ap.add_argument("--base", default="HEAD")
    ap.add_argument("--points", type=int, default=400)
    ap.add_argument("--classes", default=",".join(NULLS))
    ap.add_argument("--no-match", action="store_true")
    a = ap.parse_args(argv)
    spec = json.dumps(jobs(a.data, a.classes.split(","), a.points, not a.no_match))
    sha, src = baseline_src(a.base)
    before, cpu_b = side(src, spec)
    after, cpu_a = side(None, spec)
    diffs = [(cls, k, before[cls].get(k), after[cls].get(k)) for cls in before
             for k in sorted(set(before[cls]) | set(after[cls])) if before[cls].get(k) != after[cls].get(k)]
    for cls, k, b, v in diffs:
        print(f"DIFF {cls} {k}: {b} -> {v}")
    print(f"base {sha[:10]}: {cpu_b:.1f} s CPU; working tree: {cpu_a:.1f} s CPU; "
          f"{len(diffs)} differences over {sum(len(f) for f in before.values())} values")
    return 1 if diffs else 0


if __name__ == "__main__":
    sys.exit(main())
