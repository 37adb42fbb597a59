"""What the release benchmarks share: the groups of pairs to match, an evaluate run's landmark sets,
and the true map as a dense start."""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def groups(dataset, pairs_file=None) -> dict:
    """The release's classes (``evaluation.datasets.find_classes``), or one group per source of the
    pairs listed in ``pairs_file`` (``pair_groups``)."""
    from shapecond.evaluation.datasets import find_classes, pair_groups
    from shapecond.shapes.pairs_list import read_pairs

    return pair_groups(dataset, read_pairs(pairs_file)) if pairs_file else find_classes(dataset)


def landmark_sets(path) -> dict:
    """(class, method) -> the landmark vertex ids of an ``evaluate`` run's results.json."""
    return {(d["cls"], d["method"]): d["vertices"] for d in json.loads(Path(path).read_text())["landmarks"]}


def truth_start(null, ref_s, ref_t):
    """The true map as a vertex map: every vertex of ``null`` sent where the ground truth sends its
    nearest reference point (``ref_s`` on ``null`` ↔ ``ref_t`` on the target)."""
    from scipy.spatial import cKDTree

    _, nearest = cKDTree(null.vertices[ref_s]).query(null.vertices)
    return ref_t[nearest]


def run_or_report(doc: str, run, report, run_arguments) -> None:
    """The command line of a release benchmark with a ``run`` step (``DATASET``, ``--out`` and the
    arguments ``run_arguments(parser)`` adds) and a ``report`` step (``--run LABEL=FILE`` repeated,
    ``--note``), dispatched to ``run(args)`` or ``report(args)``."""
    p = argparse.ArgumentParser(description=doc.splitlines()[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("dataset", type=Path)
    run_arguments(r)
    r.add_argument("--out", required=True)
    q = sub.add_parser("report")
    q.add_argument("--run", action="append", required=True, help="LABEL=FILE of a run")
    q.add_argument("--note", default="")
    a = p.parse_args()
    run(a) if a.cmd == "run" else report(a)
