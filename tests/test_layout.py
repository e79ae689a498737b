"""The package's architecture: a folder per stage, imports flowing one way, no cycles.

Layers, lowest first (a module may import its own package and any lower layer)::

    core -> pilot -> flight, plants -> identification -> pilots, diagnose -> pipeline -> cli

``viz`` (figures) is imported only by ``pipeline`` and ``cli``; ``humanlike`` (the
independent generator) only by tests and benchmarks, and it imports nothing but ``core``.
Every import counts, function-level ones included: they are allowed only to keep the
command line's start-up light, never to hide a cycle.
"""

from __future__ import annotations

import ast
from pathlib import Path

import hesspipe

PACKAGE = Path(hesspipe.__file__).parent

LAYER = {"core": 0, "pilot": 1, "flight": 2, "plants": 2, "identification": 3, "pilots": 4, "diagnose": 4,
         "viz": 5, "pipeline": 6, "cli": 7, "humanlike": 1}
#: Who may import viz and humanlike (besides themselves).
ONLY_FROM = {"viz": {"pipeline", "cli"}, "humanlike": set()}


def _modules() -> dict[str, Path]:
    out = {}
    for path in PACKAGE.rglob("*.py"):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _imports(name: str, path: Path, known) -> set[str]:
    """hesspipe modules that module `name` imports (any level, function bodies included)."""
    is_package = path.name == "__init__.py"
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split(".")
                if not is_package:
                    base = base[:-1]
                base = base[:len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if not target.startswith("hesspipe"):
                continue
            for alias in node.names:  # `from . import x` may name a module
                sub = f"{target}.{alias.name}"
                found.add(sub if sub in known else target)
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.startswith("hesspipe"))
    found.discard(name)
    return found


def _graph():
    known = _modules()
    return {name: _imports(name, path, known) for name, path in known.items()}


def _room(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in LAYER else None


def test_every_module_lives_in_a_room():
    loose = [m for m in _modules() if m.count(".") == 1 and _room(m) is None
             and m not in ("hesspipe.__main__",)]
    assert not loose, f"modules outside the stage packages: {loose}"


def _against(graph) -> list[str]:
    against = []
    for module, targets in graph.items():
        here = _room(module)
        if here is None:  # hesspipe/__init__, __main__: the lazy API and the entry point
            continue
        for target in targets:
            there = _room(target)
            if there is None or there == here:
                continue
            if there in ONLY_FROM and here not in ONLY_FROM[there]:
                against.append(f"{module} -> {target} ({there} only from {sorted(ONLY_FROM[there]) or 'tests'})")
            elif here == "humanlike" and there != "core":
                against.append(f"{module} -> {target} (the independent generator imports only core)")
            elif LAYER[there] >= LAYER[here] and there not in ONLY_FROM:
                against.append(f"{module} -> {target} ({here} must not import {there})")
    return sorted(against)


def test_imports_flow_one_way():
    against = _against(_graph())
    assert not against, "imports against the layers:\n" + "\n".join(against)


def _cycles(graph) -> list[list[str]]:
    # Tarjan's strongly connected components; a package's lazy __init__ imports nothing.
    index, low, stack, on_stack, cycles = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in graph:
                continue
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return cycles


def test_no_import_cycles():
    cycles = _cycles(_graph())
    assert not cycles, f"import cycles: {cycles}"


def test_the_checks_catch_violations():
    """Not vacuous: an upward import, a figure drawn by a stage, a cycle are all reported."""
    graph = {"hesspipe.pilot.x": {"hesspipe.pilots.compare"}, "hesspipe.plants.fit": {"hesspipe.viz.plants"},
             "hesspipe.humanlike.trial": {"hesspipe.pilot.hess"}, "hesspipe.pipeline.stages": {"hesspipe.viz.x"},
             "hesspipe.pilots.compare": {"hesspipe.pilot.x"}}
    assert [a.split(" ")[0] for a in _against(graph)] == [
        "hesspipe.humanlike.trial", "hesspipe.pilot.x", "hesspipe.plants.fit"]
    assert _cycles(graph) == [["hesspipe.pilot.x", "hesspipe.pilots.compare"]]


def test_no_module_is_too_long():
    long = {m: n for m, p in _modules().items() if (n := len(p.read_text().splitlines())) > 650}
    assert not long, f"modules over ~600 lines: {long}"
