"""The package's layers: no import cycles, no import of a higher layer from a lower one.

Every ``import`` and ``from ... import`` statement of every module is read
(inside functions too: a deferred import is still a dependency); imports
under ``if TYPE_CHECKING:`` are left out (they never run).  The layers, low
to high, are those of the architecture page (docs/architecture.md).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "pathfuse"

# low -> high; a module may import its own layer and the layers below it
LAYERS: list[tuple[str, ...]] = [
    ("_version", "result", "validate", "limits", "safeyaml", "shipped", "datasets", "sigterm",
     "tier"),
    ("grid", "geometry", "problem", "stats", "robot", "sweep", "costmap", "shield"),
    ("search", "field", "io", "generate", "metrics", "metrics_kernels"),
    ("planners", "api"),
    ("world",),
    ("integrations",),
    ("viz",),
    ("bench",),
    ("studies",),
    ("cli", "web", "__init__", "__main__"),
]
# inside planners/, low -> high: global planners never import a controller, and only the
# modules that run a planner (run.py, kernel_cache.py) import both sides
PLANNER_LAYERS: list[tuple[str, ...]] = [
    ("registry", "params"),
    ("globals", "base", "drive", "recovery"),
    ("controllers",),
    ("run", "kernel_cache"),
]
MAX_LINES = 600
# modules allowed above MAX_LINES, each with the reason in docs/architecture.md
LONG: set[str] = set()


def _modules() -> dict[str, Path]:
    out = {}
    for p in SRC.rglob("*.py"):
        rel = p.relative_to(SRC).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__" and len(parts) > 1:
            parts = parts[:-1]
        out["pathfuse." + ".".join(parts) if parts != ["__init__"] else "pathfuse"] = p
    return out


MODULES = _modules()


def _layer(module: str) -> int:
    name = module.split(".")[1] if "." in module else "__init__"
    for i, names in enumerate(LAYERS):
        if name in names:
            return i
    raise AssertionError(f"{module} is in no layer of LAYERS: add it")


def _resolve(module: str, node: ast.ImportFrom | ast.Import) -> list[str]:
    if isinstance(node, ast.Import):
        return [a.name for a in node.names if a.name.startswith("pathfuse")]
    if node.level:  # relative import
        base = module.split(".")[: -node.level] if not MODULES[module].name == "__init__.py" \
            else module.split(".")[: len(module.split(".")) - node.level + 1]
        target = ".".join(base + ([node.module] if node.module else []))
    else:
        target = node.module or ""
    if not target.startswith("pathfuse"):
        return []
    out = []
    for a in node.names:  # `from pathfuse import validate`: the submodule
        sub = f"{target}.{a.name}"
        out.append(sub if sub in MODULES else target)
    return out


def _imports(module: str) -> set[str]:
    tree = ast.parse(MODULES[module].read_text(encoding="utf-8"))
    skip: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            skip.update(id(n) for n in ast.walk(node))
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Import, ast.ImportFrom)) and id(node) not in skip:
            found.update(t for t in _resolve(module, node) if t != module)
    return {t if t in MODULES else t.rsplit(".", 1)[0] for t in found}


GRAPH = {m: _imports(m) for m in MODULES}


def test_every_module_is_in_a_layer():
    for m in MODULES:
        _layer(m)


@pytest.mark.parametrize("module", sorted(MODULES))
def test_no_import_of_a_higher_layer(module):
    here = _layer(module)
    upward = sorted(t for t in GRAPH[module] if _layer(t) > here)
    assert not upward, f"{module} (layer {here}) imports higher layers: {upward}"


def _planner_layer(module: str) -> int:
    name = module.split(".")[2]
    for i, names in enumerate(PLANNER_LAYERS):
        if name in names:
            return i
    raise AssertionError(f"{module} is in no layer of PLANNER_LAYERS: add it")


PLANNER_MODULES = sorted(m for m in MODULES if m.startswith("pathfuse.planners."))


def test_every_planner_module_is_in_a_planner_layer():
    for m in PLANNER_MODULES:
        _planner_layer(m)


@pytest.mark.parametrize("module", PLANNER_MODULES)
def test_no_import_of_a_higher_planner_layer(module):
    here = _planner_layer(module)
    upward = sorted(t for t in GRAPH[module]
                    if t.startswith("pathfuse.planners.") and _planner_layer(t) > here)
    assert not upward, f"{module} (planners' layer {here}) imports higher ones: {upward}"


def test_no_import_cycles():
    # Tarjan's strongly connected components over the module graph
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    cycles: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in GRAPH.get(v, ()):
            if w not in MODULES:
                continue
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            # a package importing its own submodules (its facade) is not a cycle
            comp = [c for c in comp if not any(o.startswith(c + ".") for o in comp)]
            if len(comp) > 1:
                cycles.append(sorted(comp))

    for m in sorted(MODULES):
        if m not in index:
            visit(m)
    assert not cycles, f"import cycles: {cycles}"


def test_no_module_is_too_long():
    long = {str(p.relative_to(SRC)): sum(1 for _ in p.open(encoding="utf-8"))
            for p in MODULES.values()}
    over = {k: n for k, n in long.items() if n > MAX_LINES and k not in LONG}
    assert not over, f"modules over {MAX_LINES} lines (split them, or explain in " \
                     f"docs/architecture.md and list them in LONG): {over}"
