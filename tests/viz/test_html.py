"""HTML pages: self-contained, deterministic, built from the PNGs' scenes, and working in a
real headless Chromium with the network blocked (the browser tests skip when Chromium or Playwright is
missing)."""

import hashlib
import io
import json
import re
from pathlib import Path

import numpy as np
import pytest

import shapecond as sc
from shapecond.errors import InputError
from shapecond.shapes.synthetic import generate
from shapecond.viz import html as H
from shapecond.viz import pages
from shapecond.viz import truth as viz_truth
from shapecond.viz.render import view_rotation
from shapecond.viz.scene import heatmap_scene, make_scene

from tests.helpers import open_offline, run_cli

SMALL = "demo:animal:resolution=0.08"  # 942 vertices: what is tested is the page, not the mesh


def _data(document: str) -> list:
    """The scenes embedded in a page."""
    return [json.loads(m) for m in re.findall(r'<script type="application/json" class="sc-data">(.*?)</script>',
                                              document, re.S)]


def _front_vertex(data: dict, k: int = 0) -> int:
    """The display vertex nearest the camera of view ``k`` (nothing can hide it), off the mesh's boundary
    (a ray through a boundary vertex grazes the edge of its triangles)."""
    import base64

    P = np.frombuffer(base64.b64decode(data["positions"]), np.float32).reshape(-1, 3)
    depth = P @ view_rotation(*data["views"][k])[2]
    if data["faces"] is not None:
        F = np.frombuffer(base64.b64decode(data["faces"]), np.uint32).reshape(-1, 3).astype(np.int64)
        E = np.sort(np.vstack([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
        edges, count = np.unique(E, axis=0, return_counts=True)
        depth[np.unique(edges[count == 1])] = -np.inf
    return int(np.argmax(depth))


def _id(data: dict, i: int) -> int:
    import base64

    return i if data["ids"] is None else int(np.frombuffer(base64.b64decode(data["ids"]), np.int32)[i])


@pytest.fixture(scope="module")
def heat():
    return sc.heatmap(SMALL, n_points=24, cache=False, effort="quick")


# --- the file ----------------------------------------------------------------------------------

def test_page_is_self_contained_and_deterministic(heat):
    a, b = pages.result_page(heat), pages.result_page(heat)
    assert a == b
    # no script, style, image or frame is fetched: no src/href pointing anywhere
    assert not re.search(r"<(script|link|img|iframe)[^>]*\b(src|href)\s*=", a, re.I)
    assert not re.search(r"url\(\s*['\"]?https?:", a, re.I)
    assert "</script" not in H.three_source().lower()
    assert a.count('class="sc-data"') == 1


def test_vendored_three_js_is_the_release_with_its_licence():
    text = H.asset("three.module.min.js")
    assert hashlib.sha256(text.encode()).hexdigest() == H.THREE_SHA256
    assert f'const t="{H.THREE_VERSION.split(".")[1]}"' in text[:400]
    licence = H.asset("three.LICENSE")
    assert "MIT License" in licence and "three.js authors" in licence


def test_html_shows_the_png_colours(heat):
    """The viewer's colours are the scene's, which the PNG draws (one colour computation)."""
    import base64

    scene = heatmap_scene(heat.shape, heat.plot_values(), landmarks=range(len(heat.landmarks)))
    data = H.scene_data(scene)
    rgb = np.frombuffer(base64.b64decode(data["layers"][0]["colours"]), np.uint8).reshape(-1, 3)
    assert np.array_equal(rgb, np.round(scene.layers[0].rgba[:, :3] * 255).astype(np.uint8))
    bar = scene.layers[0].colorbar
    assert data["layers"][0]["colorbar"]["stops"][0] == bar.stops()[0] and bar.cmap == "turbo"


def test_decimation_keeps_ids_and_says_so():
    g = generate("sphere", {"subdivisions": 5})  # 10,242 vertices
    ids = np.arange(g.n_vertices) * 3 + 7
    scene = make_scene(g.vertices, g.faces, [dict(values=g.vertices[:, 2], landmarks=[5, 9])], ids=ids)
    small, note = H.decimate(scene, 2000)
    assert 500 < small.n_vertices <= 2000 and "decimated from 10,242" in note
    assert set(small.ids) <= set(ids) and small.faces.max() < small.n_vertices
    assert H.decimate(scene, 20_000) == (scene, None)
    data = H.scene_data(scene, 2000)
    assert data["n"] == small.n_vertices and any("decimated" in n for n in data["notes"])


@pytest.mark.parametrize("h", [1e-9, 0.01, 0.3])  # 1e-9: too many cells for one int64 key, the row keys
def test_grid_cells_are_numbered_as_the_rows_of_their_coordinates(h):
    V = generate("sphere", {"subdivisions": 3}).vertices
    keys = np.floor((V - V.min(axis=0)) / h).astype(np.int64)
    _, first, label = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    got = H._clusters(V, h)
    assert np.array_equal(got[0], first) and np.array_equal(got[1], label.ravel())


@pytest.mark.slow
def test_a_50k_vertex_page_is_a_few_mb():
    g = generate("sphere", {"subdivisions": 7})  # 163,842 vertices: decimated to 50k at most
    scene = make_scene(g.vertices, g.faces, [dict(values=g.vertices[:, 0])])
    document = H.page("big", [H.viewer(scene)])
    assert len(document.encode()) < 5e6
    assert _data(document)[0]["n"] <= H.MAX_DISPLAY_VERTICES


def test_bad_inputs_are_input_errors(tmp_path):
    D = np.abs(np.subtract.outer(np.arange(8.0), np.arange(8.0)))
    res = sc.match(D, D, [0, 7], [0, 7], matcher="faq")
    with pytest.raises(InputError):
        res.to_html(tmp_path / "x.html")
    assert res._repr_html_() is None and not (tmp_path / "x.html").exists()
    with pytest.raises(InputError):
        viz_truth.read_truth(str(tmp_path / "missing.txt"))


def test_cli_html_options(tmp_path, capsys):
    code, out, err = run_cli(capsys, "heatmap", SMALL, "-n", "16", "--effort", "quick", "--no-cache", "--html",
                             tmp_path / "h.html", "--json")
    assert code == 0 and (tmp_path / "h.html").stat().st_size > 1e5
    hm = json.loads(out)  # the best landmark: the vertex id of the sample with the lowest score
    values = [float(v) for v in hm["values"]]
    assert hm["best"] == hm["samples"][int(np.argmin(values))] and hm["best_value"] == min(values) < np.inf
    code, out, err = run_cli(capsys, "heatmap", SMALL, "-n", "16", "--no-cache")
    assert code == 2 and err.startswith("error: ") and "--html" in err
    code, out, err = run_cli(capsys, "match", SMALL, SMALL, "--landmarks-source", "0,50,300",
                             "--landmarks-target", "0,50,300", "-n", "20", "--matcher", "faq", "--no-cache",
                             "-o", tmp_path / "map.txt", "--truth", "same-ids", "--json")
    assert code == 0, err  # the truth measures the map without a page: the summary says how wrong it is
    truth = json.loads(out)["truth"]
    low, high = sorted((truth["median"], truth["mean"]))
    assert truth["unit"] == "sqrt(area)" and 0 <= low <= high <= truth["worst"]
    assert 0 < truth["n_points"] <= 200 and truth["mean_percent_half_diameter"] >= 0


# --- in a real browser ----------------------------------------------------------------------------

def _open(ctx, path: Path):
    """Open a page offline once every viewer drew its first frame; return (page, console errors, requests)."""
    return open_offline(ctx, path, "window.shapecond && (window.shapecond.error || (window.shapecond.ready && "
                                   "window.shapecond.viewers.every(v => v.firstFrame !== null)))")


def _check(page, errors, requests, path: Path, k: int = 0):
    """No error, nothing fetched, a drawn canvas, and the id of a known vertex on hover (viewer ``k``)."""
    import matplotlib.image as mpimg

    assert page.evaluate("window.shapecond.error") is None
    assert not [u for u in requests if not u.startswith(("file:", "blob:", "data:"))]
    canvas = page.locator("canvas").nth(k)
    img = mpimg.imread(io.BytesIO(canvas.screenshot()), format="png")[..., :3]
    assert img.std() > 0.05 and (img.max(axis=2) - img.min(axis=2)).max() > 0.2  # drawn, in colour
    data = _data(path.read_text())[k]
    i = _front_vertex(data)
    canvas.scroll_into_view_if_needed()
    xy = page.evaluate(f"window.shapecond.viewers[{k}].screenOf({i})")
    page.mouse.move(xy["x"], xy["y"])
    hover = page.locator(".sc-hover").nth(k)
    hover.wait_for(state="visible", timeout=5_000)
    assert hover.get_attribute("data-vertex") == str(_id(data, i))
    assert f"vertex {_id(data, i)}" in hover.inner_text()
    assert not errors, errors
    return hover.inner_text()


def test_browser_heatmap_page(browser, tmp_path):
    # an unreferenced first vertex: the input's ids are 1..n, not the internal 0..n-1
    g = generate("animal", {"resolution": 0.05})
    V = np.vstack([[9.0, 9.0, 9.0], g.vertices])
    res = sc.heatmap((V, g.faces + 1), n_points=20, cache=False, effort="quick")
    path = Path(res.to_html(tmp_path / "heat.html"))
    page, errors, requests = _open(browser, path)
    text = _check(page, errors, requests, path)
    assert "σ with the point fixed" in text
    assert page.locator(".sc-ramp").count() == 1


def test_browser_score_and_landmarks_pages(browser, tmp_path):
    res = sc.score(SMALL, n_points=20, landmarks=[0], cache=False, effort="quick")
    path = Path(res.to_html(tmp_path / "score.html"))
    page, errors, requests = _open(browser, path)
    _check(page, errors, requests, path)
    assert page.locator("button.sc-layer").count() == 3  # reference, witness, scale-aware witness
    page.locator("button.sc-layer").nth(1).click()
    assert page.evaluate("window.shapecond.viewers[0].current") == 1 and not errors
    lm = sc.landmarks(SMALL, 4, "fps", n_points=20, cache=False, scores=True, effort="quick")
    path = Path(lm.to_html(tmp_path / "lm.html"))
    page, errors, requests = _open(browser, path)
    _check(page, errors, requests, path)
    assert page.locator(".sc-landmarks li").count() == 4 and "σ after" in page.locator(".sc-side").inner_text()


@pytest.mark.slow
def test_browser_match_page_with_errors(browser, tmp_path, capsys):
    out = tmp_path / "match.html"
    code, _, err = run_cli(capsys, "match", SMALL, "demo:animal:resolution=0.08,delta=0.1", "--landmarks-source",
                           "0,50,300", "--landmarks-target", "0,50,300", "-n", "20", "--matcher", "faq",
                           "--no-cache", "-o", tmp_path / "map.txt", "--html", out, "--truth", "same-ids")
    assert code == 0, err
    page, errors, requests = _open(browser, out)
    text = _check(page, errors, requests, out)
    assert text.startswith("source vertex") and "→ target vertex" in text
    assert page.locator("button.sc-layer").count() == 3 and "error field" in out.read_text()   # transfer, error, doubt
    page.locator("button.sc-layer").nth(2).click()                                             # the doubt field draws
    assert "error bar's doubt" in out.read_text() and not errors


def test_browser_local_page(browser, tmp_path, capsys):
    out = tmp_path / "local.html"
    code, _, err = run_cli(capsys, "local", "demo:blob:subdivisions=2", "-l", "0,5,40", "--html", out)
    assert code == 0, err
    page, errors, requests = _open(browser, out)
    assert "σ_inf with the vertex fixed" in _check(page, errors, requests, out)


def test_browser_decimated_page(browser, tmp_path):
    g = generate("sphere", {"subdivisions": 5})
    scene = make_scene(g.vertices, g.faces, [dict(values=g.vertices[:, 2])], ids=np.arange(g.n_vertices) + 100)
    path = tmp_path / "dec.html"
    path.write_text(H.page("decimated", [H.viewer(scene, max_vertices=1500)]))
    page, errors, requests = _open(browser, path)
    _check(page, errors, requests, path)
    assert "decimated" in page.locator(".sc-notes").inner_text()


def test_browser_evaluation_report(browser, tmp_path):
    from shapecond.evaluation import EvaluationOptions, evaluate_dataset
    from shapecond.evaluation.report import write_report
    from shapecond.shapes.synthetic import plane_patch

    root = tmp_path / "data"
    (root / "strip").mkdir(parents=True)
    g = plane_patch(n=13)
    for k, bend in ((0, 0.0), (1, 0.2)):
        V = g.vertices * [1.0, 0.55, 0.0] + [0.0, 0.0, bend] * (g.vertices[:, :1] ** 2)
        with open(root / "strip" / f"strip{k}.off", "w") as f:
            f.write(f"OFF\n{len(V)} {len(g.faces)} 0\n")
            f.writelines(f"{x} {y} {z}\n" for x, y, z in V)
            f.writelines(f"3 {a} {b} {c}\n" for a, b, c in g.faces)
    ev = evaluate_dataset(root, options=EvaluationOptions(methods=("fps", "hks"), matchers=("faq",), n_points=16, cache=False))
    write_report(ev, tmp_path / "out")
    path = tmp_path / "out" / "report.html"
    document = path.read_text()
    assert "<table>" in document and 'src="data:image/png;base64,' in document
    page, errors, requests = _open(browser, path)
    _check(page, errors, requests, path)
    assert page.locator("button.sc-layer").count() == 2  # one colouring per method


def test_browser_jupyter_inline_view(browser, tmp_path, heat):
    """``_repr_html_`` is the page in a sandboxed iframe; the viewer starts inside it."""
    snippet = heat._repr_html_()
    assert snippet.startswith("<iframe srcdoc=") and "<script" not in snippet  # the page is escaped
    path = tmp_path / "notebook.html"
    path.write_text(f"<!DOCTYPE html><html><body><p>a notebook cell</p>{snippet}</body></html>")
    page = browser.new_page()
    errors = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.goto(path.as_uri())
    page.wait_for_load_state("load")
    frame = page.frames[1]  # another (opaque) origin: read from inside the frame
    frame.wait_for_function("window.shapecond && (window.shapecond.ready || window.shapecond.error)",
                            timeout=20_000)
    assert frame.evaluate("window.shapecond.error") is None and frame.evaluate("window.shapecond.viewers.length") == 1
    assert not errors


# --- picking landmarks on the match page, suggestions, the up direction -----------------------------

@pytest.fixture(scope="module")
def pair_result():
    return sc.match(SMALL, "demo:animal:resolution=0.08,delta=0.1", [0, 50, 300], [0, 50, 300], matcher="faq",
                    n_points=20, cache=False, error_bar=False)


PATHS = dict(source="my shapes/a.off", target="b.off", output="map.txt", html="page.html")


def test_match_page_knows_the_command_and_the_suggestions(pair_result, tmp_path):
    src, tgt = pair_result.drawing[:2]
    document = pages.result_page(pair_result, pages.PageOptions(command=PATHS,
                                                                suggestions=[(7, "bar after: 0.021"), (90, None)]))
    data = _data(document)[0]
    p = data["picking"]
    assert (p["source"], p["target"], p["output"], p["html"]) == ("'my shapes/a.off'", "b.off", "map.txt", "page.html")
    assert p["pairs"] == [[0, 0], [50, 50], [300, 300]] and p["placeholders"] == []
    shown = [(s["label"], s["id"], s["note"]) for s in data["suggestions"]]
    assert shown == [("S1", int(src.ids[7]), "bar after: 0.021"), ("S2", int(src.ids[90]), "")]
    bare = _data(pages.result_page(pair_result))[0]
    assert bare["picking"]["source"] == "SOURCE" and "html" in bare["picking"]["placeholders"]
    assert bare["suggestions"] == []
    for bad in (dict(command=dict(sorce="a.off")), dict(suggestions=[(src.n_vertices, "x")]),
                dict(suggestions=[(-1, "x")]), dict(suggestions=[(1.5, "x")])):
        with pytest.raises(InputError):
            pages.result_page(pair_result, pages.page_options(pair_result, bad))


def test_to_html_takes_the_declared_options_and_refuses_the_others_in_one_line(pair_result):
    """``pages.PAGE_OPTIONS`` names, for each result type, the ``PageOptions`` its page reads; any other
    keyword of ``to_html`` (a match's ``lines``, set by its page, was a TypeError) is refused like a
    misspelling, before anything is drawn."""
    from dataclasses import fields

    assert set().union(*pages.PAGE_OPTIONS.values()) == {f.name for f in fields(pages.PageOptions)}
    options = pages.page_options(pair_result, dict(title="a distinctive title", up="z"))
    assert options == pages.PageOptions(title="a distinctive title", up="z")
    assert "a distinctive title" in pages.result_page(pair_result, options)
    for bad in ("lines", "landmarks_source", "titel"):
        with pytest.raises(InputError, match=f"unknown option {bad!r} \\(its options: truth, suggestions"):
            pages.page_options(pair_result, {bad: ()})
        with pytest.raises(InputError, match=f"unknown option {bad!r}"):
            pair_result.to_html("never-written.html", **{bad: ()})


def test_match_page_stands_shapes_upright(pair_result):
    import base64

    from shapecond.shapes.validate import make_geometry

    src, tgt = pair_result.drawing[:2]
    lying = [make_geometry(g.vertices[:, [0, 2, 1]] * [1, -1, 1], g.faces, name=g.name) for g in (src, tgt)]  # z up
    vmap = np.arange(src.n_vertices)
    for shapes in ((src, tgt), lying):
        data = _data(pages.match_page(*shapes, vmap))[0]
        P = np.frombuffer(base64.b64decode(data["positions"]), np.float32).reshape(-1, 3)[: src.n_vertices]
        low = np.argsort(P[:, 2])[:20]                   # the source's lowest display points: its paws
        assert np.all(src.vertices[low, 1] < src.vertices[:, 1].min() + 0.1 * np.ptp(src.vertices[:, 1]))


def _visible(page, data: dict, part: int, avoid=()) -> int:
    """A display vertex of ``part`` near the camera of view 0 that nothing hides (the first of those the
    viewer finds all around its screen position, so that a click there cannot miss it), away from the
    vertices ``avoid``."""
    import base64

    P = np.frombuffer(base64.b64decode(data["positions"]), np.float32).reshape(-1, 3)
    _, lo, hi = data["parts"][part]
    depth = P[lo:hi] @ view_rotation(*data["views"][0])[2]
    far = np.ptp(P[lo:hi], axis=0).max() * 0.2
    for i in avoid:
        depth[np.linalg.norm(P[lo:hi] - P[i], axis=1) < far] = -np.inf
    for i in lo + np.argsort(-depth, kind="stable")[:200]:  # found under every pixel within 1.5 px
        if page.evaluate(f"(v => {{ const p = v.screenOf({i}); return [-1.5, 0, 1.5].flatMap(dx => [-1.5, 0, 1.5]"
                         f".map(dy => v.vertexAt(p.x + dx, p.y + dy))).every(j => j === {i}); }})"
                         "(window.shapecond.viewers[0])"):
            return int(i)
    raise AssertionError("no visible vertex")


def test_browser_match_page_picks_landmarks(browser, tmp_path, pair_result):
    import shlex
    from urllib.parse import unquote

    path = Path(pair_result.to_html(tmp_path / "pick.html", command=PATHS, suggestions=[(7, "bar after: 0.021")]))
    page, errors, requests = _open(browser, path)
    _check(page, errors, requests, path)
    data = _data(path.read_text())[0]
    s1, t1 = _visible(page, data, 0), _visible(page, data, 1)
    s2, t2 = _visible(page, data, 0, [s1]), _visible(page, data, 1, [t1])
    viewer = "window.shapecond.viewers[0]"

    def click(i):
        xy = page.evaluate(f"{viewer}.screenOf({i})")
        page.mouse.click(xy["x"], xy["y"])

    click(t1)  # a target first: nothing added
    assert "source vertex first" in page.locator(".sc-pick-state").inner_text()
    for i in (s1, t1, s2, t2):
        click(i)
    words = shlex.split(page.locator(".sc-command").inner_text())
    ids = [_id(data, i) for i in (s1, t1, s2, t2)]
    assert words[:4] == ["shapecond", "match", "my shapes/a.off", "b.off"]
    assert words[4:] == ["--landmarks-source", f"0,50,300,{ids[0]},{ids[2]}", "--landmarks-target",
                         f"0,50,300,{ids[1]},{ids[3]}", "-o", "map.txt", "--html", "page.html"]
    href = page.locator("a.sc-file").nth(1).get_attribute("href")
    assert unquote(href.split(",", 1)[1]) == f"0,50,300,{ids[1]},{ids[3]}\n"
    assert page.locator("a.sc-file").nth(0).get_attribute("download") == "landmarks_source.txt"
    page.locator("button.sc-undo").click()
    assert page.locator(".sc-command").get_attribute("data-target-ids") == f"0,50,300,{ids[1]}"
    page.locator(".sc-suggestion").click()  # a suggestion picks its source vertex
    assert "now click its target" in page.locator(".sc-pick-state").inner_text()
    assert page.evaluate(f"{viewer}.extra.length") == 1 + 2 + 1  # the suggestion, one pair, the pending pick
    page.locator("button.sc-copy").click()  # the clipboard answers asynchronously: wait for the page's word
    page.wait_for_function("/copied|selected/.test(document.querySelector('.sc-pick-state').innerText)",
                           timeout=10_000)
    assert not errors, errors
