"""What the tests share: running the command line, time limits, instance generators, batch tables
and class folders.  Plain functions, imported with ``from tests.helpers import ...``; fixtures
stay in the ``conftest.py`` files.

Only NumPy is imported here: the lowest-versions environment of ``.ci/run`` (no pyarrow, no Dask)
imports this module too, so every heavier import sits inside the function that needs it.

Command line
    ``run_cli(capsys, *argv)`` in-process, ``run_shapecond(*argv)`` in a child process,
    ``deadline(seconds)`` turns a hang into a failure.
Distance matrices (symmetric, zero diagonal, max 1; deterministic given a ``numpy.random.Generator``)
    ``random_instance(rng, n, dim)``: ``n`` uniform points of the unit ``dim``-cube;
    ``near_symmetric_instance(rng, n, dim, noise)``: mirror pairs (x, R x), R the reflection of
    coordinate 0, one point on the mirror plane when ``n`` is odd, plus Gaussian noise
    (``noise = 0``: an exact isometry, σ = ∞);
    ``dense_instance(rng, n, m, dim, noise=None)``: ``m`` targets whose first ``n`` are the
    samples (near-symmetric when ``noise`` is given);
    ``mixed_instances(seed, count, n)``: a cycle over the kinds above;
    ``mirror_pairs_instance(n, seed, noise)``: mirror pairs and points on the plane, perturbed;
    ``brute_sigma(D, n, landmarks)``: exact σ by enumeration; ``brute_delta(D, eps, landmarks)``:
    exact δ(ε) by enumeration; ``same(a, b)``: equal to 1e-9.
Batch tables
    ``read_table(path)`` (Parquet, CSV or JSON Lines), ``stable(rows)`` (without the
    ``VOLATILE`` columns, sorted by file), ``table_row(i, **columns)`` (a complete row).
Class folders
    ``write_off(path, V, F)``, ``bent(V, radius)``, ``write_strip_class(root)``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

# --- command line -------------------------------------------------------------------------


def run_cli(capsys, *argv):
    """Run ``shapecond ARGV`` in-process; return (exit status, stdout, stderr)."""
    import pytest

    from shapecond.cli import main

    with pytest.raises(SystemExit) as exit_info:
        main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return exit_info.value.code, out, err


def deadline(seconds: float):
    """Context manager: raise ``TimeoutError`` in the main thread if the block runs longer than
    ``seconds`` (a hang becomes a failure; a blocking ``open`` or ``read`` is interrupted too)."""
    import contextlib
    import signal

    @contextlib.contextmanager
    def guard():
        def expire(signum, frame):
            raise TimeoutError(f"still running after {seconds} s")

        previous = signal.signal(signal.SIGALRM, expire)
        signal.setitimer(signal.ITIMER_REAL, seconds)
        try:
            yield
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, previous)

    return guard()


def run_shapecond(*argv, timeout: float = 10, env=None, **kw):
    """Run ``python -m shapecond ARGV`` in a child process that is killed after ``timeout`` seconds
    (``subprocess.TimeoutExpired``: a hang fails the test instead of stalling it, even when a thread
    is stuck); return (exit status, stdout, stderr)."""
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-m", "shapecond", *map(str, argv)], capture_output=True, text=True,
                          timeout=timeout, stdin=subprocess.DEVNULL, env=env, **kw)
    return proc.returncode, proc.stdout, proc.stderr


# --- distance matrices --------------------------------------------------------------------


def distance_matrix(P: np.ndarray) -> np.ndarray:
    """Euclidean distances of the rows of ``P``, symmetric with a zero diagonal, scaled to max 1."""
    D = np.sqrt(np.sum((P[:, None, :] - P[None, :, :]) ** 2, axis=-1))
    D = 0.5 * (D + D.T)
    np.fill_diagonal(D, 0.0)
    return D / D.max()


def random_points(rng: np.random.Generator, n: int, dim: int) -> np.ndarray:
    """``n`` uniform points in the unit ``dim``-cube, shape (n, dim)."""
    return rng.random((n, dim))


def near_symmetric_points(rng: np.random.Generator, n: int, dim: int, noise: float) -> np.ndarray:
    """Mirror pairs (x, R x) with R = reflection of coordinate 0, plus noise; shape (n, dim)."""
    half = rng.standard_normal((n // 2, dim))
    half[:, 0] = np.abs(half[:, 0]) + 0.2
    mirror = half.copy()
    mirror[:, 0] *= -1.0
    parts = [half, mirror]
    if n % 2:
        mid = rng.standard_normal((1, dim))
        mid[:, 0] = 0.0
        parts.append(mid)
    P = np.concatenate(parts)[rng.permutation(n)]
    return P + noise * rng.standard_normal(P.shape)


def random_instance(rng: np.random.Generator, n: int, dim: int) -> np.ndarray:
    """(n, n) Euclidean distance matrix of random points, max 1."""
    return distance_matrix(random_points(rng, n, dim))


def near_symmetric_instance(rng: np.random.Generator, n: int, dim: int, noise: float) -> np.ndarray:
    """(n, n) distance matrix of a mirror-symmetric set plus ``noise``, max 1."""
    return distance_matrix(near_symmetric_points(rng, n, dim, noise))


def dense_instance(rng: np.random.Generator, n: int, m: int, dim: int, noise: float | None = None) -> np.ndarray:
    """(m, m) distance matrix whose first ``n`` points are the samples, max 1."""
    if noise is None:
        P = random_points(rng, m, dim)
    else:
        P = near_symmetric_points(rng, m, dim, noise)
    return distance_matrix(P)


def mixed_instances(seed: int, count: int, n: int):
    """``count`` instances cycling over random/near-symmetric, 2D/3D, noise levels."""
    rng = np.random.default_rng(seed)
    noises = (0.01, 0.05, 0.2)
    out = []
    for k in range(count):
        dim = 2 + (k % 2)
        if (k // 2) % 2 == 0:
            out.append(random_instance(rng, n, dim))
        else:
            out.append(near_symmetric_instance(rng, n, dim, noises[(k // 4) % 3]))
    return out


def mirror_pairs_instance(n: int, seed: int, noise: float = 0.03, dim: int = 3) -> np.ndarray:
    """(n, n) distances (max 1) of points in mirror pairs (x_0 -> -x_0) plus a few on the mirror
    plane, all perturbed by Gaussian noise of standard deviation ``noise``; seeded by ``seed``."""
    rng = np.random.default_rng(seed)
    half = rng.normal(size=((n - 2) // 2, dim))
    half[:, 0] = np.abs(half[:, 0]) + 0.2
    mirror = half * np.r_[-1.0, np.ones(dim - 1)]
    plane = rng.normal(size=(n - 2 * half.shape[0], dim))
    plane[:, 0] = 0.0
    P = np.vstack([half, mirror, plane]) + noise * rng.normal(size=(n, dim))
    D = np.linalg.norm(P[:, None] - P[None], axis=2)
    return D / D.max()


def brute_delta(D, eps, landmarks=()):
    """Exact δ(ε) by enumeration: the largest RMS displacement over the bijections fixing the
    landmarks whose RMS distortion is at most ε and every landmark row's too (``symmetry.scale``).
    The bijections are scored in blocks of arrays, each term as ``objective.dist2``, ``anchor_rows``
    and ``d2`` compute it."""
    import itertools
    import math

    from shapecond.symmetry.scale import budget_of

    n = D.shape[0]
    lm = list(landmarks)
    free = [x for x in range(n) if x not in lm]
    budget = budget_of(eps, n, D)  # (εN)², at least the isometry round-off level
    perms = itertools.permutations(free)
    best = 0.0
    while block := list(itertools.islice(perms, 20_000)):
        T = np.tile(np.arange(n), (len(block), 1))
        T[:, free] = block
        dist2 = np.sum((D[None, :n, :n] - D[T[:, :, None], T[:, None, :]]) ** 2, axis=(1, 2))
        ok = dist2 <= budget
        if lm:
            rows = np.sum((D[lm][None, :, :n] - D[np.asarray(lm)[None, :, None], T[:, None, :]]) ** 2, axis=2)
            ok &= rows.max(axis=1) <= budget / n
        if ok.any():
            d2 = np.sum(D[np.arange(n), T[ok]] ** 2, axis=1)
            best = max(best, math.sqrt(float(d2.max()) / n))
    return best


def brute_sigma(D, n=None, landmarks=()):
    """Exact σ and its map by enumerating every injective map of the ``n`` samples into range(M)
    that fixes the landmarks (the oracle of the small-N tests; M! / (M - n)! maps)."""
    import itertools
    import math

    from shapecond.symmetry import objective as obj

    m = D.shape[0]
    n = m if n is None else n
    lm = set(landmarks)
    free = [x for x in range(n) if x not in lm]
    targets = [y for y in range(m) if y not in lm]
    perms = np.array(list(itertools.permutations(targets, len(free))), dtype=np.int64)
    T = np.tile(np.arange(n), (len(perms), 1))
    T[:, free] = perms
    d2 = np.sum(D[np.arange(n), T] ** 2, axis=1)
    dist2 = np.sum((D[:n, :n][None] - D[T[:, :, None], T[:, None, :]]) ** 2, axis=(1, 2))
    iso = (dist2 <= obj.ISOMETRY_RTOL**2 * np.sum(D[:n, :n] ** 2)) & (d2 > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(d2 > 0, d2 / np.where(dist2 > 0, dist2, 1.0), 0.0)
    r[iso] = np.inf
    k = int(np.argmax(r))
    return math.sqrt(r[k]), T[k]


def same(a, b) -> bool:
    """``a`` equals ``b`` up to 1e-9 relative (infinities equal)."""
    return a == b or abs(a - b) <= 1e-9 * max(1.0, abs(b))


# --- batch tables -------------------------------------------------------------------------

#: columns that depend on where and when a row was computed, not on the shape
VOLATILE = ("seconds", "cpu_seconds", "peak_memory_mib", "worker")


def stable(rows):
    """Rows without the volatile columns, sorted by file (for comparing runs)."""
    return sorted(({k: v for k, v in r.items() if k not in VOLATILE} for r in rows), key=lambda r: r["file"])


def read_table(path):
    """The rows of a batch table (Parquet, CSV or JSON Lines, by extension), typed as the batch writes them."""
    from shapecond.batch import schema

    path = Path(path)
    if path.suffix == ".parquet":
        import pyarrow.parquet as pq

        return [schema.coerce_row(r) for r in pq.read_table(path).to_pylist()]
    if path.suffix == ".csv":
        import csv

        return [schema.coerce_row(r) for r in csv.DictReader(path.read_text().splitlines())]
    return [schema.coerce_row(json.loads(line)) for line in path.read_text().splitlines()]


def table_row(i: int, **columns) -> dict:
    """A complete row of shape ``/s/I.off`` with an infinite score, lists and a missing value."""
    import math

    from shapecond.batch import schema

    row = schema.empty_row()
    row.update(file=f"/s/{i}.off", content_hash=f"h{i}", params="{}", sigma_lower=math.inf, sigma_hat=1.5 * i,
               landmarks=[i, 7], landmark_scores=[math.inf, 0.25], vertices=10 + i, problems="a; b", **columns)
    return row


# --- class folders ------------------------------------------------------------------------


def write_off(path, V, F) -> None:
    """An OFF file of vertices ``V`` (n, 3) and triangles ``F`` (f, 3)."""
    Path(path).write_text(f"OFF\n{len(V)} {len(F)} 0\n" + "\n".join(" ".join(map(str, v)) for v in V) + "\n"
                          + "\n".join(f"3 {a} {b} {c}" for a, b, c in F) + "\n")


def bent(V: np.ndarray, radius: float) -> np.ndarray:
    """A flat patch in the plane z = 0 rolled onto a cylinder of ``radius`` along x (an isometry)."""
    th = V[:, 0] / radius
    return np.column_stack([radius * np.sin(th), V[:, 1], radius * (1 - np.cos(th))])


def write_strip_class(root) -> Path:
    """Class folder ``root/strip``: a flat 1 x 0.55 grid (strip0) and two bent copies (strip7,
    strip12, the second also moved), one vertex order; returns ``root``."""
    from shapecond.shapes.synthetic import plane_patch

    root = Path(root)
    (root / "strip").mkdir(parents=True)
    g = plane_patch(n=19)
    V = g.vertices * [1.0, 0.55, 0.0]
    write_off(root / "strip" / "strip0.off", V, g.faces)
    write_off(root / "strip" / "strip7.off", bent(V, 0.5), g.faces)
    write_off(root / "strip" / "strip12.off", bent(V, 0.3) + [1.0, 2.0, 3.0], g.faces)
    return root


def bent_strip(n: int, bend=None, seed=None):
    """(V, F, uv): a 1 × 0.55 rectangle meshed n × n, bent onto a cylinder of radius ``bend`` (an isometry)
    and its vertices renumbered by ``seed`` on request; ``uv`` the rectangle coordinates of each vertex."""
    from shapecond.shapes.synthetic import plane_patch

    g = plane_patch(n=n)
    uv = g.vertices[:, :2] * [1.0, 0.55]
    V = np.column_stack([uv, np.zeros(len(uv))])
    if bend is not None:
        th = uv[:, 0] / bend
        V = np.column_stack([bend * np.sin(th), uv[:, 1], bend * (1 - np.cos(th))])
    F = g.faces
    if seed is not None:
        perm = np.random.default_rng(seed).permutation(len(V))
        V, uv, F = V[perm], uv[perm], np.argsort(perm)[F]
    return V, F, uv


def descendants(pid: int) -> set[int]:
    """The processes below ``pid`` (Linux /proc)."""
    import os

    parents = {}
    for name in os.listdir("/proc"):
        if name.isdigit():
            try:
                with open(f"/proc/{name}/stat", "rb") as fh:
                    parents[int(name)] = int(fh.read().rsplit(b")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
    found, todo = set(), [pid]
    while todo:
        parent = todo.pop()
        kids = [p for p, q in parents.items() if q == parent]
        found.update(kids)
        todo += kids
    return found


def open_offline(ctx, path: Path, ready: str = "window.shapecond && (window.shapecond.error || window.shapecond.ready)"):
    """Open the page ``path`` in the browser context ``ctx`` with every network request refused, and wait
    until the JavaScript condition ``ready`` holds; returns (page, console errors, network requests)."""
    import re

    page = ctx.new_page()
    errors, requests = [], []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("request", lambda r: requests.append(r.url))
    page.route(re.compile(r"^(https?|wss?|ftp)://"), lambda route: route.abort())
    page.goto(Path(path).resolve().as_uri())
    page.wait_for_function(ready, timeout=20_000)
    return page, errors, requests
