"""The stack's import graph, read from the source: no import cycle runs between packages, and the layers
that were once tangled stay apart (the commander and the position controller, the launch profiles and the
scenarios). Imports inside functions count too: they close a cycle as surely, only later."""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import stack

ROOT = Path(stack.__file__).resolve().parent


def module_files() -> dict[str, Path]:
    files = {}
    for path in ROOT.rglob("*.py"):
        parts = ("stack", *path.relative_to(ROOT).with_suffix("").parts)
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        files[name] = path
    return files


MODULES = module_files()


def imported(path: Path) -> Iterator[str]:
    """The stack modules a file imports (``from stack.x import y`` names ``stack.x.y`` when that is a module)."""
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [node.module, *(f"{node.module}.{alias.name}" for alias in node.names)]
        else:
            continue
        yield from (name for name in names if name in MODULES)


GRAPH = {name: set(imported(path)) - {name} for name, path in MODULES.items()}


def package(module: str) -> str:
    return module.split(".")[1] if module.count(".") else module


def cycles(graph: dict[str, set[str]]) -> list[set[str]]:
    """The strongly connected components of more than one node (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack_: list[str] = []
    on_stack: set[str] = set()
    found: list[set[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack_.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = set()
            while True:
                w = stack_.pop()
                on_stack.discard(w)
                component.add(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(component)

    for v in graph:
        if v not in index:
            visit(v)
    return found


def package_imports(importer: str) -> dict[str, list[str]]:
    """For each package ``importer``'s modules import, which of its modules do."""
    uses: dict[str, list[str]] = {}
    for module, targets in GRAPH.items():
        if package(module) == importer:
            for target in targets:
                if package(target) != importer:
                    uses.setdefault(package(target), []).append(module)
    return uses


def test_the_graph_is_read():
    assert "stack.commander.land_detector" in GRAPH["stack.commander.module"]
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [{"a", "b", "c"}]


def test_no_import_cycle_runs_between_packages():
    between = [sorted(c) for c in cycles(GRAPH) if len({package(m) for m in c}) > 1]
    assert between == []


def test_the_commander_does_not_import_the_position_controller():
    assert package_imports("commander").get("posctl", []) == []


def test_launch_files_are_found_without_the_supervisor():
    assert GRAPH["stack.launch_files"] <= {"stack.names"}  # the closest name of a mission; nothing of the supervisor
    scenarios = [m for m in MODULES if m.startswith("stack.scenario.")]
    flying_files = ["stack.scenario.mission_box", "stack.scenario.plane_mission"]
    assert sorted(m for m in scenarios if "stack.launch_files" in GRAPH[m]) == flying_files
    for m in flying_files:
        assert "stack.supervisor.profile" not in GRAPH[m]
