"""nnik/ flows one way: no module imports, directly or through others, a module that imports it.

The graph is read with ast from every nnik/**/*.py, with the imports inside functions counted
too (a lazy import is still a dependency, it only hides the circle until run time).
"""

from __future__ import annotations

import ast
from pathlib import Path

NNIK = Path(__file__).resolve().parents[1] / "nnik"


def _modules() -> dict[str, Path]:
    mods = {}
    for p in NNIK.rglob("*.py"):
        parts = list(p.relative_to(NNIK.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        mods[".".join(parts)] = p
    return mods


def _owner(name: str, mods: dict[str, Path]) -> str | None:
    """The module a dotted name lives in (nnik.a.b.func -> nnik.a.b)."""
    while name and name not in mods:
        name = name.rpartition(".")[0]
    return name or None


def import_graph() -> dict[str, set[str]]:
    mods = _modules()
    graph: dict[str, set[str]] = {m: set() for m in mods}
    for mod, path in mods.items():
        package = mod if path.name == "__init__.py" else mod.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            names: list[str] = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    up = package.split(".")[:len(package.split(".")) - node.level + 1]
                    base = ".".join(up + ([base] if base else []))
                # `from pkg import sub` loads pkg/__init__ and pkg.sub; `from mod import name` loads mod
                subs = [f"{base}.{a.name}" for a in node.names if f"{base}.{a.name}" in mods]
                names = subs + [base]
            for name in names:
                target = _owner(name, mods) if name.startswith("nnik") else None
                # a package's own __init__ runs before its submodules: not an edge back up
                if target and target != mod and not mod.startswith(target + "."):
                    graph[mod].add(target)
    return graph


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import circle as [a, b, ..., a], or None."""
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    path: list[str] = []

    def visit(v: str) -> list[str] | None:
        state[v] = 1
        path.append(v)
        for w in sorted(graph[v]):
            if state.get(w) == 1:
                return path[path.index(w):] + [w]
            if w not in state and (found := visit(w)):
                return found
        path.pop()
        state[v] = 2
        return None

    for v in sorted(graph):
        if v not in state and (found := visit(v)):
            return found
    return None


def test_nnik_has_no_import_circle():
    graph = import_graph()
    assert "nnik.implementations.mlp.export" in graph and "nnik.estimate.predict" in graph
    cycle = find_cycle(graph)
    assert cycle is None, " -> ".join(cycle)


def test_the_graph_sees_lazy_imports_and_the_checker_finds_circles():
    graph = import_graph()
    # a lazy import inside a function is an edge (the estimator's sweep trains through the pipeline)
    assert "nnik.pipeline" in graph["nnik.estimate.sweep"]
    assert "nnik.implementations.mlp.fastc" in graph["nnik.implementations.mlp.export"]
    looped = {k: set(v) for k, v in graph.items()}
    looped["nnik.implementations.mlp.fastc"].add("nnik.implementations.mlp.export")
    assert find_cycle(looped) is not None


def test_prediction_does_not_reach_the_pipeline():
    graph = import_graph()
    seen, todo = set(), ["nnik.estimate.predict", "nnik.estimate"]
    while todo:
        v = todo.pop()
        if v not in seen:
            seen.add(v)
            todo.extend(graph[v])
    assert "nnik.pipeline" not in seen
    assert not any(m.startswith("nnik.estimate.") and m.rpartition(".")[2] in ("calibrate", "sweep", "measure")
                   for m in seen)


def test_fastc_does_not_import_export():
    assert "nnik.implementations.mlp.export" not in import_graph()["nnik.implementations.mlp.fastc"]
