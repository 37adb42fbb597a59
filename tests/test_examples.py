"""The ``Examples`` sections of the public modules run as written, and every public function has one."""

import doctest
import importlib
import inspect

import pytest

import shapecond

MODULES = ["shapecond.api.inputs", "shapecond.api.scores", "shapecond.api.problem", "shapecond.api.settings",
           "shapecond.api.matching", "shapecond.api.level", "shapecond.api.collection", "shapecond.api.params",
           "shapecond.matching.problem", "shapecond.evaluation.run", "shapecond.checks", "shapecond.jsonable", "shapecond.output",
           "shapecond.symmetry.verdict"]


@pytest.mark.parametrize("name", [pytest.param(m, marks=pytest.mark.slow)
                                  if m in ("shapecond.api.matching", "shapecond.api.collection") else m
                                  for m in MODULES])
def test_examples_run(name, tmp_path, monkeypatch):
    monkeypatch.setenv("SHAPECOND_CACHE", str(tmp_path))
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


PUBLIC_FUNCTIONS = [n for n in shapecond.__all__ if inspect.isfunction(getattr(shapecond, n))
                    or inspect.isclass(getattr(shapecond, n)) and n == "SymmetryProblem"]


@pytest.mark.parametrize("name", PUBLIC_FUNCTIONS)
def test_every_public_function_has_an_example_that_the_runs_above_cover(name):
    f = getattr(shapecond, name)
    assert "Examples\n" in (f.__doc__ or ""), f"sc.{name} has no Examples section"
    assert f.__module__ in MODULES, f"{f.__module__} is not doctested"
