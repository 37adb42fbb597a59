"""The import graph of the package: layers that only import downwards, and no cycle.

Read from the source with ``ast`` (every ``import`` and ``from ... import``,
those inside functions included), so that an arrow that runs back up fails here
whether or not it is executed.
"""

import ast
from pathlib import Path

import shapecond

ROOT = Path(shapecond.__file__).parent

#: Each top-level part of the package, lowest first: a module may import its own part and parts listed
#: before it.  The maths parts share a rank with one order among them; ``viz`` sits beside the maths.
LAYERS = [
    ("_version", "errors"), ("jsonable", "checks"), ("threads",), ("limits",), ("output",), ("cache",),
    ("_jit_cache", "cholesky"), ("shapes",), ("symmetry",), ("deformation",), ("selection",), ("matching",),
    ("viz",), ("parallel",), ("api",), ("evaluation", "batch"), ("cli",), ("__main__", ""),
]
RANK = {part: rank for rank, parts in enumerate(LAYERS) for part in parts}
MATHS = {"shapes", "symmetry", "deformation", "selection", "matching"}


def _modules() -> dict:
    out = {}
    for path in ROOT.rglob("*.py"):
        parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _imports(name: str, path: Path, modules: dict) -> set:
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            base = package.split(".")[: len(package.split(".")) - node.level + 1] if node.level else []
            module = ".".join(base + ([node.module] if node.module else [])) if node.level else node.module or ""
            targets = [f"{module}.{a.name}" if f"{module}.{a.name}" in modules else module for a in node.names]
        elif isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        else:
            continue
        for target in targets:
            while target not in modules and "." in target:
                target = target.rsplit(".", 1)[0]
            if target in modules and target != name:
                found.add(target)
    return found


def _part(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


GRAPH = {name: _imports(name, path, _modules()) for name, path in _modules().items()}


def test_every_part_has_a_layer():
    assert {_part(m) for m in GRAPH} <= set(RANK), {_part(m) for m in GRAPH} - set(RANK)


def back_arrows(graph) -> list:
    return [f"{a} -> {b}" for a, targets in graph.items() for b in targets
            if _part(a) != _part(b) and _part(a) != "" and RANK[_part(b)] > RANK[_part(a)]]


def test_no_arrow_runs_back_up():
    assert back_arrows(GRAPH) == []


def test_the_maths_never_imports_the_pictures_and_nothing_imports_the_command_line():
    assert [f"{a} -> {b}" for a, t in GRAPH.items() for b in t if _part(a) in MATHS and _part(b) == "viz"] == []
    assert [f"{a} -> {b}" for a, t in GRAPH.items() for b in t if _part(b) == "cli" and _part(a) not in ("cli", "__main__")] == []


def cycles(graph) -> list:
    """Strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, found, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in graph:
        if v not in index:
            visit(v)
    return found


def test_no_import_cycle():
    assert cycles(GRAPH) == []


def test_the_checker_sees_a_back_arrow_and_a_cycle():
    """The checks above can fail: a planted arrow from the maths up to the front door is one of each."""
    planted = dict(GRAPH, **{"shapecond.symmetry.score": GRAPH["shapecond.symmetry.score"] | {"shapecond.api.scores"}})
    assert back_arrows(planted) == ["shapecond.symmetry.score -> shapecond.api.scores"]
    assert any("shapecond.symmetry.score" in c and "shapecond.api.scores" in c for c in cycles(planted))
