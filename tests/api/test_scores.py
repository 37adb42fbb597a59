"""The parameter tables of ``score``, ``landmarks``, ``heatmap``, ``kappa`` and ``metric_shape``
(``api.scores.SCORE_PARAMS``, ``LANDMARK_PARAMS``, ``HEATMAP_PARAMS``, ``KAPPA_PARAMS``,
``api.inputs.METRIC_SHAPE_PARAMS``; the command ``sample`` is ``metric_shape``'s): every
bad value of a row is refused by the Python function and the command alike, naming the parameter, before any
work; the commands' options and defaults are the table's; the options several functions share are one ``Param``."""

import dataclasses
import inspect

import click
import pytest

import shapecond as sc
from shapecond.api.matching import MATCH_PARAMS
from shapecond.api.options import ShapeOptions
from shapecond.api.params import (BACKEND, CACHE, EFFORT, FORCE, LARGEST_COMPONENT, POINTS, SEED, SHAPE_PARAMS,
                                  REQUIRED, Ids, cli_key)
from shapecond.api.inputs import METRIC_SHAPE_PARAMS
from shapecond.api.scores import HEATMAP_PARAMS, KAPPA_PARAMS, KAPPA_POINTS, LANDMARK_PARAMS, SCORE_PARAMS
from shapecond.cli.cmd_heatmap import command as heatmap_command
from shapecond.cli.cmd_kappa import command as kappa_command
from shapecond.cli.cmd_landmarks import command as landmarks_command
from shapecond.cli.cmd_sample import command as sample_command
from shapecond.cli.cmd_score import command as score_command
from shapecond.errors import InputError

from tests.cli.bad_inputs import table_cases
from tests.helpers import run_cli

MISSING = "no/such/shape.off"  # a check after loading would say "no such file"
#: Per table: the Python function, its other arguments, its command and the command's other words.
TABLES = {"score": (SCORE_PARAMS, sc.score, {}, score_command, ["score", MISSING, "--no-cache"]),
          "landmarks": (LANDMARK_PARAMS, sc.landmarks, {"k": 2, "method": "fps"}, landmarks_command,
                        ["landmarks", MISSING, "-k", "2", "--method", "fps", "--no-cache"]),
          "heatmap": (HEATMAP_PARAMS, sc.heatmap, {}, heatmap_command, ["heatmap", MISSING, "--png", "OUT.png"]),
          "kappa": (KAPPA_PARAMS, sc.kappa, {}, kappa_command, ["kappa", MISSING]),
          "metric_shape": (METRIC_SHAPE_PARAMS, sc.metric_shape, {}, sample_command,
                           ["sample", MISSING, "-o", "OUT.npz"])}
CASES = [(name, *case) for name in TABLES for case in table_cases(TABLES[name][0], cli=False)]
CLI_CASES = [(name, *case) for name in TABLES for case in table_cases(TABLES[name][0], cli=True)]


def test_the_tables_cover_every_keyword_of_the_signatures():
    for table, function, *_ in TABLES.values():
        names = {p.name for p in table}
        signature = inspect.signature(function).parameters
        assert set(signature) - {"x", "options"} <= names
        for q in signature.values():
            if q.name in names:  # the signature's defaults are the table's
                row = next(p for p in table if p.name == q.name)
                assert (row.default is REQUIRED) == (q.default is q.empty)
                assert q.default is q.empty or q.default == row.default, q.name


@pytest.mark.parametrize("name,cls,p,value", CASES, ids=[f"{c[0]} {c[1]}" for c in CASES])
def test_the_function_refuses_a_bad_value_naming_it_before_loading(name, cls, p, value):
    _, function, others, *_ = TABLES[name]
    with pytest.raises(InputError) as exc:
        function(MISSING, **{**others, p.name: value})
    message = str(exc.value)
    assert "\n" not in message and p.name in message and "no such file" not in message


@pytest.mark.parametrize("name,cls,p,value", CLI_CASES, ids=[f"{c[0]} {c[1]}" for c in CLI_CASES])
def test_the_command_refuses_a_bad_value_naming_it(name, cls, p, value, capsys):
    code, out, err = run_cli(capsys, *TABLES[name][4], p.cli[0], value)
    lines = err.strip().splitlines()
    assert code == 2 and out == "" and len(lines) == 1 and lines[0].startswith("error: ")
    assert p.cli[0] in err and "no such file" not in err


def test_every_table_command_has_cases_of_each_kind():
    kinds = {(name, type(p.constraint).__name__) for name, _, p, _ in CLI_CASES}
    for kind in ("IntRange", "FloatRange", "Choice", "Ids", "File"):
        assert ("score", kind) in kinds and ("landmarks", kind) in kinds, kind


@pytest.mark.parametrize("name", TABLES)
def test_the_command_s_options_and_defaults_are_the_table_s(name):
    table, _, _, command, _ = TABLES[name]
    options = {o.name: o for o in command.params if isinstance(o, click.Option)}
    for p in (p for p in table if p.cli):
        o = options.pop(p.name)
        assert o.opts + o.secondary_opts == [w for d in p.cli for w in d.split("/")], p.name
        assert o.help.startswith(p.help), p.name
        if p.default is REQUIRED:
            assert o.required, p.name
        elif isinstance(p.constraint, Ids):  # no ids given: None on the command line, () in Python
            assert p.check(o.default, p.name) == p.check(p.default, p.name) == []
        else:
            assert o.default == p.default and type(o.default) is type(p.default), p.name
    assert set(options) <= {"epsilon_from", "witness_png", "scale_witness_png", "html", "png", "ply", "up", "output",
                            "as_json"}


def test_the_flags_give_the_python_values(capsys, monkeypatch):
    """``--exact`` gives True (not given: "auto"), ``--no-cache`` cache=False, ``--no-scores`` scores=False."""
    seen = {}

    def spy(name):
        def record(input_spec, **kw):
            seen[name] = kw
            raise InputError("stop")
        return record

    import shapecond.cli.cmd_landmarks as cmd_landmarks
    import shapecond.cli.cmd_score as cmd_score

    monkeypatch.setattr(cmd_score, "score", spy("score"))
    monkeypatch.setattr(cmd_landmarks, "landmarks", spy("landmarks"))
    run_cli(capsys, "score", MISSING, "--no-cache", "--exact", "--landmarks", "3,1")
    assert (seen["score"]["exact"], seen["score"]["cache"], seen["score"]["landmarks"]) == (True, False, [3, 1])
    run_cli(capsys, "score", MISSING)
    assert (seen["score"]["exact"], seen["score"]["cache"], seen["score"]["landmarks"]) == ("auto", True, [])
    run_cli(capsys, "landmarks", MISSING, "-k", "3", "--no-scores", "--geodesic-backend", "fmm")
    kw = seen["landmarks"]
    assert (kw["k"], kw["method"], kw["scores"], kw["backend"], kw["n_points"]) == (3, "cnbs", False, "fmm", None)


def test_an_unknown_keyword_names_the_nearest():
    with pytest.raises(InputError, match=r"score\(\) got unknown option 'efort' \(did you mean 'effort'\?\)"):
        sc.score(MISSING, efort="quick")
    with pytest.raises(InputError, match=r"unknown option 'user_landmark' for method 'fps' "
                                         r"\(did you mean 'user_landmarks'\?\)"):
        sc.landmarks(MISSING, 2, "fps", user_landmark=[1])


def test_a_method_s_own_option_passes_the_table():
    """CNBS's ``resolve_fraction`` is no row of the table but an option of the method: the call goes on to load."""
    with pytest.raises(InputError, match="no such file"):
        sc.landmarks(MISSING, 2, "cnbs", resolve_fraction=0.5)
    with pytest.raises(InputError, match="resolve fraction must lie in"):
        sc.landmarks("demo:sphere:subdivisions=1", 2, "cnbs", 8, cache=False, resolve_fraction=-1.0)


def test_the_shape_rows_are_the_shape_options_fields():
    assert sorted(p.name for p in SHAPE_PARAMS) == sorted(f.name for f in dataclasses.fields(ShapeOptions))
    assert ShapeOptions(**{p.name: p.default for p in SHAPE_PARAMS}) == ShapeOptions()


def test_the_shared_options_are_one_param_in_every_table():
    """``seed``, ``backend``, ... are the same object in match's, score's and landmarks' tables; ``n_points`` is
    ``POINTS`` everywhere, with match's own default (it always samples 400) and kappa's shown default (8 free
    samples of a mesh: ``KAPPA_POINTS``, the same constraint)."""
    for table in (MATCH_PARAMS, SCORE_PARAMS, LANDMARK_PARAMS, HEATMAP_PARAMS, KAPPA_PARAMS, METRIC_SHAPE_PARAMS):
        rows = {p.name: p for p in table}
        for shared in (SEED, BACKEND, CACHE, LARGEST_COMPONENT, FORCE):
            assert rows[shared.name] is shared
        assert (rows["n_points"] is POINTS or rows["n_points"] == POINTS.with_default(400)
                or rows["n_points"] == dataclasses.replace(POINTS, cli_default=KAPPA_POINTS.cli_default))
    for table in (SCORE_PARAMS, LANDMARK_PARAMS, HEATMAP_PARAMS, KAPPA_PARAMS, METRIC_SHAPE_PARAMS):
        assert all(p in table for p in SHAPE_PARAMS) and (POINTS in table or KAPPA_POINTS in table)
    assert KAPPA_POINTS in KAPPA_PARAMS and "8" in KAPPA_POINTS.cli_default
    assert all(EFFORT in table for table in (SCORE_PARAMS, LANDMARK_PARAMS, HEATMAP_PARAMS))


def test_the_older_commands_name_the_shared_options_as_before():
    """sample, kappa, heatmap and batch read the shape options under the command line's names (batch stores them)."""
    assert [cli_key(p) for p in (POINTS, *SHAPE_PARAMS) if p.cli] == [
        "points", "metric", "geodesic_backend", "seed", "largest_component", "no_cache", "target", "target_factor",
        "symmetry_map", "force"]
