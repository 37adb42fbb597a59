"""Every function of the package has at most 8 parameters as called and at most 80 lines (the project's
standards; issue 33: "0 functions with more than 8 parameters as called").

Read from the source with ``ast``, nested functions and methods included: ``self`` and ``cls`` are not
passed by a caller, and ``*args``/``**kwargs`` are not counted (the parameter tables, ``api.params``,
check what a ``**options`` takes)."""

import ast
from pathlib import Path

import shapecond

ROOT = Path(shapecond.__file__).parent
MAX_PARAMETERS, MAX_LINES = 8, 80


def parameters(node) -> int:
    """The named parameters a call passes to the ``def`` ``node``."""
    names = [a.arg for a in node.args.posonlyargs + node.args.args + node.args.kwonlyargs]
    return len(names) - (names[:1] in (["self"], ["cls"]))


def oversized(source: str, where: str) -> list:
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            n, lines = parameters(node), node.end_lineno - node.lineno + 1
            if n > MAX_PARAMETERS or lines > MAX_LINES:
                found.append(f"{where}:{node.lineno} {node.name}: {n} parameters, {lines} lines")
    return found


def test_no_function_over_8_parameters_or_80_lines():
    found = [f for path in sorted(ROOT.rglob("*.py")) for f in oversized(path.read_text(), str(path.relative_to(ROOT)))]
    assert found == []


def test_the_check_sees_a_long_list_and_a_long_body():
    nine = "def f(a, b, c, d, e, f, g, h, i, **kw):\n    pass\n"
    method = "class C:\n    def m(self, a, b, c, d, e, *, f, g, h):\n        pass\n"  # 8 as called
    long = "def g():\n" + "    x = 1\n" * 80
    assert oversized(nine, "x") == ["x:1 f: 9 parameters, 2 lines"]
    assert oversized(method, "x") == []
    assert oversized(long, "x") == ["x:1 g: 0 parameters, 81 lines"]
