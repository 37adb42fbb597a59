"""Every sub-command's ``--json`` parses from a child process: stdout holds exactly one JSON object,
with no NaN or Infinity token, whatever a compiled library prints (HiGHS printed its banner on
stdout before the JSON of ``score --upper``, which in-process tests cannot see)."""

import json

import numpy as np
import pytest

from shapecond.shapes.synthetic import plane_patch

from tests.helpers import bent, run_shapecond, write_off, write_strip_class

SMALL = "demo:sphere:subdivisions=2"  # 162 vertices


def _match_files(d):
    """A 0.55 x 1 grid and the same grid bent with shuffled vertex ids, and three corresponding landmarks."""
    g = plane_patch(n=11)
    V = g.vertices * [1.0, 0.55, 0.0]
    perm = np.random.default_rng(0).permutation(len(V))
    inv = np.argsort(perm)
    write_off(d / "src.off", V, g.faces)
    write_off(d / "tgt.off", bent(V, 0.4)[perm], inv[g.faces])
    ls = [0, 10, 11 * 7 + 3]
    return [d / "src.off", d / "tgt.off", "--landmarks-source", ",".join(map(str, ls)),
            "--landmarks-target", ",".join(str(inv[v]) for v in ls)]


#: name -> (arguments given a scratch folder, marks): every command and every ``cache`` sub-command.
CASES = {
    "score --upper": (lambda d: ["score", "demo:animal:delta=0.1", "-n", 12, "--target", "samples", "--upper"],
                      (pytest.mark.slow,)),
    "info": (lambda d: ["info", SMALL], ()),
    "sample": (lambda d: ["sample", SMALL, "-n", 12, "-o", d / "s.npz"], ()),
    "kappa": (lambda d: ["kappa", SMALL, "-n", 8, "--trials", 3], ()),
    "local": (lambda d: ["local", "demo:sphere:subdivisions=1"], ()),
    "heatmap": (lambda d: ["heatmap", SMALL, "-n", 10, "--html", d / "h.html"], (pytest.mark.slow,)),
    "landmarks": (lambda d: ["landmarks", SMALL, "-n", 12, "-k", 2], (pytest.mark.slow,)),
    "match": (lambda d: ["match", *_match_files(d), "--points", 30, "-o", d / "map.txt"], (pytest.mark.slow,)),
    "batch": (lambda d: ["batch", SMALL, "demo:sphere:subdivisions=1", "-n", 12, "--out", d / "b.csv"],
              (pytest.mark.slow,)),
    "evaluate": (lambda d: ["evaluate", write_strip_class(d / "data"), "--methods", "fps", "--matchers", "faq",
                            "--points", 12, "--out", d / "report"], (pytest.mark.slow,)),
    "demo": (lambda d: ["demo", "--points", 12, "--landmark-points", 8, "--out", d / "demo"], (pytest.mark.slow,)),
    "cache info": (lambda d: ["cache", "info"], ()),
    "cache clear": (lambda d: ["cache", "clear"], ()),
}


def _refuse(token):
    raise AssertionError(f"{token} in the JSON (infinite values are written \"inf\", missing ones null)")


def test_every_command_is_covered():
    from shapecond.cli import cli
    from shapecond.cli.cmd_cache import command as cache

    names = set(cli.list_commands(None)) - {"cache"} | {f"cache {c}" for c in cache.list_commands(None)}
    assert {name.split(" -")[0] for name in CASES} == names


@pytest.mark.parametrize("name", [pytest.param(n, marks=m) for n, (_, m) in CASES.items()])
def test_json_stdout_is_one_object(name, tmp_path, monkeypatch):
    if name.startswith("cache"):  # its own cache folder: `cache clear` must not empty the session's
        monkeypatch.setenv("SHAPECOND_CACHE", str(tmp_path / "cache"))
    code, out, err = run_shapecond(*CASES[name][0](tmp_path), "--json", timeout=120)
    assert code == 0, err
    assert out.endswith("}\n") and out.count("\n") == 1, out[:300]
    summary = json.loads(out, parse_constant=_refuse)  # one value and nothing around it, or this raises
    assert isinstance(summary, dict) and summary
