"""The parameter table of ``match`` (``api.params``, ``api.matching.MATCH_PARAMS``): its defaults are the
maths' own, every bad value of a row is refused by ``sc.match`` and ``shapecond match`` alike, naming the
parameter, before any work, and the dense stage's rows reach the dense stage."""

import dataclasses
import inspect

import numpy as np
import pytest

import shapecond as sc
from shapecond.api.matching import MATCH_PARAMS, match_options
from shapecond.api.params import IntRange, Param, check_keywords
from shapecond.errors import InputError
from shapecond.matching import pipeline
from shapecond.matching.pipeline import MatchOptions
from shapecond.matching.problem import MatchProblem
from shapecond.matching.seeded import FAQOptions
from shapecond.matching.spectral import LH05Options
from shapecond.matching.zoomout import ZoomOutOptions

from tests.cli.bad_inputs import MATCH_ARGV, match_option_cases
from tests.helpers import run_cli

#: The options object each ``feeds`` of ``MATCH_PARAMS`` names ("call": the call's own settings).
OBJECTS = {"match": MatchOptions, "zoomout": ZoomOutOptions, "lh05": LH05Options, "faq": FAQOptions}
SOURCE = "demo:animal:resolution=0.08"
TARGET = "demo:animal:resolution=0.08,delta=0.1"
LM = [0, 50, 300, 600]


@pytest.mark.parametrize("p", MATCH_PARAMS, ids=lambda p: f"{p.feeds[0]}.{p.name}")
def test_every_row_feeds_a_field_whose_default_it_keeps(p):
    if p.feeds[0] == "call":
        assert match_options({})[1][p.name] == p.default
        return
    declared = {f.name: f.default for f in dataclasses.fields(OBJECTS[p.feeds[0]])}
    assert p.feeds[1] in declared and declared[p.feeds[1]] == p.default


def test_match_signature_defaults_are_the_table_s():
    rows = {p.name: p for p in MATCH_PARAMS}
    shown = [q for q in inspect.signature(sc.match).parameters.values() if q.default is not q.empty]
    assert shown and all(rows[q.name].default == q.default for q in shown)


def test_the_defaults_build_the_maths_default_options():
    opts, flags = match_options({})
    assert opts == MatchOptions()
    assert flags == {"error_bar": True, "largest_component": False, "suggest": 0, "force": False}
    faq, _ = match_options({"matcher": "faq", "seed": 7})
    assert faq.matcher_options == FAQOptions(seed=7) and faq.seed == 7


@pytest.mark.parametrize("cls,p,value,own", match_option_cases(cli=False), ids=lambda x: x if isinstance(x, str) else "")
def test_sc_match_refuses_a_bad_value_naming_it_before_loading(cls, p, value, own):
    with pytest.raises(InputError) as exc:  # the shapes do not exist: a check after loading would say so
        sc.match("no/such/source.off", "no/such/target.off", [0], [0], **{**own, p.name: value})
    message = str(exc.value)
    assert "\n" not in message and p.name in message and "no such file" not in message


@pytest.mark.parametrize("cls,p,value,own", match_option_cases(cli=True), ids=lambda x: x if isinstance(x, str) else "")
def test_shapecond_match_refuses_a_bad_value_naming_it(cls, p, value, own, capsys, tmp_path):
    argv = ["match", "no/such/source.off", *MATCH_ARGV[2:-1], str(tmp_path / "map.txt")]
    code, out, err = run_cli(capsys, *argv, *[w for k, m in own.items() for w in (f"--{k}", m)], p.cli[0], value)
    lines = err.strip().splitlines()
    assert code == 2 and out == "" and len(lines) == 1 and lines[0].startswith("error: ")
    assert p.cli[0] in err and "no such file" not in err and not (tmp_path / "map.txt").exists()


def test_an_unknown_keyword_names_the_nearest_or_its_matcher():
    table = (Param("k", IntRange(1, 10), 5, "Neighbours.", ("lh05", None)), Param("step", IntRange(1), 1, "Step."))
    assert check_keywords(table, {"k": "3"}, "f") == {"k": 3, "step": 1}
    with pytest.raises(InputError, match=r"f\(\) got unknown option 'stp' \(did you mean 'step'\?\)"):
        check_keywords(table, {"stp": 2}, "f")
    with pytest.raises(InputError, match="unknown option 'k' for matcher 'faq' \\(k is an option of lh05\\)"):
        check_keywords(table, {"k": 2}, "f", off=("lh05",), context=" for matcher 'faq'")


# --- the dense stage's rows reach the dense stage ---------------------------------------------------------

@pytest.fixture
def zoomout_spy(monkeypatch):
    """The ZoomOutOptions every dense stage of the test ran with."""
    seen, real = [], pipeline.zoomout

    def spy(*args):
        seen.append(args[-1])
        return real(*args)

    monkeypatch.setattr(pipeline, "zoomout", spy)
    return seen


GIVEN = {"zoomout_k_start": 8, "zoomout_k_end": 60, "zoomout_step": 4, "zoomout_subsample_factor": 5,
         "zoomout_sigma": 0.07}
EXPECTED = ZoomOutOptions(k_start=8, k_end=60, step=4, subsample_factor=5, sigma=0.07)


@pytest.mark.slow
def test_dense_stage_options_from_sc_match_reach_zoomout_and_change_the_map(zoomout_spy):
    default = sc.match(SOURCE, TARGET, LM, LM, n_points=40, error_bar=False)
    assert zoomout_spy == [ZoomOutOptions()]
    tuned = sc.match(SOURCE, TARGET, LM, LM, n_points=40, error_bar=False, **GIVEN)
    assert zoomout_spy[1:] == [EXPECTED]
    assert np.mean(tuned.map != default.map) > 0.01  # 2.1 % of the 942 vertices move (a near-isometric pair)


def test_dense_stage_options_from_the_command_line_reach_zoomout(zoomout_spy, capsys, tmp_path):
    words = [w for name, v in GIVEN.items() for w in ("--" + name.replace("_", "-"), v)]
    code, _, err = run_cli(capsys, "match", SOURCE, TARGET, "--landmarks-source", "0,50,300,600", "--landmarks-target",
                           "0,50,300,600", "-n", 40, "--no-error-bar", "-o", tmp_path / "map.txt", *words)
    assert code == 0, err
    assert zoomout_spy == [EXPECTED]
    zoomout_spy.clear()  # the zoomout matcher runs the dense stage twice (4 landmarks: two starts), both tuned
    code, _, err = run_cli(capsys, "match", SOURCE, TARGET, "--landmarks-source", "0,50,300,600", "--landmarks-target",
                           "0,50,300,600", "--matcher", "zoomout", "--no-error-bar", "-o", tmp_path / "z.txt",
                           "--zoomout-k-start", 8)
    assert code == 0, err
    assert zoomout_spy == [ZoomOutOptions(k_start=8)] * 2


def test_default_keywords_give_the_maths_default_map():
    """``sc.match`` with no option is the maths run with their own defaults (``MatchOptions()``, as the
    evaluation's protocols build them), map for map."""
    got = sc.match(SOURCE, TARGET, LM, LM, n_points=40, error_bar=False)
    src, tgt = sc.load(SOURCE), sc.load(TARGET)
    problem = MatchProblem(src, tgt, src.to_internal(LM), tgt.to_internal(LM), MatchOptions(n_points=40))
    assert np.array_equal(got.map[src.ids], tgt.ids[problem.vertex_map])
