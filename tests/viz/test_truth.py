"""The ground truth of a match page (``match --html --truth``): read and checked before the matching."""

import os

import numpy as np
import pytest

from shapecond.errors import InputError
from shapecond.matching.problem import truth_errors
from shapecond.shapes.io import load_geometry, write_mesh
from shapecond.shapes.synthetic import sphere
from shapecond.viz import truth as viz_truth
from tests.helpers import deadline, run_cli


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    """A 162-vertex sphere and the same sphere with its vertices in another order, with the true map, and the
    two .vts files of a 'release' whose reference points are every third source vertex."""
    d = tmp_path_factory.mktemp("pair")
    g = sphere(subdivisions=2)
    n = len(g.vertices)
    perm = np.random.default_rng(0).permutation(n)  # target vertex k is source vertex perm[k]
    inv = np.argsort(perm)                           # source vertex i is target vertex inv[i]
    write_mesh(d / "a.off", g.vertices, g.faces)
    write_mesh(d / "b.off", g.vertices[perm], inv[g.faces])
    ref = np.arange(0, n, 3)
    np.savetxt(d / "a.vts", ref + 1, fmt="%d")
    np.savetxt(d / "b.vts", inv[ref] + 1, fmt="%d")
    np.savetxt(d / "truth.txt", inv, fmt="%d")
    return d, inv, ref


def _args(d, inv, *extra):
    lms = (0, 40, 100)
    return ["match", d / "a.off", d / "b.off", "--landmarks-source", ",".join(map(str, lms)),
            "--landmarks-target", ",".join(str(inv[i]) for i in lms), "-n", "20", "--matcher", "faq",
            "--no-error-bar", "--no-cache", *extra]


def test_a_map_file_is_read_strictly(tmp_path):
    cases = {"minus_five": "0\n-5\n", "superscript": "0\n²\n", "words": "0\nleft paw\n", "two": "0 1\n",
             "fraction": "1.5\n", "empty": "", "comments_only": "# nothing\n", "huge": f"{2 ** 70}\n"}
    for name, text in cases.items():
        (tmp_path / name).write_text(text)
        with pytest.raises(InputError) as exc:
            viz_truth.read_truth(str(tmp_path / name))
        assert "\n" not in str(exc.value), name
    (tmp_path / "ok").write_text("3\n-1\n# a comment\n0  # trailing\n")
    assert viz_truth.read_truth(str(tmp_path / "ok")).tolist() == [3, -1, 0]


@pytest.mark.parametrize("special", ["fifo", "/dev/zero"])
def test_a_fifo_or_a_device_is_refused_without_reading(tmp_path, special):
    """np.loadtxt blocked on a FIFO for ever and read /dev/zero until memory ran out."""
    path = special
    if special == "fifo":
        path = str(tmp_path / "fifo")
        os.mkfifo(path)
    with deadline(10), pytest.raises(InputError, match="not a regular file"):
        viz_truth.read_truth(path)


def test_reference_truth_is_known_at_the_reference_vertices_only(pair):
    d, inv, ref = pair
    src, tgt = load_geometry(d / "a.off"), load_geometry(d / "b.off")
    truth = viz_truth.read_truth(f"{d / 'a.vts'},{d / 'b.vts'}")
    t = viz_truth.truth_map(truth, src, tgt)
    full = viz_truth.truth_map(viz_truth.read_truth(str(d / "truth.txt")), src, tgt)
    assert np.array_equal(np.flatnonzero(t >= 0), ref) and np.array_equal(t[ref], full[ref])
    wrong = np.where(np.arange(len(inv)) % 2 == 0, full, np.roll(full, 5))
    err, samples = truth_errors(src, tgt, wrong, t)
    assert set(samples.tolist()) <= set(ref.tolist()) and len(samples) == len(ref)
    right = wrong[samples] == t[samples]
    assert right.any() and (~right).any() and np.all(err[right] == 0) and np.all(err[~right] > 0)


def test_reference_truth_out_of_range_or_unequal_is_refused(pair, tmp_path):
    d, inv, ref = pair
    src, tgt = load_geometry(d / "a.off"), load_geometry(d / "b.off")
    (tmp_path / "short.vts").write_text("1\n2\n")
    with pytest.raises(InputError, match="reference points"):
        viz_truth.read_truth(f"{d / 'a.vts'},{tmp_path / 'short.vts'}")
    (tmp_path / "big.vts").write_text("".join(f"{500 + k}\n" for k in range(len(ref))))
    with pytest.raises(InputError, match="out of range"):
        viz_truth.truth_map(viz_truth.read_truth(f"{d / 'a.vts'},{tmp_path / 'big.vts'}"), src, tgt)
    with pytest.raises(InputError, match="only -1"):
        viz_truth.truth_map(np.where(inv == 3, -5, inv), src, tgt)


@pytest.mark.parametrize("bad", ["minus_five", "out_of_range", "fifo"])
def test_cli_truth_is_refused_before_the_matching(pair, tmp_path, capsys, bad):
    """Every --truth problem was found after the matching, with -o already written."""
    d, inv, _ = pair
    truth = tmp_path / bad
    if bad == "fifo":
        os.mkfifo(truth)
    else:
        truth.write_text("\n".join(map(str, np.where(np.arange(inv.size) == 7,
                                                     -5 if bad == "minus_five" else 10_000, inv))) + "\n")
    out = tmp_path / "map.txt"
    with deadline(60):
        code, _, err = run_cli(capsys, *_args(d, inv, "-o", out, "--html", tmp_path / "p.html", "--truth", truth))
    assert code == 2 and len(err.strip().splitlines()) == 1 and not out.exists(), err
    assert not (tmp_path / "p.html").exists()


@pytest.mark.slow
def test_cli_truth_of_two_vts_files_shows_the_error_at_the_reference_vertices(pair, tmp_path, capsys):
    d, inv, ref = pair
    page = tmp_path / "p.html"
    code, _, err = run_cli(capsys, *_args(d, inv, "-o", tmp_path / "map.txt", "--html", page,
                                          "--truth", f"{d / 'a.vts'},{d / 'b.vts'}"))
    assert code == 0, err
    assert f"measured at {len(ref)} source samples" in page.read_text()


def test_cli_drawing_distance_matrices_is_refused_before_the_matching(tmp_path, capsys):
    """match d.npy d.npy --doubt-ply d.ply ended in a TypeError (exit 1) after the matching."""
    P = np.random.default_rng(0).random((12, 3))
    D = np.linalg.norm(P[:, None] - P[None], axis=-1)
    np.save(tmp_path / "d.npy", D)
    for option in ("--doubt-ply", "--html", "--doubt-png"):
        code, _, err = run_cli(capsys, "match", tmp_path / "d.npy", tmp_path / "d.npy", "--landmarks-source", "0",
                               "--landmarks-target", "0", "-o", tmp_path / "m.txt", option, tmp_path / "x")
        assert code == 2 and "distance matrix" in err and not (tmp_path / "m.txt").exists(), err
