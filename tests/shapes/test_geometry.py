"""``Geometry.shares_vertex_order``: one vertex order means one mesh deformed, not one vertex count."""

import numpy as np

from shapecond.shapes.synthetic import plane_patch
from shapecond.shapes.validate import make_geometry


def test_a_deformed_copy_shares_its_order_and_a_renumbered_one_does_not():
    g = plane_patch(n=11)
    bent = make_geometry(g.vertices + [0.0, 0.0, 0.3] * g.vertices[:, :1] ** 2, g.faces, "bent")
    flipped = make_geometry(g.vertices, g.faces[:, ::-1], "flipped")  # same triangles, other orientation
    perm = np.random.default_rng(0).permutation(g.n_vertices)
    renumbered = make_geometry(g.vertices[perm], np.argsort(perm)[g.faces], "renumbered")
    assert g.shares_vertex_order(bent) and g.shares_vertex_order(flipped)
    assert not g.shares_vertex_order(renumbered) and not renumbered.shares_vertex_order(g)
    assert not g.shares_vertex_order(plane_patch(n=12))  # another vertex count
    cloud = make_geometry(g.vertices + 0.1, None, "cloud")
    assert g.shares_vertex_order(cloud) and cloud.shares_vertex_order(g)  # ids only
