"""The compact views of matched maps (``viz.mapview``): their payload, and the report that shows them in a
real headless Chromium with the network blocked (skipped when Chromium or Playwright is missing)."""

import base64
import io
import re

import matplotlib
import numpy as np
import pytest

import shapecond as sc
from shapecond.api.results import MatchResult
from shapecond.batch import schema
from shapecond.batch.report import report_html
from shapecond.shapes.validate import make_geometry
from shapecond.viz.mapview import VIEW_VERTICES, map_view, payload_json
from shapecond.viz.scene import position_colours

from tests.helpers import open_offline

SMALL = "demo:animal:resolution=0.08"  # 942 vertices
LARGER = "demo:animal:resolution=0.04"  # 4002 vertices: decimated to VIEW_VERTICES


def _array(view: dict, key: str, dtype, width: int = 3) -> np.ndarray:
    return np.frombuffer(base64.b64decode(view[key]), dtype).reshape(-1, width)


def _positions(view: dict) -> np.ndarray:
    return np.asarray(view["lo"]) + np.asarray(view["step"]) * _array(view, "positions", np.uint16)


@pytest.fixture(scope="module")
def animal():
    return sc.load(SMALL)


def _shuffled(g, seed=0):
    """``g`` with its vertices in another order: (the copy, perm), copy vertex j = vertex perm[j] of ``g``."""
    perm = np.random.default_rng(seed).permutation(g.n_vertices)
    inv = np.empty_like(perm)
    inv[perm] = np.arange(perm.size)
    return make_geometry(g.vertices[perm], inv[g.faces]), perm, inv


def _result(src, tgt, vertex_map, doubt=None, suggestions=()):
    """A ``MatchResult`` of a known map (source id -> target id) and doubt field (per source id)."""
    return MatchResult(np.asarray(vertex_map, dtype=np.int64), {"suggestions": list(suggestions)},
                       (src, tgt, (), ()), doubt)


def test_colours_are_the_transfer_and_the_doubt_carried_through_the_map(animal):
    tgt, perm, inv = _shuffled(animal)
    doubt = animal.vertices[:, 0] - animal.vertices[:, 0].min()  # a known field: the source's x
    view = map_view(_result(animal, tgt, inv, doubt), max_vertices=animal.n_vertices)  # nothing decimated
    assert view["n"] == view["vertices"] == animal.n_vertices
    # target vertex j is source vertex perm[j]: it takes that vertex's position colour and doubt
    transfer = np.round(position_colours(animal.vertices)[perm] * 255)
    assert np.abs(_array(view, "transfer", np.uint8) - transfer).max() <= 1
    turbo = np.round(matplotlib.colormaps["turbo"](doubt[perm] / doubt.max())[:, :3] * 255)
    assert np.abs(_array(view, "doubt", np.uint8) - turbo).max() <= 1
    assert view["doubt_scale"]["lo"] == 0 and view["doubt_scale"]["hi"] == pytest.approx(doubt.max())
    # the positions are the target's, turned and moved (distances kept to the quantisation)
    P, V = _positions(view), tgt.vertices
    pick = np.arange(0, V.shape[0], 37)
    d = lambda X: np.linalg.norm(X[pick, None] - X[None, pick], axis=2)  # noqa: E731
    assert np.abs(d(P) - d(V)).max() < 2 * np.linalg.norm(view["step"])
    F = _array(view, "faces", np.uint16).astype(np.int64)
    assert np.array_equal(np.sort(np.sort(F, axis=1), axis=0), np.sort(np.sort(tgt.faces, axis=1), axis=0))
    # without an error bar there is no doubt to show
    bare = map_view(_result(animal, tgt, inv), max_vertices=animal.n_vertices)
    assert bare["doubt"] is None and bare["doubt_scale"] is None and bare["transfer"] == view["transfer"]


def test_the_suggested_point_is_marked_where_its_image_lies(animal):
    tgt, perm, inv = _shuffled(animal, 1)
    view = map_view(_result(animal, tgt, inv, suggestions=[{"source_id": 5, "image_id": int(inv[5])}]),
                    max_vertices=animal.n_vertices)
    assert np.linalg.norm(np.asarray(view["suggest"]) - _positions(view)[inv[5]]) < np.linalg.norm(view["step"])
    assert map_view(_result(animal, tgt, inv), max_vertices=animal.n_vertices)["suggest"] is None


def test_a_view_is_small_decimated_and_deterministic():
    g = sc.load(LARGER)
    doubt = np.linspace(0.0, 0.2, g.n_vertices)
    view = map_view(_result(g, g, np.arange(g.n_vertices), doubt))
    text = payload_json(view)
    assert view["vertices"] == g.n_vertices and 0.8 * VIEW_VERTICES <= view["n"] <= VIEW_VERTICES
    assert len(text) <= 60_000, len(text)
    assert _array(view, "faces", np.uint16).max() < view["n"]
    again = sc.load(LARGER)  # another load, another result: the same bytes
    assert payload_json(map_view(_result(again, again, np.arange(g.n_vertices), doubt.copy()))) == text
    small = map_view(_result(g, g, np.arange(g.n_vertices), doubt), max_vertices=300)
    assert small["n"] <= 300 and len(payload_json(small)) < 40 * 300 + 2_000


def test_a_point_cloud_is_drawn_as_points(animal):
    cloud = make_geometry(animal.vertices)
    view = map_view(_result(cloud, cloud, np.arange(cloud.n_vertices), np.zeros(cloud.n_vertices)))
    assert view["faces"] is None and view["n"] == cloud.n_vertices and view["doubt"] is not None


# --- the report, in a browser ------------------------------------------------------------------------

def _rows_and_views(animal, n_maps: int):
    """Rows of a matched batch, each with a view of the animal (maps that turn it more and more)."""
    rows, views = [], {}
    tgt, perm, inv = _shuffled(animal, 2)
    doubt = animal.vertices[:, 1] - animal.vertices[:, 1].min()
    for k in range(n_maps):
        row = schema.empty_row()
        name = f"shape{k:02d}"
        row.update(file=f"/c/{name}.off", match_template="/c/t.off", match_direction="template to shape",
                   match_source="/c/t.off", match_target=f"/c/{name}.off", bar=0.01 * (k + 1), bar_epsilon=0.01,
                   bar_epsilon_hat=0.01, landmark_pairs=4, landmark_labels="a b c d",
                   map_file=f"/c/maps/{name}.txt", seconds=1.0, suggest_source_id=5, suggest_image_id=int(inv[5]))
        rows.append(row)
        views[row["map_file"]] = map_view(_result(animal, tgt, inv, doubt * (k + 1),
                                                  [{"source_id": 5, "image_id": int(inv[5])}]), max_vertices=400)
    return rows, views


def test_the_report_shows_each_view_once_and_cells_that_draw_it(animal):
    rows, views = _rows_and_views(animal, 8)
    page = report_html(rows, views)
    data = re.findall(r'class="sc-mapdata" data-view="(\d+)"', page)
    cells = re.findall(r'class="sc-mapview" data-view="(\d+)"', page)
    assert sorted(data) == sorted(set(cells)) and len(data) == 8  # the data once per map...
    assert len(cells) == 8 + 3  # ...a cell in every table that lists it (3 bars above 0.05)
    assert 'id="sc-three"' in page and "class MapViews" in page
    assert 'id="sc-three"' not in report_html(rows) and "sc-mapview" not in report_html(rows)


def _canvas_pixels(page, k: int) -> np.ndarray:
    import matplotlib.image as mpimg

    shot = page.locator(".sc-mapview canvas").nth(k).screenshot()
    return mpimg.imread(io.BytesIO(shot), format="png")[..., :3]


def test_browser_report_views_turn_and_switch_colourings(browser, tmp_path, animal):
    rows, views = _rows_and_views(animal, 30)
    path = tmp_path / "report.html"
    path.write_text(report_html(rows, views))
    page, errors, requests = open_offline(browser, path)
    assert page.evaluate("window.shapecond.error") is None
    cells = page.locator(".sc-mapview")
    assert cells.count() == 30 + 25 and page.evaluate("window.shapecond.mapviews.views.length") == 55
    # one renderer: the views are 2-D canvases; only those in sight are drawn
    assert page.evaluate("document.querySelectorAll('.sc-mapview canvas').length") == 55
    assert page.evaluate("window.shapecond.mapviews.views[54].frames") == 0
    first = cells.nth(0)
    first.scroll_into_view_if_needed()
    page.wait_for_function("window.shapecond.mapviews.views[0].frames > 0", timeout=5_000)
    before = _canvas_pixels(page, 0)
    assert before.std() > 0.05 and (before.max(axis=2) - before.min(axis=2)).max() > 0.2  # drawn, in colour
    box = first.locator("canvas").bounding_box()
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(x, y)
    page.mouse.down()
    page.mouse.move(x + 60, y + 10, steps=5)
    page.mouse.up()
    page.wait_for_timeout(100)
    turned = _canvas_pixels(page, 0)
    assert page.evaluate("window.shapecond.mapviews.views[0].azim") != views[rows[-1]["map_file"]]["view"][1]
    assert np.abs(turned - before).max() > 0.2
    first.locator("button[data-layer=doubt]").click()
    assert "sc-on" in first.locator("button[data-layer=doubt]").get_attribute("class")
    assert first.locator(".sc-ramp").count() == 1
    assert np.abs(_canvas_pixels(page, 0) - turned).max() > 0.2
    cells.nth(54).scroll_into_view_if_needed()
    page.wait_for_function("window.shapecond.mapviews.views[54].frames > 0", timeout=5_000)
    assert not [u for u in requests if not u.startswith(("file:", "blob:", "data:"))]
    assert not errors, errors
