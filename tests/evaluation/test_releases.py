"""The releases as they ship: flat and split layouts, pairs lists, mirror images, and their bad inputs."""

import shutil

import numpy as np
import pytest

from shapecond.errors import InputError
from shapecond.evaluation import EvaluationOptions, evaluate_dataset
from shapecond.evaluation.datasets import check_layout, find_classes, pair_groups
from shapecond.shapes.pairs_list import read_pairs
from shapecond.evaluation.report import markdown, pooled, write_report
from tests.evaluation.test_remeshed import H, W, _strip, _write


def _flat(root, names=("strip0", "strip4", "strip9", "plate1", "plate2"), mirror=True):
    """A flat release: NAME.off beside corres/NAME.vts and NAME.sym.vts (strips and plates: two classes)."""
    u, v = np.meshgrid(np.linspace(0.04, 0.96, 12) * W, np.linspace(0.04, 0.96, 7) * H)
    ref = np.column_stack([u.ravel(), v.ravel()])
    mirrored = np.column_stack([W - ref[:, 0], ref[:, 1]])
    args = {"strip0": (21,), "strip4": (27, 0.5, 1), "strip9": (17, 0.35, 2), "plate1": (19, None, 3),
            "plate2": (23, 0.6, 4)}
    for name in names:
        V, F, uv = _strip(*args[name])
        _write(root / "tmp", name, V, F, uv, ref)
        shutil.move(root / "tmp" / "shapes" / f"{name}.off", root / f"{name}.off")
        (root / "corres").mkdir(exist_ok=True)
        shutil.move(root / "tmp" / "corres" / f"{name}.vts", root / "corres" / f"{name}.vts")
        if mirror:
            near = np.argmin(((uv[None] - mirrored[:, None]) ** 2).sum(-1), axis=1)
            (root / "corres" / f"{name}.sym.vts").write_text("".join(f"{i + 1}\n" for i in near))
    shutil.rmtree(root / "tmp")
    return root


def test_a_flat_release_is_read_with_its_classes_by_name(tmp_path):
    root = _flat(tmp_path / "vtx_5k")
    found = find_classes(root)
    assert list(found) == ["plate", "strip"]
    assert [p.stem for p in found["strip"].shapes] == ["strip0", "strip4", "strip9"]
    cls = found["strip"]
    assert cls.layout == "remeshed" and cls.vts_path(cls.null) == root / "corres" / "strip0.vts"
    assert cls.mirror_path(cls.null) == root / "corres" / "strip0.sym.vts"
    assert list(find_classes(tmp_path)) == ["plate", "strip"]   # the release folder holding vtx_5k/


def test_a_split_release_is_one_class_when_names_are_not_class_and_number(tmp_path):
    root = _flat(tmp_path / "rel", names=("strip0", "strip4", "strip9"), mirror=False)
    (root / "shapes_train").mkdir()
    (root / "shapes_test").mkdir()
    shutil.move(root / "strip0.off", root / "shapes_train" / "cow_alpha.off")
    shutil.move(root / "strip4.off", root / "shapes_train" / "horse.off")
    shutil.move(root / "strip9.off", root / "shapes_test" / "fox-05.off")
    for old, new in (("strip0", "cow_alpha"), ("strip4", "horse"), ("strip9", "fox-05")):
        shutil.move(root / "corres" / f"{old}.vts", root / "corres" / f"{new}.vts")
    (cls,) = find_classes(root).values()
    assert cls.name == "rel" and cls.null.stem == "fox-05" and len(cls.shapes) == 3   # lowest number first
    check_layout(cls)


def test_a_pairs_list_groups_the_pairs_by_source_across_classes(tmp_path):
    root = _flat(tmp_path / "vtx_5k")
    (tmp_path / "test_pairs.txt").write_text("strip0\tstrip4\nstrip0\tplate2\n# a comment\n\nplate1 strip9\n")
    pairs = read_pairs(tmp_path / "test_pairs.txt")
    assert pairs == [("strip0", "strip4"), ("strip0", "plate2"), ("plate1", "strip9")]
    groups = pair_groups(root, pairs)
    assert {k: [p.stem for p in g.shapes] for k, g in groups.items()} == {
        "strip0": ["strip0", "strip4", "plate2"], "plate1": ["plate1", "strip9"]}


@pytest.mark.slow
def test_the_listed_pairs_are_evaluated_with_flips_and_the_pooled_table(tmp_path):
    _flat(tmp_path / "vtx_5k")
    ev = evaluate_dataset(tmp_path, options=EvaluationOptions(methods=("fps",), matchers=("zoomout",), n_points=60, pairs=(("strip0", "plate2"), ("plate1", "strip9")), n_landmarks=4, counts=(3,), error_bars=False, scores=False))
    assert all(d["scores"] == {} and d["scale"] == {} for d in ev.landmarks)   # the matchings alone
    assert sorted((r.cls, r.target, r.n_landmarks) for r in ev.records) == [
        ("plate1", "strip9", 3), ("plate1", "strip9", 4), ("strip0", "plate2", 3), ("strip0", "plate2", 4)]
    spacing = max(W / 16, H / 16) / np.sqrt(W * H)
    for r in ev.records:
        assert r.error_area < 0.75 * spacing and r.flipped == 0.0, r   # .sym.vts gives the mirror images
    table = pooled(ev.records)
    assert table[("fps", 4, "zoomout")]["n"] == 2 and table[("fps", 4, "zoomout")]["failed"] == 0
    assert "All matchings pooled" in markdown(ev) and "2 listed pairs" in markdown(ev)
    write_report(ev, tmp_path / "out")  # without scores there is no score axis: no such figure, no failure
    assert (tmp_path / "out" / "results.json").exists() and (tmp_path / "out" / "report.html").exists()
    assert not (tmp_path / "out" / "score_vs_error_remeshed.png").exists()


def test_faqs_objective_reaches_the_matchings_and_is_recorded(tmp_path, monkeypatch):
    """``faq_objective`` (``evaluate --faq-objective``) is the objective of every FAQ matching of the run,
    written in its settings; the other matchers keep their own options; a bad name is refused in one line."""
    from shapecond.evaluation import protocols
    from shapecond.evaluation.protocols import MatchingSetup

    setup = MatchingSetup((3,), ("faq", "lh05"), faq_objective="local")
    assert setup.options("faq").matcher_options.objective == "local"
    assert setup.options("lh05") == MatchingSetup((3,), ("lh05",)).options("lh05")
    assert MatchingSetup((3,), ("faq",)).options("faq") == protocols.MatchOptions(matcher="faq", dense="zoomout")
    seen = []
    real = protocols.MatchProblem.__init__
    monkeypatch.setattr(protocols.MatchProblem, "__init__",
                        lambda self, *a, **k: seen.append(a[4].matcher_options.objective) or real(self, *a, **k))
    _flat(tmp_path / "vtx_5k")
    ev = evaluate_dataset(tmp_path, options=EvaluationOptions(
        methods=("fps",), matchers=("faq",), n_points=40, pairs=(("strip0", "plate2"),), n_landmarks=3, counts=(3,),
        error_bars=False, scores=False, dense="nearest", faq_objective="local"))
    assert seen and set(seen) == {"local"} and ev.settings["faq_objective"] == "local"
    with pytest.raises(InputError, match="unknown FAQ objective 'Local'"):
        EvaluationOptions(faq_objective="Local")


def test_bad_releases_and_pairs_are_refused_in_one_line(tmp_path):
    root = _flat(tmp_path / "vtx_5k")
    (tmp_path / "p.txt").write_text("strip0 nothere\n")
    with pytest.raises(InputError, match="nothere"):
        pair_groups(root, read_pairs(tmp_path / "p.txt"))
    for text, match in (("strip0\n", "two shape names"), ("strip0 strip0\n", "itself"), ("# none\n", "no pairs")):
        (tmp_path / "p.txt").write_text(text)
        with pytest.raises(InputError, match=match):
            read_pairs(tmp_path / "p.txt")
    (root / "corres" / "strip4.sym.vts").write_text("1\n2\n")          # a .sym.vts of another length
    with pytest.raises(InputError, match="strip4.sym.vts"):
        check_layout(find_classes(root)["strip"])
    (root / "corres" / "strip4.vts").write_text("1\n2\n")              # a .vts of another length
    with pytest.raises(InputError, match="unequal reference counts"):
        check_layout(find_classes(root)["strip"])
    (root / "corres" / "strip4.vts").unlink()                          # a .sym.vts without its .vts
    with pytest.raises(InputError, match="strip4.vts"):
        find_classes(root)
    empty = tmp_path / "empty"
    (empty / "corres").mkdir(parents=True)
    with pytest.raises(InputError, match="no shapes"):
        find_classes(empty)
    with pytest.raises(InputError, match="either classes or a pairs list"):
        evaluate_dataset(tmp_path, options=EvaluationOptions(classes=("strip",), pairs=(("strip0", "strip4"),)))


def test_two_shapes_of_one_name_and_unreadable_entries_are_refused_not_dropped(tmp_path):
    import os

    root = _flat(tmp_path / "vtx_5k", names=("strip0", "strip4"))
    shutil.copy(root / "strip4.off", root / "strip4.ply")
    with pytest.raises(InputError, match="two shapes named 'strip4'"):
        find_classes(root)
    (root / "strip4.ply").unlink()
    os.mkfifo(root / "strip9.off")
    with pytest.raises(InputError, match="strip9.off: not a regular file"):
        find_classes(root)
    (root / "strip9.off").unlink()
    (root / "loop.off").symlink_to(root / "loop.off")
    with pytest.raises(InputError, match="loop.off"):
        find_classes(root)


def test_the_cli_refuses_a_bad_pairs_file_or_release_in_one_line_and_writes_nothing(tmp_path, capsys):
    from tests.helpers import run_cli

    root = _flat(tmp_path / "vtx_5k", names=("strip0", "strip4"))
    out = tmp_path / "report"
    (tmp_path / "pairs.txt").write_text("strip0 strip9\n")
    for args, match in (((root, "--pairs", tmp_path / "pairs.txt"), "strip9"),
                        ((root, "--pairs", tmp_path / "none.txt"), "none.txt"),
                        ((root, "--pairs", tmp_path / "pairs.txt", "--classes", "strip"), "not both")):
        code, stdout, err = run_cli(capsys, "evaluate", *args, "--out", out, "--methods", "fps", "-n", 20)
        assert code == 2 and match in err and err.count("\n") == 1 and stdout == "", err
        assert not out.exists()
