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
    assert "nnik.implementations.mlp.export" in graph and "nnik.implementations.mlp.cost.predict" in graph
    cycle = find_cycle(graph)
    assert cycle is None, " -> ".join(cycle)


def test_the_graph_sees_lazy_imports_and_the_checker_finds_circles():
    graph = import_graph()
    # a lazy import inside a function is an edge (the estimator's sweep trains through the pipeline)
    assert "nnik.pipeline" in graph["nnik.bench.mlp_cost.sweep"]
    assert "nnik.implementations.mlp.fastc" in graph["nnik.implementations.mlp.export"]
    looped = {k: set(v) for k, v in graph.items()}
    looped["nnik.implementations.mlp.fastc"].add("nnik.implementations.mlp.export")
    assert find_cycle(looped) is not None


def test_prediction_does_not_reach_the_pipeline():
    graph = import_graph()
    seen, todo = set(), ["nnik.implementations.mlp.cost.predict", "nnik.implementations.mlp.cost"]
    while todo:
        v = todo.pop()
        if v not in seen:
            seen.add(v)
            todo.extend(graph[v])
    assert "nnik.pipeline" not in seen
    assert not any(m.startswith("nnik.bench") for m in seen)  # calibrate, sweep, measure: nnik.bench.mlp_cost


def test_fastc_does_not_import_export():
    assert "nnik.implementations.mlp.export" not in import_graph()["nnik.implementations.mlp.fastc"]


# ---- layers: nnik/ imports only downward ----------------------------------------------------------
#
# A room is a top-level module or package of nnik/, with three splits: each implementation family's
# folder is a room of its own ("implementations.<family>", minus its family.py), the families'
# interface (the registry nnik.implementations, every <family>/family.py and the MLP's
# outputs.py) is the room
# "implementations", and the estimator's calibration tools (which train through the pipeline)
# are "estimate.tools". Rooms stand on layers, from the ground up; a module imports only from its
# own layer or below (lazy imports count, as above):
LAYERS = (
    ("errors", "progress", "emit", "files"),  # errors; progress bars (on a terminal only); jinja environment,
    # C text helpers, the AVR asm statement; outdir, atomic writes, hashes, pick state
    ("machine", "dynamics"),  # scenario, params, actuator, domain, data, synth, kinematics, reference,
    # [motion]/[dynamics]; the axes' spring-damper model, input shapers, precompensation
    ("targets",),  # toolchains, simulators, sizes, the host build, the float IK (speed reference)
    # what the families are made of: the shared contract (base, problem, verify, accuracy,
    # c_common, avr_asm) and each family's fit, integer model, C, fast paths and cost
    ("implementations.shared", "implementations.mlp", "implementations.poly", "implementations.lut",
     "implementations.hybrid", "implementations.servo"),  # servo: the closed loop's controllers (no family)
    ("estimate",),  # the MLP's cost model: it predicts cycles from the C the MLP emits
    ("implementations",),  # the families as the pipeline sees them: <family>/family.py and the registry
    ("selection",),
    ("pipeline",),
    ("search", "firmware"),
    ("report", "job"),  # the job: its stages in their order (nnik/job/__init__.py), over the firmware's model
    ("commands",),  # one module per command (nnik job today; the rest as cli.py is split)
    ("cli",),  # cli.py and __main__.py (python -m nnik)
    ("bench", "estimate.tools"),
)
# Known upward edges, each with its reason. Nothing else may import upward.
UPWARD_ALLOWED: set[tuple[str, str]] = set()  # nothing may import upward
FAMILY_FOLDERS = ("mlp", "poly", "lut", "hybrid")
ESTIMATE_TOOLS = ("sweep", "calibrate", "measure", "search_check", "__main__")


def room(mod: str) -> str:
    parts = mod.split(".")[1:]
    if not parts:
        return "errors"  # nnik/__init__: imports nothing of its own
    if parts == ["__main__"]:
        return "cli"  # python -m nnik: the CLI's entry
    if parts[0] == "implementations":
        # calibrate runs its family end to end; the MLP's outputs (model.pt, c/mlp/ and their
        # verification, which the estimator predicts) are its family as the pipeline writes it
        if len(parts) == 1 or parts[-1] in ("family", "calibrate", "outputs"):
            return "implementations"
        if parts[1] in FAMILY_FOLDERS or (NNIK / "implementations" / parts[1]).is_dir():  # a folder, its __init__ too
            return f"implementations.{parts[1]}"
        return "implementations.shared"
    if parts[0] == "estimate" and len(parts) > 1 and parts[1] in ESTIMATE_TOOLS:
        return "estimate.tools"
    return parts[0]


def layer(mod: str) -> int:
    r = room(mod)
    for i, rooms in enumerate(LAYERS):
        if r in rooms:
            return i
    raise AssertionError(f"{mod}: room {r!r} is on no layer (add it to LAYERS)")


def room_graph(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    rooms: dict[str, set[str]] = {}
    for a, bs in graph.items():
        rooms.setdefault(room(a), set())
        for b in bs:
            if room(a) != room(b) and (a, b) not in UPWARD_ALLOWED:
                rooms[room(a)].add(room(b))
    return rooms


def levels(graph: dict[str, set[str]]) -> int:
    """The longest import chain, counted in nodes (an acyclic graph)."""
    memo: dict[str, int] = {}

    def depth(v: str) -> int:
        if v not in memo:
            memo[v] = 1 + max((depth(w) for w in graph.get(v, ())), default=0)
        return memo[v]

    return max(depth(v) for v in graph)


def test_layers_only_import_downward():
    graph = import_graph()
    up = sorted(f"{a} (layer {layer(a)} {room(a)}) -> {b} (layer {layer(b)} {room(b)})"
                for a, bs in graph.items() for b in bs if layer(b) > layer(a) and (a, b) not in UPWARD_ALLOWED)
    assert not up, "imports that go up a layer:\n" + "\n".join(up)
    stale = [e for e in UPWARD_ALLOWED if e[1] not in graph.get(e[0], ())]
    assert not stale, f"UPWARD_ALLOWED lists edges that no longer exist: {stale}"


def test_rooms_have_no_circle_and_at_most_14_levels():
    rooms = room_graph(import_graph())
    cycle = find_cycle(rooms)
    assert cycle is None, " -> ".join(cycle)
    assert levels(rooms) <= 14, levels(rooms)  # 14: the commands layer between report and cli, the job's stages
    # between the firmware and the commands


def test_the_top_of_nnik_is_small_and_no_module_is_long():
    top = [p.name for p in NNIK.glob("*.py")]
    assert len(top) <= 10, sorted(top)
    long = {str(p.relative_to(NNIK)): n for p in NNIK.rglob("*.py") if (n := len(p.read_text().splitlines())) > 500}
    assert not long, long


def test_the_layer_check_sees_an_upward_import():
    graph = {k: set(v) for k, v in import_graph().items()}
    graph["nnik.machine.data"].add("nnik.pipeline")
    assert any(layer(b) > layer(a) for a, bs in graph.items() for b in bs if (a, b) not in UPWARD_ALLOWED)
    assert find_cycle(room_graph(graph)) is not None
