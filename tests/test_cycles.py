"""No import circles between the project's modules (docs/layout.md, "Layers"; issue 44).

tests/test_layers.py checks that imports go down the layers; inside one layer two modules could still import
each other, one of them through an import inside a function. Such a circle works only as long as the lazy
import stays lazy, and it hides which of the two is the lower. This test builds the graph of every import
statement of ``urdf2links/`` and ``compare/`` (lazy ones included, read with :mod:`ast`: nothing is imported)
and fails on every strongly connected set of more than one module, naming the modules and the lines. An import
of a package counts as an import of its ``__init__``; a package's ``__init__`` importing its own modules (the
re-exports) is an edge like any other.
"""

from __future__ import annotations

import pytest
from test_layers import ALL_MODULES, SOURCES, imports_of


def import_graph(sources: dict[str, str]) -> dict[str, dict[str, int]]:
    """``{module: {imported module: first line}}`` over ``sources`` (module -> source text)."""
    graph = {}
    for module, text in sources.items():
        edges: dict[str, int] = {}
        is_package = SOURCES[module].name == "__init__.py" if module in SOURCES else False
        for line, target in imports_of(text, module, is_package=is_package):
            if target in sources and target != module:
                edges.setdefault(target, line)
        graph[module] = edges
    return graph


def circles(graph: dict[str, dict[str, int]]) -> list[list[str]]:
    """The strongly connected sets of more than one module (Tarjan), each sorted; sorted."""
    index, low, on, stack, out, counter = {}, {}, set(), [], [], [0]

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
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(out)


def _described(graph, comp) -> str:
    inside = set(comp)
    return "; ".join(f"{a} line {line} imports {b}" for a in comp for b, line in sorted(graph[a].items())
                     if b in inside)


def _project_sources() -> dict[str, str]:
    return {m: p.read_text() for m, p in SOURCES.items()}


def test_no_import_circles():
    graph = import_graph(_project_sources())
    assert len(graph) == len(SOURCES) and ALL_MODULES >= set(graph)
    found = circles(graph)
    assert found == [], "\n".join(_described(graph, c) for c in found)


@pytest.mark.parametrize("module, planted, partner", [
    # a lazy import back up the pair: the scene's data importing the plan that reads it
    ("urdf2links.scenes.functions", "def f():\n    from .plan import compile_plan\n", "urdf2links.scenes.plan"),
    # a module-level one inside compare/: the numbers' formatting importing the report that formats with it
    ("urdf2links.compare.formatting", "from .reports.report import write_report\n",
     "urdf2links.compare.reports.report"),
])
def test_a_planted_circle_is_caught(module, planted, partner):
    """Each planted line closes a circle through modules that import each other's way already."""
    sources = _project_sources()
    assert module in import_graph(sources)[partner]      # the partner's import of the module is there already
    sources[module] += "\n" + planted
    found = circles(import_graph(sources))
    assert any(module in c and partner in c for c in found), found
