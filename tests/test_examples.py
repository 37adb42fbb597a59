"""The ``Examples`` sections of the public modules run as written."""

import doctest
import importlib

import pytest

MODULES = ["shapecond.api", "shapecond.checks", "shapecond.jsonable", "shapecond.output",
           "shapecond.symmetry.verdict"]


@pytest.mark.parametrize("name", MODULES)
def test_examples_run(name, tmp_path, monkeypatch):
    monkeypatch.setenv("SHAPECOND_CACHE", str(tmp_path))
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
