"""``shapecond match``: map file, JSON summary, and one-line errors for bad input."""

import json

import numpy as np
import pytest

from shapecond.shapes.synthetic import plane_patch

from tests.helpers import bent, write_off
from tests.helpers import run_cli as run


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A 0.55 x 1 grid and the same grid bent, rotated and with shuffled vertex ids."""
    d = tmp_path_factory.mktemp("match")
    g = plane_patch(n=21)
    V = g.vertices * [1.0, 0.55, 0.0]
    perm = np.random.default_rng(0).permutation(len(V))       # target vertex j = source perm[j]
    inv = np.argsort(perm)
    Vb = bent(V, 0.4)
    c, s = np.cos(0.7), np.sin(0.7)
    Vb = Vb @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) + [3.0, -1.0, 2.0]
    write_off(d / "src.off", V, g.faces)
    write_off(d / "tgt.off", Vb[perm], inv[g.faces])
    return d, V, inv


@pytest.mark.parametrize("matcher", ["lh05", "faq"])
def test_match_writes_one_target_id_per_source_vertex(files, capsys, matcher):
    d, V, inv = files
    ls = [0, 20, 21 * 14 + 6]
    code, out, err = run(capsys, "match", d / "src.off", d / "tgt.off",
                         "--landmarks-source", ",".join(map(str, ls)),
                         "--landmarks-target", ",".join(str(inv[v]) for v in ls),
                         "--matcher", matcher, "--points", 80, "-o", d / f"{matcher}.txt", "--json")
    assert code == 0, err
    summary = json.loads(out)
    assert summary["matcher"] == matcher and summary["direction"] == "source to target"
    m = np.loadtxt(d / f"{matcher}.txt", dtype=np.int64)
    assert m.shape == (len(V),)
    assert all(m[v] == inv[v] for v in ls)
    # error in the flat parameter domain (the bend is an isometry)
    truth_xy = V[:, :2]
    pred_xy = V[np.argsort(inv)[m], :2]
    err_mean = np.linalg.norm(pred_xy - truth_xy, axis=1).mean()
    assert err_mean < np.sqrt(0.55 / 80), err_mean


def test_matching_two_distance_matrices(tmp_path, capsys):
    rng = np.random.default_rng(1)
    p = rng.uniform(size=(40, 2))
    D = np.linalg.norm(p[:, None] - p[None], axis=2)
    perm = rng.permutation(40)
    np.save(tmp_path / "a.npy", D)
    np.save(tmp_path / "b.npy", D[np.ix_(perm, perm)])
    inv = np.argsort(perm)
    code, _, err = run(capsys, "match", tmp_path / "a.npy", tmp_path / "b.npy",
                       "--landmarks-source", "0,1,2", "--landmarks-target",
                       ",".join(str(inv[v]) for v in (0, 1, 2)), "--matcher", "faq", "-o", tmp_path / "m.txt")
    assert code == 0, err
    assert np.mean(np.loadtxt(tmp_path / "m.txt", dtype=int) == inv) > 0.95


@pytest.mark.parametrize("ls, lt, needle", [
    ("0,1,2", "0,1", "landmark counts differ"),
    ("0,1,99999", "0,1,2", "99999"),
    ("0,1,2", "0,1,x", "is not a vertex id"),
])
def test_bad_landmarks_give_one_line_errors(files, capsys, ls, lt, needle):
    d, _, _ = files
    code, out, err = run(capsys, "match", d / "src.off", d / "tgt.off", "--landmarks-source", ls,
                         "--landmarks-target", lt, "--points", 30, "-o", d / "bad.txt")
    assert code == 2 and out == ""
    assert err.startswith("error:") and needle in err and err.count("\n") == 1
    assert not (d / "bad.txt").exists()


@pytest.mark.parametrize("matcher", ["lh05", "faq"])
def test_same_ids_samples_report_the_sample_error(files, capsys, matcher):
    """A bent copy with the same vertex ids: the target is sampled at the source's samples."""
    d, V, inv = files
    g = plane_patch(n=21)
    Vb = bent(V, 0.4)
    write_off(d / "bent.off", Vb, g.faces)
    ls = "0,20,300"
    code, out, err = run(capsys, "match", d / "src.off", d / "bent.off", "--landmarks-source", ls,
                         "--landmarks-target", ls, "--samples", "same-ids", "--matcher", matcher,
                         "--points", 60, "-o", d / f"same-{matcher}.txt", "--json")
    assert code == 0, err
    summary = json.loads(out)
    assert summary["samples"] == "same-ids"
    assert summary["exact"] == 1.0 and summary["sample_error"] == 0.0
    m = np.loadtxt(d / f"same-{matcher}.txt", dtype=np.int64)
    assert np.mean(m == np.arange(len(V))) > 0.9
    # different target landmarks contradict same-ids; a different vertex count is refused
    code, _, err = run(capsys, "match", d / "src.off", d / "bent.off", "--landmarks-source", ls,
                       "--landmarks-target", "0,20,301", "--samples", "same-ids", "--points", 60,
                       "-o", d / "x.txt")
    assert code == 2 and "target landmarks must be the source's" in err and err.count("\n") == 1
    small = plane_patch(n=19)
    write_off(d / "small.off", small.vertices, small.faces)
    code, _, err = run(capsys, "match", d / "src.off", d / "small.off", "--landmarks-source", ls,
                       "--landmarks-target", ls, "--samples", "same-ids", "--points", 60, "-o", d / "x.txt")
    assert code == 2 and "do not share their vertex order" in err and err.count("\n") == 1
    # one vertex count is not one vertex order: the same surface with its vertices renumbered is refused
    code, _, err = run(capsys, "match", d / "src.off", d / "tgt.off", "--landmarks-source", ls,
                       "--landmarks-target", ls, "--samples", "same-ids", "--points", 60, "-o", d / "x.txt")
    assert code == 2 and "do not share their vertex order" in err and err.count("\n") == 1
    assert not (d / "x.txt").exists()
    # nor is the identity their ground truth for the page's error field, refused before matching
    code, _, err = run(capsys, "match", d / "src.off", d / "tgt.off", "--landmarks-source", ls,
                       "--landmarks-target", ls, "--points", 60, "-o", d / "x.txt", "--html", d / "x.html",
                       "--truth", "same-ids")
    assert code == 2 and "--truth same-ids" in err and "vertex order" in err and err.count("\n") == 1
    assert not (d / "x.txt").exists() and not (d / "x.html").exists()


def test_the_error_bar_is_in_the_summary_and_its_doubt_field_in_a_ply(files, capsys):
    d, V, inv = files
    ls = [0, 20, 21 * 14 + 6]
    code, out, err = run(capsys, "match", d / "src.off", d / "tgt.off",
                         "--landmarks-source", ",".join(map(str, ls)),
                         "--landmarks-target", ",".join(str(inv[v]) for v in ls),
                         "--points", 80, "-o", d / "bar.txt", "--doubt-ply", d / "doubt.ply", "--doubt-png",
                         d / "doubt.png", "--html", d / "match.html", "--json")
    assert code == 0, err
    bar = json.loads(out)["error_bar"]
    # the bend is an isometry and the map right: it distorts distances far less than the sample spacing
    assert 0 < bar["epsilon_hat"] <= bar["epsilon"] < 0.01 * bar["resolution"] and bar["n_samples"] == 80
    assert bar["epsilon_source"] in ("the map's own distortion", "the landmarks' own distortion")
    assert bar["bar"] >= bar["resolution"] > 0 and bar["unit"] == "sqrt(area)"
    assert f"{bar['bar']:.3g}" in bar["text"]
    assert "--points 80" in (d / "match.html").read_text()   # the page's command repeats the run's options
    import trimesh
    ply = trimesh.load(d / "doubt.ply", process=False)
    assert len(ply.vertices) == len(V)
    assert (d / "doubt.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    page = (d / "match.html").read_text()
    assert "error bar's doubt (on the source)" in page and bar["text"] in page
    code, out, err = run(capsys, "match", d / "src.off", d / "tgt.off", "--landmarks-source", "0,20,300",
                         "--landmarks-target", "0,20,300", "--points", 80, "-o", d / "nobar.txt", "--no-error-bar",
                         "--json")
    assert code == 0 and "error_bar" not in json.loads(out)


def test_the_page_s_command_repeats_every_option_that_differs_from_its_default():
    from shapecond.api.matching import MATCH_PARAMS
    from shapecond.cli.cmd_match import _repeated_options

    o = {p.name: p.default for p in MATCH_PARAMS}
    o.update(k=10, refine=False, cache=False, largest_component=True, zoomout_step=5, n_points=80)
    assert _repeated_options(o, "same-ids") == ["--points", 80, "--k", 10, "--no-refine", "--zoomout-step", 5,
                                                "--largest-component", "--no-cache", "--truth", "same-ids"]
    o.update(matcher="faq")  # --k and --no-refine are lh05's: not passed to faq, not repeated
    assert _repeated_options(o, None) == ["--matcher", "faq", "--points", 80, "--zoomout-step", 5,
                                          "--largest-component", "--no-cache"]
