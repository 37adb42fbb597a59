"""Pictures and PLY files: written, readable, and showing what they should."""

from types import SimpleNamespace

import matplotlib.image as mpimg
import numpy as np
import pytest
import trimesh

from shapecond.errors import InputError
from shapecond.symmetry.starts import classical_mds
from shapecond.viz.heatmap import render_heatmap_png
from shapecond.viz.ply import write_ply
from shapecond.viz.render import Look, render_png, view_rotation
from shapecond.viz.scene import Colouring, interpolate_to_vertices
from shapecond.viz.witness import render_witness_png


@pytest.fixture(scope="module")
def box():
    m = trimesh.creation.icosphere(subdivisions=3)
    v = m.vertices * np.array([2.0, 1.0, 0.6])
    return v, np.asarray(m.faces)


def _red_pixels(img):
    return int(np.sum((img[..., 0] > 0.8) & (img[..., 1] < 0.3) & (img[..., 2] < 0.3)))


def test_view_rotation_is_orthonormal():
    R = view_rotation(23.0, -71.0)
    assert np.allclose(R @ R.T, np.eye(3))
    assert np.isclose(np.linalg.det(R), 1.0)


def test_render_mesh_with_landmarks(tmp_path, box):
    v, f = box
    two = ((20, 30), (5, 0))
    plain = render_png(tmp_path / "a.png", v, f, v[:, 0], look=Look(views=two))
    marked = render_png(tmp_path / "b.png", v, f, v[:, 0], landmarks=[0, 1, 2, 3],
                        look=Look(views=two, colouring=Colouring("Greys")))
    a, b = mpimg.imread(plain), mpimg.imread(marked)
    assert a.shape[0] > 200 and a.shape[1] > 400
    # a grey colour map with red markers: red pixels exist only where the landmarks are
    assert _red_pixels(b) > 20
    grey = render_png(tmp_path / "c.png", v, f, v[:, 0], look=Look(views=two, colouring=Colouring("Greys")))
    assert _red_pixels(mpimg.imread(grey)) == 0


def test_render_point_cloud_and_colours(tmp_path, box):
    v, _ = box
    col = np.tile([1.0, 0.0, 0.0], (len(v), 1))
    out = render_png(tmp_path / "p.png", v, None, col, look=Look(point_size=20))
    assert _red_pixels(mpimg.imread(out)) > 100


def test_render_bad_input(tmp_path, box):
    v, f = box
    with pytest.raises(InputError):
        render_png(tmp_path / "x.png", v, f, np.ones(3))
    with pytest.raises(InputError):
        render_png(tmp_path / "x.png", v, f, landmarks=[len(v)])
    with pytest.raises(InputError):
        render_png(tmp_path / "x.png", v, f + len(v))
    with pytest.raises(InputError):
        render_png(tmp_path / "x.png", v, f, look=Look(up="w"))
    assert not list(tmp_path.iterdir())  # nothing half-written


def test_ply_roundtrip_keeps_order_and_colours(tmp_path, box):
    v, f = box
    path = write_ply(tmp_path / "m.ply", v, f, v[:, 2], landmarks=[5, 9, 11, 40], ring=False)
    back = trimesh.load(path, process=False)
    assert np.allclose(back.vertices, v, atol=1e-5)
    assert np.array_equal(back.faces, f)
    c = back.visual.vertex_colors
    assert tuple(c[5, :3]) == (230, 20, 20) and tuple(c[40, :3]) == (30, 200, 30)
    # the colour map is monotone along a viridis ramp: lowest z darker than highest z
    lo, hi = np.argmin(v[:, 2]), np.argmax(v[:, 2])
    assert c[lo, :3].sum() < c[hi, :3].sum()
    cloud = trimesh.load(write_ply(tmp_path / "c.ply", v, None, None), process=False)
    assert len(cloud.vertices) == len(v)
    with pytest.raises(InputError):
        write_ply(tmp_path / "bad.ply", v, f, np.ones(4))


def _fake_shape(v, f, n, m=None, seed=0):
    rng = np.random.default_rng(seed)
    m = n if m is None else m
    samples = rng.choice(len(v), m, replace=False)
    P = v[samples]
    D = np.linalg.norm(P[:, None] - P[None], axis=2)
    D /= D.max()
    near = np.argmin(np.linalg.norm(v[:, None] - P[None], axis=2), axis=1)
    return SimpleNamespace(D=D, n_samples=n, samples=samples, nearest=near,
                           geometry=SimpleNamespace(vertices=v, faces=f))


def test_interpolation_reproduces_sample_values(box):
    v, f = box
    sh = _fake_shape(v, f, 30)
    vals = np.linspace(0, 1, 30)
    for method in ("nearest", "smooth"):
        out = interpolate_to_vertices(sh, vals, method=method)
        assert out.shape == (len(v),)
        assert np.allclose(out[sh.samples], vals, atol=1e-4)
        assert out.min() >= -1e-12 and out.max() <= 1 + 1e-12
    assert np.allclose(interpolate_to_vertices(sh, np.full(30, 0.3)), 0.3)
    # values over all M targets use MetricShape.nearest
    sh2 = _fake_shape(v, f, 10, m=40)
    allv = np.arange(40.0)
    assert np.array_equal(interpolate_to_vertices(sh2, allv, "nearest"), allv[sh2.nearest])
    with pytest.raises(InputError):
        interpolate_to_vertices(sh, np.ones(7))


def test_heatmap_and_witness_pictures(tmp_path, box):
    v, f = box
    sh = _fake_shape(v, f, 40)
    vals = np.random.default_rng(1).random(40)
    vals[3] = np.inf
    out = render_heatmap_png(sh, vals, tmp_path / "h.png", landmarks=[0, 1], ply=str(tmp_path / "h.ply"))
    assert mpimg.imread(out).shape[1] > 400 and (tmp_path / "h.ply").exists()
    # mirror map x -> -x on a symmetric point set
    P = v[sh.samples]
    mirror = np.argmin(np.linalg.norm(P[:, None] * [-1, 1, 1] - P[None], axis=2), axis=1)
    out = render_witness_png(sh, mirror, tmp_path / "w.png", landmarks=[0])
    assert mpimg.imread(out).shape[0] > 400  # two rows
    with pytest.raises(InputError):
        render_witness_png(sh, mirror[:-1], tmp_path / "w2.png")
    # a matrix input (no geometry) is drawn through classical MDS
    mat = SimpleNamespace(D=sh.D, n_samples=40, geometry=None, samples=None)
    assert mpimg.imread(render_witness_png(mat, mirror, tmp_path / "w3.png")).size > 0


def test_classical_mds_recovers_distances():
    rng = np.random.default_rng(0)
    X = rng.normal(size=(12, 3))
    D = np.linalg.norm(X[:, None] - X[None], axis=2)
    Y = classical_mds(D)
    assert np.allclose(np.linalg.norm(Y[:, None] - Y[None], axis=2), D, atol=1e-8)


def rotations(g):
    """The generated animal (y up) turned so that y, z and -y are up."""
    V = np.asarray(g.vertices, float)
    return {"y": V, "z": V[:, [0, 2, 1]] * [1, -1, 1], "-y": V * [1, -1, -1]}


def test_guess_up_finds_the_feet_whatever_the_axis():
    from shapecond.shapes.synthetic import generate
    from shapecond.viz.scene import guess_up, up_frame

    g = generate("animal", {"resolution": 0.05})
    for up, V in rotations(g).items():
        shape = SimpleNamespace(vertices=V, faces=g.faces)
        assert guess_up(shape) == up and guess_up(shape, shape) == up
        D = (V - V.mean(axis=0)) @ up_frame(up, V).T
        feet = np.argsort(D[:, 2])[:20]                 # drawn upright: the lowest points are the paws,
        assert np.all(g.vertices[feet, 1] < g.vertices[:, 1].min() + 0.1 * np.ptp(g.vertices[:, 1]))
        cloud = SimpleNamespace(vertices=V, faces=None)  # a point cloud too
        assert guess_up(cloud) == up
    assert guess_up(None) == "z" and guess_up(SimpleNamespace(vertices=None)) == "z"
    with pytest.raises(InputError):
        up_frame("+-y")
