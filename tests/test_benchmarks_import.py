"""Every benchmark still fits the package: it imports without running anything, without the
benchmark-only packages, and every shapecond module, function and attribute it names (at module
level, inside its functions, and in the worker code it runs in fresh interpreters) exists."""

import ast
import importlib
import os
import re
import subprocess
import sys
import types
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
MODULES = sorted(p.stem for p in BENCHMARKS.glob("*.py"))
#: needed only by benchmark functions (pyFM, gpytoolbox) or by extras a test run may lack
OPTIONAL = ("pyFM", "pyfmaps", "gpytoolbox", "playwright", "pyarrow", "dask", "distributed", "gdist")


def _ours(obj) -> bool:
    name = getattr(obj, "__name__", "") if isinstance(obj, types.ModuleType) else ""
    return name == "shapecond" or name.startswith("shapecond.") or name in MODULES


def _bindings(tree, namespace=None) -> dict:
    """Names bound to shapecond or benchmark modules and objects by the import statements of ``tree``
    (anywhere in it), on top of ``namespace``; raises if an imported module or name does not exist."""
    names = dict(namespace or {})
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] in ("shapecond", *MODULES):
                    module = importlib.import_module(alias.name)
                    if alias.asname:
                        names[alias.asname] = module
                    else:
                        names.setdefault(alias.name.split(".")[0], importlib.import_module(alias.name.split(".")[0]))
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module \
                and node.module.split(".")[0] in ("shapecond", *MODULES):
            module = importlib.import_module(node.module)
            for alias in node.names:
                if alias.name == "*":
                    continue
                if not hasattr(module, alias.name):  # a submodule not imported by its package yet
                    importlib.import_module(f"{node.module}.{alias.name}")
                names[alias.asname or alias.name] = getattr(module, alias.name)
    return names


def _stale_attributes(tree, names) -> list[str]:
    """``module.attr`` chains of ``tree`` naming something that a shapecond module or class lacks."""
    stale = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Attribute):
            continue
        chain, base = [], node
        while isinstance(base, ast.Attribute):
            chain.append(base.attr)
            base = base.value
        if not isinstance(base, ast.Name) or not _ours(names.get(base.id)):
            continue
        obj = names[base.id]
        for attr in reversed(chain):
            if not hasattr(obj, attr):
                stale.append(f"line {node.lineno}: {base.id}.{'.'.join(reversed(chain))} ({attr} missing)")
                break
            obj = getattr(obj, attr)
            if not isinstance(obj, (types.ModuleType, type)):
                break
    return sorted(set(stale))


class _Blank(dict):
    def __missing__(self, key):
        return "0"


def _worker_code(tree):
    """The Python source strings of a benchmark (code it runs in a fresh interpreter), parsed: whole,
    or filled in with placeholders (templates), or else (pieces of f-strings) their import lines."""
    for node in ast.walk(tree):
        if not (isinstance(node, ast.Constant) and isinstance(node.value, str)
                and re.search(r"^\s*(from\s+\S+\s+)?import\s", node.value, re.M)):
            continue
        for fill in (False, True):
            try:
                yield ast.parse(node.value.format_map(_Blank()) if fill else node.value)
                break
            except (SyntaxError, ValueError, KeyError, IndexError, AttributeError):
                continue
        else:
            for line in re.findall(r"^\s*((?:from\s+\S+\s+)?import\s[^;\n]+)", node.value, re.M):
                try:
                    yield ast.parse(line.strip())
                except SyntaxError:
                    continue


@pytest.fixture
def isolated(monkeypatch, capsys):
    """``benchmarks/`` on sys.path, the optional packages unimportable, subprocesses refused; the
    path and the benchmark modules restored after, nothing written into ``benchmarks/``, nothing printed."""
    for name in OPTIONAL:
        monkeypatch.setitem(sys.modules, name, None)  # import raises ImportError

    def refuse(*args, **kwargs):
        raise AssertionError(f"a subprocess at import time: {args[:1]}")

    monkeypatch.setattr(subprocess, "Popen", refuse)
    monkeypatch.setattr(os, "system", refuse)
    path = list(sys.path)
    before = {p.name: p.stat().st_mtime_ns for p in BENCHMARKS.iterdir() if p.name != "__pycache__"}
    sys.path.insert(0, str(BENCHMARKS))
    yield
    sys.path[:] = path
    for name in MODULES:
        sys.modules.pop(name, None)
    after = {p.name: p.stat().st_mtime_ns for p in BENCHMARKS.iterdir() if p.name != "__pycache__"}
    assert after == before, "importing a benchmark wrote into benchmarks/"
    out, err = capsys.readouterr()
    assert out == "" and err == "", (out, err)


@pytest.mark.parametrize("name", MODULES)
def test_a_benchmark_imports_without_side_effects_and_names_only_what_exists(isolated, name):
    env = dict(os.environ)
    module = importlib.import_module(name)
    assert dict(os.environ) == env, "importing a benchmark changed the environment"
    tree = ast.parse((BENCHMARKS / f"{name}.py").read_text())
    names = _bindings(tree, vars(module))
    assert _stale_attributes(tree, names) == []
    for code in _worker_code(tree):
        assert _stale_attributes(code, _bindings(code)) == []


def test_a_stale_name_is_found():
    """The check itself: a removed function of a shapecond module is reported, a present one is not."""
    code = ast.parse("from shapecond.shapes import metric as m\nm.build_metric_shape\nm._cache_path(m._cache_key(1))\n")
    assert _stale_attributes(code, _bindings(code)) == ["line 3: m._cache_key (_cache_key missing)",
                                                        "line 3: m._cache_path (_cache_path missing)"]
    with pytest.raises(ImportError):
        _bindings(ast.parse("from shapecond.shapes.metric import _cache_path\n"))


@pytest.mark.parametrize("no_bars", [False, True])
def test_the_remeshed_benchmarks_evaluate_code_runs_as_python(isolated, no_bars):
    """The code bench_remeshed hands a fresh interpreter parses, and every keyword it passes to
    ``sc.evaluate`` is one of its options (a wrong one was found only after an hour's run)."""
    import argparse
    import dataclasses

    from shapecond.evaluation.run import EvaluationOptions
    bench = importlib.import_module("bench_remeshed")
    a = argparse.Namespace(classes="cat,dog", methods="fps,cnbs-scale", matchers="lh05", counts="3,6",
                           jobs=1, points=400, max_targets=2, no_bars=no_bars)
    tree = ast.parse(bench.evaluate_code(Path("/data"), Path("/out"), a))
    call = next(n for n in ast.walk(tree) if isinstance(n, ast.Call) and getattr(n.func, "attr", "") == "evaluate")
    accepted = {f.name for f in dataclasses.fields(EvaluationOptions)}
    assert {k.arg for k in call.keywords} <= accepted
    assert ("error_bars" in {k.arg for k in call.keywords}) == no_bars
