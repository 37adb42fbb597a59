"""The next landmark read off a match: cell gains, the map's disagreement with the landmarks, the loop."""

import numpy as np
import pytest

from shapecond.errors import InputError
from shapecond.matching.error_bar import bar_and_samples
from shapecond.matching.sampled import sample_surface
from shapecond.matching.suggest import cell_gains, landmark_disagreement, suggest_landmarks
from shapecond.shapes.synthetic import bumpy_blob


def test_cell_gains_are_the_suspicion_each_point_would_take_from_the_fixed_ones():
    rng = np.random.default_rng(0)
    P = rng.normal(size=(9, 2))
    D = np.linalg.norm(P[:, None] - P[None], axis=-1)
    s = rng.uniform(size=9)
    fixed = [0, 3]
    brute = np.zeros(9)
    for x in range(9):
        if x in fixed:
            continue
        for y in range(9):  # y changes hands when x is nearer than every fixed point
            if D[y, x] < min(D[y, f] for f in fixed):
                brute[x] += s[y]
    np.testing.assert_allclose(cell_gains(D, fixed, s), brute / 9)


def test_landmark_disagreement_is_the_rms_over_the_landmarks_of_the_distance_changes():
    D = np.array([[0.0, 1.0, 2.0], [1.0, 0.0, 1.5], [2.0, 1.5, 0.0]])
    Dt = D.copy()
    Dt[2, :2] = Dt[:2, 2] = [2.3, 1.1]
    r = landmark_disagreement(D, Dt, 2)
    np.testing.assert_allclose(r, [0.0, 0.0, np.sqrt((0.3 ** 2 + 0.4 ** 2) / 2)])


def test_a_region_carried_elsewhere_is_suggested_first_and_the_bar_does_not_grow():
    g = bumpy_blob(subdivisions=3)
    src = sample_surface(g, 60, landmarks=[5, 200, 400], cache=False)
    vmap = np.arange(g.n_vertices)
    rows = src.rows[3]                                  # a region around the 4th sample goes wrong:
    far = int(np.argmax(src.rows[0]))
    wrong = rows < np.quantile(rows, 0.08)
    vmap[wrong] = far                                   # ... every vertex of it is sent to one far vertex
    bar, coarse, Dt = bar_and_samples(src, g, vmap, 3)
    got = suggest_landmarks(coarse, Dt, bar, 3, vmap, g.ids, k=2)
    assert len(got) == 2 and wrong[got[0].vertex]       # the first point lies in the region carried away
    assert got[0].image_id == g.ids[far] and got[0].gain > 0
    assert got[1].vertex != got[0].vertex
    assert got[1].bar_after <= got[0].bar_after + 1e-12 <= bar.bar + 1e-9   # fixing more never widens the bar
    with pytest.raises(InputError):
        suggest_landmarks(coarse, Dt, bar, 3, vmap, g.ids, k=0)


def test_match_suggests_with_the_error_bar_and_refuses_without_it():
    import shapecond as sc

    # the second Laplace basis of the blob from the session cache
    r = sc.match("demo:blob", "demo:blob", [0, 100, 200], [0, 100, 200], n_points=40, suggest=2)
    assert len(r.summary["suggestions"]) == 2 and "click source vertex" in r.summary["verdict"]
    first = r.summary["suggestions"][0]
    assert r.map[first["source_id"]] == first["image_id"]   # the provisional image is the map's
    assert r.suggest(1)[0] == first
    with pytest.raises(InputError, match="error bar"):
        sc.match("demo:blob", "demo:blob", [0, 100, 200], [0, 100, 200], n_points=40, cache=False, suggest=1,
                 error_bar=False)
