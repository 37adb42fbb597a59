"""Generated shapes for tests, examples and the demo (no data files needed).

* ``sphere``, ``bumpy_blob``: icospheres; the blob is a radial function of the
  direction, so every subdivision level samples *the same* surface
  (4 -> 2,562, 5 -> 10,242, 6 -> 40,962 vertices).
* ``torus``, ``capped_cylinder``, ``plane_patch``: parametric grids.
* ``animal``: a bilaterally symmetric four-legged animal (ellipsoid body, head,
  neck, legs and tail as capsules, smoothly unioned), meshed by marching cubes on
  the half space x >= 0 and mirrored, so the mesh is *exactly* symmetric under
  x -> -x with a known vertex correspondence (``Geometry.symmetry``).  The
  asymmetry ``delta`` deforms the right half smoothly (longer legs, longer body)
  while keeping the vertex correspondence, so ``delta = 0`` is exactly
  symmetric, samples included (sampling follows the symmetry map).
"""

from __future__ import annotations

import numpy as np
import trimesh

from ..checks import check_float, check_int, check_seed
from ..errors import InputError, TooLargeError
from .geometry import Geometry
from .validate import make_geometry


def sphere(subdivisions: int = 4, radius: float = 1.0) -> Geometry:
    """Icosphere; mirror-symmetric under every coordinate reflection."""
    m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    return make_geometry(m.vertices, m.faces, name="sphere")


def bumpy_blob(subdivisions: int = 4, seed: int = 0, amplitude: float = 0.3, n_bumps: int = 7) -> Geometry:
    """An asymmetric blob r(u) = 1 + amplitude * Σ_k c_k exp(κ (u·d_k − 1)).

    The bump directions ``d_k`` and weights ``c_k`` come from ``seed`` only, so the
    surface is the same at every subdivision level.
    """
    rng = np.random.default_rng(seed)
    dirs = rng.normal(size=(n_bumps, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    weights = rng.uniform(0.4, 1.0, size=n_bumps)
    kappa = rng.uniform(2.0, 6.0, size=n_bumps)
    m = trimesh.creation.icosphere(subdivisions=subdivisions)
    u = m.vertices / np.linalg.norm(m.vertices, axis=1, keepdims=True)
    r = 1.0 + amplitude * np.sum(weights * np.exp(kappa * (u @ dirs.T - 1.0)), axis=1)
    return make_geometry(u * r[:, None], m.faces, name="blob")


def _grid_faces(n_rows: int, n_cols: int, wrap_cols: bool, wrap_rows: bool = False) -> np.ndarray:
    """Two triangles per quad of a (n_rows x n_cols) vertex grid, row-major."""
    faces = []
    rows = n_rows if wrap_rows else n_rows - 1
    cols = n_cols if wrap_cols else n_cols - 1
    for i in range(rows):
        for j in range(cols):
            a = i * n_cols + j
            b = i * n_cols + (j + 1) % n_cols
            c = ((i + 1) % n_rows) * n_cols + (j + 1) % n_cols
            d = ((i + 1) % n_rows) * n_cols + j
            faces.append((a, b, c))
            faces.append((a, c, d))
    return np.asarray(faces, dtype=np.int64)


def torus(major: float = 1.0, minor: float = 0.35, n_major: int = 64, n_minor: int = 24) -> Geometry:
    """A torus of revolution around the z axis."""
    u = 2 * np.pi * np.arange(n_major) / n_major
    v = 2 * np.pi * np.arange(n_minor) / n_minor
    uu, vv = np.meshgrid(u, v, indexing="ij")
    x = (major + minor * np.cos(vv)) * np.cos(uu)
    y = (major + minor * np.cos(vv)) * np.sin(uu)
    z = minor * np.sin(vv)
    verts = np.stack([x, y, z], axis=-1).reshape(-1, 3)
    faces = _grid_faces(n_major, n_minor, True, True)[:, ::-1]  # outward normals
    return make_geometry(verts, faces, name="torus")


def capped_cylinder(radius: float = 0.5, height: float = 2.0, sections: int = 48,
                    n_height: int = 24, n_cap_rings: int = 8) -> Geometry:
    """A cylinder around the z axis closed by flat discs triangulated in rings."""
    theta = 2 * np.pi * np.arange(sections) / sections
    ring = np.stack([np.cos(theta), np.sin(theta)], axis=1)
    verts = []
    # bottom cap centre, bottom cap rings (inner to outer), side rings, top cap rings, top centre
    zs = np.linspace(-height / 2, height / 2, n_height + 1)
    radii = radius * np.arange(1, n_cap_rings) / n_cap_rings
    layers = [(r, zs[0]) for r in radii] + [(radius, z) for z in zs] + [(r, zs[-1]) for r in radii[::-1]]
    for r, z in layers:
        verts.append(np.column_stack([r * ring, np.full(sections, z)]))
    verts = np.vstack([[[0.0, 0.0, zs[0]]], np.vstack(verts), [[0.0, 0.0, zs[-1]]]])
    n_layers = len(layers)
    body = _grid_faces(n_layers, sections, True) + 1
    bottom = [(0, 1 + (j + 1) % sections, 1 + j) for j in range(sections)]
    top_c = verts.shape[0] - 1
    last = 1 + (n_layers - 1) * sections
    top = [(top_c, last + j, last + (j + 1) % sections) for j in range(sections)]
    faces = np.vstack([np.asarray(bottom), body, np.asarray(top)])
    return make_geometry(verts, faces, name="cylinder")


def plane_patch(n: int = 41, size: float = 1.0) -> Geometry:
    """A flat square grid of ``n x n`` vertices in the plane z = 0."""
    s = np.linspace(0.0, size, n)
    xx, yy = np.meshgrid(s, s, indexing="ij")
    verts = np.column_stack([xx.ravel(), yy.ravel(), np.zeros(n * n)])
    return make_geometry(verts, _grid_faces(n, n, False), name="plane")


# --- the animal -------------------------------------------------------------------

def _capsule(p, a, b, r):
    a, b = np.asarray(a, float), np.asarray(b, float)
    ab = b - a
    h = np.clip(((p - a) @ ab) / (ab @ ab), 0.0, 1.0)
    return np.linalg.norm(p - a - h[:, None] * ab, axis=1) - r


def _ellipsoid(p, c, radii):
    q = (p - np.asarray(c, float)) / np.asarray(radii, float)
    return (np.linalg.norm(q, axis=1) - 1.0) * min(radii)


def _smin(a, b, k=0.08):
    h = np.clip(0.5 + 0.5 * (b - a) / k, 0.0, 1.0)
    return b * (1 - h) + a * h - k * h * (1 - h)


def _animal_field(p: np.ndarray) -> np.ndarray:
    """Signed distance-like field, negative inside; symmetric in x by using |x|."""
    q = p.copy()
    q[:, 0] = np.abs(q[:, 0])
    f = _ellipsoid(q, (0.0, 0.0, 0.0), (0.32, 0.28, 0.7))
    f = _smin(f, _capsule(q, (0.0, 0.15, 0.55), (0.0, 0.38, 0.82), 0.13))          # neck
    f = _smin(f, _ellipsoid(q, (0.0, 0.42, 0.95), (0.17, 0.16, 0.24)))             # head
    f = _smin(f, _capsule(q, (0.09, 0.55, 0.88), (0.1, 0.68, 0.84), 0.045), 0.04)  # ear
    for z in (0.42, -0.42):                                                         # legs
        f = _smin(f, _capsule(q, (0.17, -0.1, z), (0.2, -0.85, z + 0.04), 0.085))
    f = _smin(f, _capsule(q, (0.0, 0.05, -0.65), (0.0, 0.42, -1.12), 0.05), 0.05)  # tail
    return f


def animal(delta: float = 0.0, resolution: float = 0.03) -> Geometry:
    """A bilaterally symmetric four-legged animal, body along z, up along y.

    Parameters
    ----------
    delta : float
        Asymmetry: the right half (x > 0) is stretched by up to ``delta`` (legs and
        body longer), smoothly to zero at the mirror plane.  0 = exactly symmetric.
    resolution : float
        Marching-cubes grid spacing (0.03 -> about 6k vertices, 0.02 -> about 13k).

    Returns
    -------
    Geometry with ``symmetry`` set to the mirror vertex correspondence.
    """
    from skimage.measure import marching_cubes

    h = float(resolution)
    lo = np.array([0.0, -1.0, -1.3])
    hi = np.array([0.5, 0.85, 1.3])
    counts = np.ceil((hi - lo) / h).astype(int) + 1
    axes = [lo[i] + h * np.arange(counts[i]) for i in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    field = _animal_field(grid).reshape(counts)
    field[np.abs(field) < 1e-9] = 1e-9  # keep the level set off the grid nodes
    verts, faces, _, _ = marching_cubes(field, level=0.0, spacing=(h, h, h), allow_degenerate=False)
    verts = verts + lo
    on_plane = np.abs(verts[:, 0]) < 1e-12
    verts[on_plane, 0] = 0.0
    n_half = verts.shape[0]
    off = np.flatnonzero(~on_plane)
    mirror_index = np.arange(n_half)
    mirror_index[off] = n_half + np.arange(off.size)
    mirrored = verts[off] * np.array([-1.0, 1.0, 1.0])
    all_verts = np.vstack([verts, mirrored])
    faces = faces.astype(np.int64)
    all_faces = np.vstack([faces, mirror_index[faces][:, ::-1]])
    symmetry = np.empty(all_verts.shape[0], dtype=np.int64)
    symmetry[:n_half] = mirror_index
    symmetry[n_half:] = off
    mesh = trimesh.Trimesh(all_verts, all_faces, process=False)
    if mesh.volume < 0:
        all_faces = all_faces[:, ::-1]
    all_verts = _asymmetric_stretch(all_verts, delta)
    return make_geometry(all_verts, all_faces, name="animal", symmetry=symmetry)


def _asymmetric_stretch(v: np.ndarray, delta: float) -> np.ndarray:
    if delta == 0:
        return v
    w = np.clip(v[:, 0] / 0.15, 0.0, 1.0)
    w = w * w * (3 - 2 * w)  # smoothstep: 0 on the mirror plane and the left half
    out = v.copy()
    below = v[:, 1] < 0
    out[below, 1] = v[below, 1] * (1 + delta * w[below])
    out[:, 2] = v[:, 2] * (1 + 0.5 * delta * w)
    return out


GENERATORS = {
    "animal": animal,
    "sphere": sphere,
    "torus": torus,
    "cylinder": capped_cylinder,
    "blob": bumpy_blob,
    "plane": plane_patch,
}

_POS = dict(lo=0.0, lo_open=True)
#: Allowed values of every generator parameter: (kind, range) with kind "int",
#: "float" or "seed".  Ranges keep the shape a valid, connected surface.
PARAMETERS = {
    "animal": {"delta": ("float", dict(lo=-0.5, hi=1.0)), "resolution": ("float", dict(lo=0.01, hi=0.08))},
    "sphere": {"subdivisions": ("int", dict(lo=0, hi=8)), "radius": ("float", _POS)},
    "torus": {"major": ("float", _POS), "minor": ("float", _POS),
              "n_major": ("int", dict(lo=3, hi=4096)), "n_minor": ("int", dict(lo=3, hi=4096))},
    "cylinder": {"radius": ("float", _POS), "height": ("float", _POS), "sections": ("int", dict(lo=3, hi=4096)),
                 "n_height": ("int", dict(lo=1, hi=4096)), "n_cap_rings": ("int", dict(lo=2, hi=1024))},
    "blob": {"subdivisions": ("int", dict(lo=0, hi=8)), "seed": ("seed", {}),
             "amplitude": ("float", dict(lo=0.0, hi=100.0)), "n_bumps": ("int", dict(lo=0, hi=1000))},
    "plane": {"n": ("int", dict(lo=2, hi=4096)), "size": ("float", _POS)},
}
#: Generated shapes above this many vertices are refused unless forced.
MAX_GENERATED_VERTICES = 700_000


def _vertex_estimate(name: str, p: dict) -> int:
    if name in ("sphere", "blob"):
        return 10 * 4 ** p.get("subdivisions", 4) + 2
    if name == "torus":
        return p.get("n_major", 64) * p.get("n_minor", 24)
    if name == "cylinder":
        return p.get("sections", 48) * (p.get("n_height", 24) + 2 * p.get("n_cap_rings", 8))
    if name == "plane":
        return p.get("n", 41) ** 2
    return int(6000 * (0.03 / p.get("resolution", 0.03)) ** 2)


def generate(name: str, params: dict | None = None, force: bool = False) -> Geometry:
    """Build a generated shape by name (``demo:NAME`` on the command line).

    ``params``: the shape's parameters by name (None: its defaults); values may be numbers or
    strings (from ``demo:NAME:key=value``), each checked against ``PARAMETERS``.  Shapes with more than
    ``MAX_GENERATED_VERTICES`` vertices are refused unless ``force``.
    """
    if name not in GENERATORS:
        raise InputError(f"unknown generated shape {name!r}; choose from {', '.join(sorted(GENERATORS))}")
    spec = PARAMETERS[name]
    values = {}
    for key, value in (params or {}).items():
        if key not in spec:
            raise InputError(f"demo:{name} has no parameter {key!r} (parameters: {', '.join(spec)})")
        kind, bounds = spec[key]
        label = f"demo:{name} parameter {key}"
        values[key] = (check_int(value, label, **bounds) if kind == "int" else
                       check_seed(value, label) if kind == "seed" else check_float(value, label, **bounds))
    if name == "torus" and values.get("minor", 0.35) >= values.get("major", 1.0):
        raise InputError(f"demo:torus needs minor < major (got minor {values.get('minor', 0.35):g}, "
                         f"major {values.get('major', 1.0):g}): the tube would cross itself")
    estimate = _vertex_estimate(name, values)
    if estimate > MAX_GENERATED_VERTICES and not force:
        raise TooLargeError(f"demo:{name} with these parameters has about {estimate:,} vertices, more than "
                            f"{MAX_GENERATED_VERTICES:,}; lower them or use --force")
    return GENERATORS[name](**values)
