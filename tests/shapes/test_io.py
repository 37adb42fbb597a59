"""Readers, writers and the validation errors of the shape inputs."""

import numpy as np
import pytest
import trimesh

from shapecond.checks import read_ids
from shapecond.errors import InputError
from shapecond.output import atomic_open
from shapecond.shapes import synthetic
from shapecond.shapes.io import load_geometry, load_input, read_symmetry_map, write_mesh

TETRA_V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
TETRA_F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


@pytest.mark.parametrize("suffix", ["off", "obj", "ply", "stl"])
def test_mesh_round_trip_keeps_vertex_order(tmp_path, suffix):
    g = synthetic.bumpy_blob(subdivisions=2)
    path = tmp_path / f"blob.{suffix}"
    write_mesh(path, g.vertices, g.faces)
    back = load_geometry(path)
    if suffix == "stl":  # STL stores triangle corners, not vertices: compare the surfaces
        assert back.faces.shape == g.faces.shape
        assert np.allclose(back.vertices[back.faces], g.vertices[g.faces], atol=1e-5)
    else:
        assert np.allclose(back.vertices, g.vertices, atol=1e-5)
        assert np.array_equal(back.faces, g.faces)
        assert np.array_equal(back.ids, np.arange(g.n_vertices))


def test_ply_with_colours_round_trip(tmp_path):
    g = synthetic.sphere(subdivisions=1)
    colors = np.tile([255, 0, 0, 255], (g.n_vertices, 1)).astype(np.uint8)
    write_mesh(tmp_path / "c.ply", g.vertices, g.faces, colors=colors)
    loaded = trimesh.load(tmp_path / "c.ply", process=False)
    assert np.array_equal(np.asarray(loaded.visual.vertex_colors)[:, :3], colors[:, :3])


def test_tosca_vert_tri_is_one_based(tmp_path):
    np.savetxt(tmp_path / "t.vert", TETRA_V)
    np.savetxt(tmp_path / "t.tri", TETRA_F + 1, fmt="%d")
    for name in ("t.vert", "t.tri"):
        g = load_geometry(tmp_path / name)
        assert np.array_equal(g.faces, TETRA_F)


def test_point_cloud_readers(tmp_path):
    pts = np.random.default_rng(0).normal(size=(20, 3))
    np.savetxt(tmp_path / "p.xyz", pts)
    np.savetxt(tmp_path / "p.txt", np.column_stack([pts, np.ones(20)]))  # extra columns ignored
    np.save(tmp_path / "p.npy", pts)
    write_mesh(tmp_path / "p.ply", pts, None)
    for name in ("p.xyz", "p.txt", "p.npy", "p.ply"):
        g = load_input(str(tmp_path / name))
        assert g.faces is None and np.allclose(g.vertices, pts, atol=1e-6)


def test_distance_matrix_input(tmp_path):
    pts = np.random.default_rng(1).normal(size=(6, 3))
    D = np.linalg.norm(pts[:, None] - pts[None], axis=-1)
    np.save(tmp_path / "d.npy", D)
    assert np.allclose(load_input(str(tmp_path / "d.npy")), D)


def test_unreferenced_vertices_dropped_with_ids(tmp_path):
    V = np.vstack([[[9, 9, 9]], TETRA_V, [[5, 5, 5]]])
    path = tmp_path / "iso.off"
    write_mesh(path, V, TETRA_F + 1)
    g = load_geometry(path)
    assert g.n_vertices == 4
    assert np.array_equal(g.ids, [1, 2, 3, 4])
    assert np.array_equal(g.to_internal([4, 1]), [3, 0])
    with pytest.raises(InputError, match="not a vertex"):
        g.to_internal([0])


def _off(path, V, F):
    lines = ["OFF", f"{len(V)} {len(F)} 0"] + [" ".join(map(str, v)) for v in V] + [f"3 {a} {b} {c}" for a, b, c in F]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("case,match", [
    ("empty", "empty"),
    ("garbage", "binary data"),
    ("nan", "NaN"),
    ("past", "index"),
    ("zero_area", "zero area"),
    ("duplicate", "duplicate"),
    ("disconnected", "2 connected components"),
])
def test_bad_meshes_raise_one_line_errors(tmp_path, case, match):
    path = tmp_path / f"{case}.off"
    if case == "empty":
        path.write_text("")
    elif case == "garbage":
        path.write_text("this is not a mesh\n\x00\x01")
    elif case == "nan":
        V = TETRA_V.copy()
        V[1, 0] = np.nan
        _off(path, V, TETRA_F)
    elif case == "past":
        _off(path, TETRA_V, np.vstack([TETRA_F, [[1, 2, 7]]]))
    elif case == "zero_area":
        _off(path, TETRA_V, np.vstack([TETRA_F, [[1, 1, 2]]]))
    elif case == "duplicate":
        _off(path, TETRA_V, np.vstack([TETRA_F, TETRA_F[:1]]))
    elif case == "disconnected":
        _off(path, np.vstack([TETRA_V, TETRA_V + 5]), np.vstack([TETRA_F, TETRA_F + 4]))
    with pytest.raises(InputError, match=match) as info:
        load_geometry(path)
    assert "\n" not in str(info.value)


def test_largest_component_option(tmp_path):
    V = np.vstack([TETRA_V, synthetic.sphere(1).vertices + 5])
    F = np.vstack([TETRA_F, synthetic.sphere(1).faces + 4])
    g = load_geometry(_off(tmp_path / "two.off", V, F), largest_component=True)
    assert g.n_vertices == synthetic.sphere(1).n_vertices
    assert g.ids.min() == 4  # file ids are kept


@pytest.mark.parametrize("D,match", [
    (np.ones((3, 4)), "N x N"),
    (np.array([[0, 1, 2], [1, 0, 1], [3, 1, 0.0]]), "symmetric"),
    (np.array([[0, -1, 2], [-1, 0, 1], [2, 1, 0.0]]), "negative"),
    (np.zeros((4, 4)), "zero"),
    (np.array([[0, 1, np.nan], [1, 0, 1], [np.nan, 1, 0]]), "NaN"),
])
def test_bad_distance_matrices(tmp_path, D, match):
    np.save(tmp_path / "d.npy", D)
    with pytest.raises(InputError, match=match):
        load_input(str(tmp_path / "d.npy"))


def test_unknown_file_type_and_missing_file(tmp_path):
    (tmp_path / "x.docx").write_text("hello")
    with pytest.raises(InputError, match="unknown file type"):
        load_input(str(tmp_path / "x.docx"))
    with pytest.raises(InputError, match="no such file"):
        load_input(str(tmp_path / "missing.off"))


def test_landmark_and_symmetry_files(tmp_path):
    (tmp_path / "l.pid").write_text("  12 0 0 0\n\n7 0.0 0.0 0.0\n")  # BIM .pid vertex points
    assert read_ids(tmp_path / "l.pid") == [12, 7]
    for text in ("1 2 3\n", "1,2,3\n", "1\n2\n3\n", "1, 2 # left paw\n3.0\n"):  # every id, however written
        (tmp_path / "l.txt").write_text(text)
        assert read_ids(tmp_path / "l.txt") == [1, 2, 3], text
    for text, message in (("5, 7.5, 9\n", "7.5' is not an integer vertex id"),
                          ("12 0.5 0.5 0\n", "point inside a triangle"),
                          ("12 0.1 0.2\n", "0.1' is not an integer vertex id"),
                          ("1 2 2\n", "id 2 is repeated"), ("1 two\n", "'two' is not a vertex id")):
        (tmp_path / "l.txt").write_text(text)
        with pytest.raises(InputError, match=message):
            read_ids(tmp_path / "l.txt")
    (tmp_path / "s.sym").write_text("2\n1\n3\n")
    assert list(read_symmetry_map(tmp_path / "s.sym")) == [1, 0, 2]
    (tmp_path / "bad.sym").write_text("0\n1\n")
    with pytest.raises(InputError):
        read_symmetry_map(tmp_path / "bad.sym")


def test_atomic_write_leaves_nothing_on_failure(tmp_path):
    target = tmp_path / "out.txt"
    with pytest.raises(RuntimeError):
        with atomic_open(target, "w") as fh:
            fh.write("half")
            raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("suffix", [".off", ".obj", ".ply"])
def test_a_tiny_mesh_written_and_read_back_keeps_its_size(tmp_path, suffix):
    """write_mesh wrote a mesh scaled by 1e-25 with 10 decimals: every vertex at 0, refused as one point."""
    import shapecond as sc
    from shapecond.shapes.synthetic import sphere

    g = sphere(subdivisions=2)
    write_mesh(tmp_path / f"tiny{suffix}", g.vertices * 1e-25, g.faces)
    back = sc.load(tmp_path / f"tiny{suffix}")
    np.testing.assert_allclose(back.vertices, g.vertices * 1e-25, rtol=1e-7, atol=0)


def test_a_file_with_every_vertex_at_one_point_says_what_happened(tmp_path):
    import shapecond as sc

    (tmp_path / "zero.off").write_text("OFF\n4 2 0\n" + "0.0000000000 0.0000000000 -0.0000000000\n" * 4
                                        + "3 0 1 2\n3 0 2 3\n")
    with pytest.raises(InputError, match="same coordinates.*too few decimals"):
        sc.load(tmp_path / "zero.off")
