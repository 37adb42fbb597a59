"""Remeshed TOSCA: every shape remeshed on its own, with ``.vts`` ground truth (the FAUST_r layout).

Usage:
    python benchmarks/make_remeshed.py ../shared/data/tosca_hires [--out DIR] [--classes cat,dog]

The field's benchmarks of non-rigid matching (remeshed FAUST and SCAPE, SHREC'19,
SMAL_r, DT4D-H) give every shape its own triangulation, so that no matcher can
profit from a shared vertex order.  This script makes that setting from TOSCA,
whose shapes of a class share one triangulation:

* each shape is remeshed **on its own** by isotropic remeshing (Botsch and
  Kobbelt 2004, ``gpytoolbox.remesh_botsch``, 10 iterations, projected onto the
  original surface, after making the triangles' winding consistent) to a target edge length giving about 5,000–8,000 vertices;
  the target count of a shape is drawn from the CRC-32 of its name, so shapes of
  one class get different vertex counts and connectivity, and the result is the
  same on every run (the remesher is deterministic; checked below);
* ``corres/NAME.vts`` holds, for every reference point j (the vertices of the
  original class triangulation that every shape of the class references), the
  1-based id of the remeshed vertex nearest to the original vertex j (Euclidean,
  the remeshed surface lies on the original one) among those whose normal agrees
  with the original vertex's (``on_the_same_sheet``: where a hand touches a thigh,
  the plain nearest vertex was on the thigh for 5-12 % of a human's reference
  points, and those points erred a geodesic diameter whatever the map).  Shapes a
  and b of a class then correspond at (vts_a[j], vts_b[j]), as in the remeshed
  releases;
* ``shapes/NAME.off`` is the remeshed mesh; only its largest connected
  component is kept (remeshing can leave slivers where the original has holes);
* ``corres/reference.sym``, when the source has ``symmetries/CLASS.sym`` (TOSCA's
  left–right maps of the original vertices): line j holds the 1-based reference
  point mirroring reference point j, so that the evaluation can count flips.

Output: ``DIR/CLASS/shapes/*.off`` and ``DIR/CLASS/corres/*.vts``; default DIR is
the ``datasets/tosca_remeshed`` folder of the shapecond cache (never committed).
Shapes already written are kept (delete the folder to remake them).
"""

from __future__ import annotations

import argparse
import sys
import time
import zlib
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

#: Target vertex counts: each shape draws one in [LOW, HIGH) from the CRC-32 of its name.
LOW, HIGH = 5000, 8000
ITERATIONS = 10


def read_off(path: Path):
    """(V, F) of an ASCII OFF file (the TOSCA files); comments and blank lines skipped."""
    tokens = [ln.split() for ln in path.read_text().splitlines() if ln.strip() and not ln.startswith("#")]
    assert tokens[0][0] == "OFF", path
    nv, nf = int(tokens[1][0]), int(tokens[1][1])
    V = np.array(tokens[2:2 + nv], dtype=np.float64)
    F = np.array([t[1:4] for t in tokens[2 + nv:2 + nv + nf]], dtype=np.int64)
    return V, F


def write_off(path: Path, V, F) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    lines = ["OFF", f"{len(V)} {len(F)} 0"]
    lines += [f"{x:.6f} {y:.6f} {z:.6f}" for x, y, z in V]
    lines += [f"3 {a} {b} {c}" for a, b, c in F]
    tmp = path.with_suffix(".tmp")
    tmp.write_text("\n".join(lines) + "\n")
    tmp.replace(path)


def largest_component(V, F):
    """Vertices and faces of the largest connected component (by vertex count), reindexed."""
    n = len(V)
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    A = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    _, lab = sp.csgraph.connected_components(A, directed=False)
    used = np.zeros(n, dtype=bool)
    used[F.ravel()] = True
    counts = np.bincount(lab[used], minlength=lab.max() + 1)
    keep = (lab == np.argmax(counts)) & used
    new = -np.ones(n, dtype=np.int64)
    new[keep] = np.arange(keep.sum())
    Fk = F[keep[F[:, 0]]]
    return V[keep], new[Fk]


def target_count(name: str) -> int:
    return LOW + zlib.crc32(name.encode()) % (HIGH - LOW)


def remesh(V, F, name: str):
    import gpytoolbox as gp
    import trimesh

    # consistent winding first: on TOSCA centaur3/4 (some flipped triangles) the remesher
    # otherwise grows without bound until the process is killed for memory
    mesh = trimesh.Trimesh(V, F, process=False)
    trimesh.repair.fix_winding(mesh)
    F = np.asarray(mesh.faces, dtype=np.int64)
    used = np.unique(F)
    area = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1).sum()
    n = target_count(name)
    h = np.sqrt(area / (2 * n) * 4 / np.sqrt(3))  # n vertices: about 2n equilateral triangles
    remap = -np.ones(len(V), dtype=np.int64)
    remap[used] = np.arange(used.size)
    U, G = gp.remesh_botsch(V[used], remap[F].astype(np.int32), ITERATIONS, h, True)
    return largest_component(np.asarray(U, dtype=np.float64), np.asarray(G, dtype=np.int64))


def vertex_normals(V, F) -> np.ndarray:
    """Area-weighted unit vertex normals (trimesh), with the winding made consistent first."""
    import trimesh

    mesh = trimesh.Trimesh(V, F, process=False)
    trimesh.repair.fix_winding(mesh)
    return np.asarray(mesh.vertex_normals)


def on_the_same_sheet(V, F, U, G, ref, k: int = 16) -> np.ndarray:
    """The remeshed vertex of every reference point: the nearest one whose normal agrees with the
    original vertex's normal.

    Where two parts of a pose touch (a hand on a thigh), the Euclidean-nearest remeshed vertex can lie
    on the other part, a geodesic diameter away; the two sheets face each other, so their normals are
    opposite.  Of the ``k`` nearest remeshed vertices the nearest one with a positive dot product is
    taken (the nearest one when none has, which does not happen on the TOSCA shapes).  The remeshed
    surface's orientation is first matched to the original's (the majority of the nearest pairs).
    """
    n_orig, n_new = vertex_normals(V, F), vertex_normals(U, G)
    dist, cand = cKDTree(U).query(V[ref], k=k)
    if np.mean(np.sum(n_orig[ref] * n_new[cand[:, 0]], axis=1) > 0) < 0.5:
        n_new = -n_new  # the remesher wound the whole surface the other way
    agree = np.einsum("ij,ikj->ik", n_orig[ref], n_new[cand]) > 0
    first = np.where(agree.any(axis=1), np.argmax(agree, axis=1), 0)
    return cand[np.arange(len(ref)), first]


def class_shapes(folder: Path) -> list[Path]:
    import re

    def key(p):
        m = re.search(r"(\d+)$", p.stem)
        return (int(m.group(1)) if m else 10**9, p.stem)

    return sorted(folder.glob("*.off"), key=key)


def write_reference_symmetry(sym_file: Path, ref: np.ndarray, out: Path) -> None:
    """``corres/reference.sym`` from a map of original vertex ids (1-based, one line per vertex)."""
    sym = np.loadtxt(sym_file, dtype=np.int64) - 1
    pos = -np.ones(max(int(sym.max()), int(ref.max())) + 1, dtype=np.int64)
    pos[ref] = np.arange(ref.size)
    mirror = pos[sym[ref]]
    if np.any(mirror < 0):
        sys.exit(f"{sym_file}: the mirror of a reference point is not a reference point")
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("\n".join(str(int(i) + 1) for i in mirror) + "\n")


def make_class(folder: Path, out: Path) -> list[str]:
    paths = class_shapes(folder)
    meshes = {p.stem: read_off(p) for p in paths}
    referenced = None
    for V, F in meshes.values():
        used = np.zeros(len(V), dtype=bool)
        used[F.ravel()] = True
        referenced = used if referenced is None else referenced & used
    ref = np.flatnonzero(referenced)  # reference points: original vertices every shape references
    sym_file = folder.parent / "symmetries" / f"{folder.name}.sym"
    if sym_file.is_file():
        write_reference_symmetry(sym_file, ref, out / "corres" / "reference.sym")
    lines = []
    for name, (V, F) in meshes.items():
        off, vts = out / "shapes" / f"{name}.off", out / "corres" / f"{name}.vts"
        if off.exists() and vts.exists():
            continue
        t0 = time.perf_counter()
        U, G = remesh(V, F, name)
        U2, G2 = remesh(V, F, name) if name == next(iter(meshes)) else (U, G)
        if not (np.array_equal(U, U2) and np.array_equal(G, G2)):
            sys.exit(f"{name}: the remesher gave two different meshes for the same input")
        nearest = on_the_same_sheet(V, F, U, G, ref)
        write_off(off, U, G)
        vts.parent.mkdir(parents=True, exist_ok=True)
        vts.write_text("\n".join(str(int(i) + 1) for i in nearest) + "\n")
        lines.append(f"{folder.name}/{name}: {len(V)} -> {len(U)} vertices, {len(ref)} reference points, "
                     f"{time.perf_counter() - t0:.1f} s")
        print(lines[-1], file=sys.stderr)
    return lines


def default_out() -> Path:
    from shapecond.cache import cache_dir

    return cache_dir() / "datasets" / "tosca_remeshed"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("source", type=Path, help="folder of TOSCA class folders (e.g. ../shared/data/tosca_hires)")
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--classes", default=None, help="comma-separated class names (default: every class)")
    a = ap.parse_args(argv)
    out = a.out or default_out()
    wanted = a.classes.split(",") if a.classes else None
    for folder in sorted(p for p in a.source.iterdir() if p.is_dir()):
        if (wanted and folder.name not in wanted) or not any(folder.glob("*.off")):
            continue
        make_class(folder, out / folder.name)
    print(out)


if __name__ == "__main__":
    main()
