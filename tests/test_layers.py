"""Layers only point down (the house style: data and skeleton math at the bottom, solvers in the middle, benchmark,
viewer and CLI on top): no module of ``posekit`` reaches, through any chain of imports, back to itself.

The graph is read from the source with :mod:`ast`, every ``import`` counted wherever it stands (a function's
import inside a function is an edge like any other: it runs the moment the function does). ``from pkg import name``
points at ``pkg.name`` when that is a module, else at ``pkg``; a package's own ``__init__`` is not counted as
imported by its submodules (Python runs it first, but it names its parts, it does not use them).
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "posekit"


def modules(package: Path = PACKAGE) -> dict:
    """``{dotted name: (path, is a package)}`` of every module under ``package``."""
    out = {}
    for path in sorted(package.rglob("*.py")):
        parts = list(path.relative_to(package.parent).with_suffix("").parts)
        is_package = parts[-1] == "__init__"
        if is_package:
            parts = parts[:-1]
        out[".".join(parts)] = (path, is_package)
    return out


def _targets(name: str, is_package: bool, node, known) -> list:
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    if node.level:
        base = name.split(".") if is_package else name.split(".")[:-1]
        base = base[:len(base) - (node.level - 1)]
        target = ".".join(base + ([node.module] if node.module else []))
    else:
        target = node.module
    return [f"{target}.{a.name}" if f"{target}.{a.name}" in known else target for a in node.names]


def import_graph(package: Path = PACKAGE) -> dict:
    """``{module: {imported module: first line}}`` of every import of a ``posekit`` module by another."""
    known = modules(package)
    top = package.name
    graph = {}
    for name, (path, is_package) in known.items():
        edges = {}
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            if not isinstance(node, (ast.Import, ast.ImportFrom)):
                continue
            for target in _targets(name, is_package, node, known):
                while target and target not in known:  # posekit.viz.studio.PosingStudio -> posekit.viz.studio
                    target = target.rpartition(".")[0]
                if target and target != name and target.split(".")[0] == top:
                    edges.setdefault(target, node.lineno)
        graph[name] = edges
    return graph


def cycles(graph: dict) -> list:
    """The strongly connected components of more than one module (Tarjan's algorithm, iterative), each sorted."""
    index, low, on_stack, stack, found = {}, {}, set(), [], []
    counter = 0
    for start in graph:
        if start in index:
            continue
        work = [(start, iter(graph[start]))]
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        on_stack.add(start)
        while work:
            v, children = work[-1]
            for w in children:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(graph[w])))
                    break
                if w in on_stack:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    component = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        component.append(w)
                        if w == v:
                            break
                    if len(component) > 1:
                        found.append(sorted(component))
    return found


def _describe(graph: dict, component: list) -> str:
    inside = set(component)
    return "; ".join(f"{m}:{line} -> {t}" for m in component for t, line in sorted(graph[m].items()) if t in inside)


def test_the_import_graph_finds_a_cycle_and_its_edges(tmp_path):
    """The checker itself: a package whose modules import each other, one of them inside a function."""
    pkg = tmp_path / "posekit"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "low.py").write_text("import numpy\n")
    (pkg / "a.py").write_text("from .low import x\nfrom .sub import b\n")
    (pkg / "sub" / "b.py").write_text("def f():\n    from ..a import g\n")
    graph = import_graph(pkg)
    assert graph["posekit.a"] == {"posekit.low": 1, "posekit.sub.b": 2} and graph["posekit.sub.b"] == {"posekit.a": 2}
    assert cycles(graph) == [["posekit.a", "posekit.sub.b"]]


def test_no_module_of_posekit_imports_itself_back():
    graph = import_graph()
    assert len(graph) > 100
    found = cycles(graph)
    assert found == [], "import cycles (module:line -> module): " + " | ".join(_describe(graph, c) for c in found)
