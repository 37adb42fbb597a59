"""The remeshed protocol on a generated class: differently meshed strips with .vts ground truth."""

import numpy as np
import pytest

from shapecond.evaluation import EvaluationOptions, evaluate_dataset
from shapecond.evaluation.datasets import find_classes
from shapecond.evaluation.protocols import landmark_images
from shapecond.evaluation.report import markdown
from shapecond.shapes.geodesics import DistanceSolver
from shapecond.shapes.synthetic import plane_patch

W, H = 1.0, 0.55  # a rectangle: 3 landmarks off its axes remove its symmetries


def _strip(n, bend=None, seed=None):
    g = plane_patch(n=n)
    uv = g.vertices[:, :2] * [W, H]
    V = np.column_stack([uv, np.zeros(len(uv))])
    if bend is not None:  # bent onto a cylinder: an isometry
        th = uv[:, 0] / bend
        V = np.column_stack([bend * np.sin(th), uv[:, 1], bend * (1 - np.cos(th))])
    F = g.faces
    if seed is not None:  # vertices in another order
        perm = np.random.default_rng(seed).permutation(len(V))
        V, uv, F = V[perm], uv[perm], np.argsort(perm)[F]
    return V, F, uv


def _write(folder, name, V, F, uv, ref):
    (folder / "shapes").mkdir(parents=True, exist_ok=True)
    (folder / "corres").mkdir(exist_ok=True)
    (folder / "shapes" / f"{name}.off").write_text(
        f"OFF\n{len(V)} {len(F)} 0\n" + "".join(f"{x} {y} {z}\n" for x, y, z in V)
        + "".join(f"3 {a} {b} {c}\n" for a, b, c in F))
    nearest = np.argmin(((uv[None, :, :] - ref[:, None, :]) ** 2).sum(-1), axis=1)
    (folder / "corres" / f"{name}.vts").write_text("".join(f"{i + 1}\n" for i in nearest))


@pytest.fixture(scope="module")
def remeshed(tmp_path_factory):
    """Class 'strip': three resolutions, two of them bent and renumbered; 12 x 7 reference points."""
    root = tmp_path_factory.mktemp("remeshed")
    u, v = np.meshgrid(np.linspace(0.04, 0.96, 12) * W, np.linspace(0.04, 0.96, 7) * H)
    ref = np.column_stack([u.ravel(), v.ravel()])
    for name, args in (("strip0", (21,)), ("strip4", (27, 0.5, 1)), ("strip9", (17, 0.35, 2))):
        _write(root / "strip", name, *_strip(*args), ref)
    # the mirror u -> W - u of reference point j (the rectangle's symmetry) for the flip count
    mirror = [int(np.argmin(((ref - [W - a, b]) ** 2).sum(1))) + 1 for a, b in ref]
    (root / "strip" / "corres" / "reference.sym").write_text("".join(f"{m}\n" for m in mirror))
    return root


def test_a_corres_folder_makes_a_remeshed_class(remeshed):
    (cls,) = find_classes(remeshed).values()
    assert cls.layout == "remeshed" and [p.stem for p in cls.shapes] == ["strip0", "strip4", "strip9"]
    assert find_classes(remeshed / "strip")["strip"].layout == "remeshed"  # one class given directly


@pytest.mark.slow
def test_dense_maps_between_differently_meshed_strips_err_below_a_vertex_spacing(remeshed):
    ev = evaluate_dataset(remeshed, options=EvaluationOptions(methods=("fps",), matchers=("lh05", "zoomout"), n_points=60))
    assert ev.settings["protocols"] == ["remeshed"]
    # 2 targets x counts {3, 10} x 2 matchers
    assert len(ev.records) == 8 and {r.protocol for r in ev.records} == {"remeshed"}
    spacing = max(W / 16, H / 16) / np.sqrt(W * H)   # the coarsest mesh's edge, in units of sqrt(area)
    for r in ev.records:
        assert r.error_area < 0.75 * spacing, r        # the .vts quantisation alone is up to ~half of it
        assert r.flipped == 0.0, r
    text = markdown(ev)
    assert "remeshed protocol, matcher zoomout" in text and "sqrt(area)" in text


def test_reference_errors_of_the_truth_and_of_its_mirror_image():
    from shapecond.evaluation.protocols import reference_errors
    from shapecond.shapes.validate import make_geometry

    V, F, uv = _strip(15)
    g = make_geometry(V, F)
    u, v = np.meshgrid(np.linspace(0.1, 0.9, 6) * W, np.linspace(0.1, 0.9, 4) * H)
    ref = np.column_stack([u.ravel(), v.ravel()])
    truth = np.argmin(((uv[None] - ref[:, None]) ** 2).sum(-1), axis=1)
    sym = np.array([int(np.argmin(((ref - [W - a, b]) ** 2).sum(1))) for a, b in ref])
    errors, diameter, mirror = reference_errors(g, truth, {"truth": truth, "mirror": truth[sym]}, "heat", truth[sym])
    assert errors["truth"].max() < 1e-6
    assert errors["mirror"].mean() == pytest.approx(mirror, rel=1e-6)   # a flip errs by the mirror distance
    assert errors["mirror"].mean() > 0.5 * mirror                       # ... so it is counted as flipped
    assert diameter == pytest.approx(np.hypot(W, H), rel=0.05)


def test_landmarks_off_every_reference_point_go_through_the_nearest_one():
    from shapecond.shapes.validate import make_geometry

    V, F, uv = _strip(11)
    g = make_geometry(V, F)
    ref_s = np.array([0, 60, 120])            # three reference points on the source...
    ref_t = np.array([5, 6, 7])               # ... and where they are on the target
    # vertex 60 is a reference point; vertex 61 (its neighbour) is not: it goes through 60
    np.testing.assert_array_equal(landmark_images([61, 0, 120], ref_s, ref_t, DistanceSolver(g)), [6, 5, 7])


def test_two_landmarks_on_one_target_vertex_take_the_nearest_free_reference_point():
    from shapecond.shapes.validate import make_geometry

    V, F, uv = _strip(11)
    g = make_geometry(V, F)
    ref_s = np.array([0, 60, 61, 120])        # 60 and 61 are neighbours on the source ...
    ref_t = np.array([5, 6, 6, 7])            # ... that the coarser target merges into vertex 6
    images = landmark_images([60, 61, 62], ref_s, ref_t, DistanceSolver(g))
    assert images[0] == 6 and len(set(images.tolist())) == 3        # a correspondence: distinct images
    assert set(images[1:].tolist()) == {5, 7}                        # the nearest reference points still free
