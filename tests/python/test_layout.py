"""The package's layout: no import cycles, and every import goes down the layers (cli -> studies
-> batch / cosim -> runners -> model -> foundation), as the package docstring describes.

The import graph is read from the source (ast), counting every import: at module level, inside
functions (lazy imports) and under `if TYPE_CHECKING:`."""

from __future__ import annotations

import ast
from functools import cache
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "python" / "csfh"

LAYERS: dict[str, int] = {
    "csfh._version": 0,
    "csfh.errors": 0,
    "csfh.paths": 0,
    "csfh.output": 0,
    "csfh.progress": 0,
    "csfh.trajectory": 1,
    "csfh.plotting": 1,
    "csfh.model": 2,
    "csfh.runners": 3,
    "csfh.batch": 4,
    "csfh.cosim": 4,
    "csfh.studies": 5,
    "csfh.cli": 6,
    "csfh": 7,  # the package's face (__init__, __main__)
}
"""Rank of each part: a module may import only from parts of a lower rank, and from its own part."""


def module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def modules(root: Path) -> dict[str, Path]:
    return {module_name(p, root): p for p in sorted(root.rglob("*.py"))}


def imports(path: Path, name: str, known: set[str]) -> set[str]:
    """The package's modules that the module imports (resolved: `from . import x` is the
    submodule x where there is one)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                prefix = ".".join([*base, node.module] if node.module else base)
            else:
                prefix = node.module or ""
            targets = [f"{prefix}.{a.name}" for a in node.names] + [prefix]
        else:
            continue
        for target in targets:
            # the longest known module that the target names (a.b.c -> a.b if c is a function)
            parts = target.split(".")
            while parts and ".".join(parts) not in known:
                parts.pop()
            if parts and ".".join(parts) != name:
                out.add(".".join(parts))
    # `from .x import y` also names the package .x itself: keep only the most specific module
    return {m for m in out if not any(o.startswith(m + ".") for o in out)}


def import_graph(root: Path) -> dict[str, set[str]]:
    found = modules(root)
    known = set(found)
    return {name: imports(path, name, known) for name, path in found.items()}


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    counter = 0

    def visit(v: str) -> None:
        nonlocal counter
        index[v] = low[v] = counter
        counter += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
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

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def part(module: str) -> str:
    """The part of LAYERS a module belongs to (the longest matching prefix)."""
    parts = module.split(".")
    while ".".join(parts) not in LAYERS:
        parts.pop()
        if not parts:
            raise KeyError(f"{module} is in no part of LAYERS: add it")
    return ".".join(parts)


def test_the_cycle_finder_finds_cycles() -> None:
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": {"e"}}
    assert cycles(graph) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_the_graph_reads_relative_lazy_and_type_checking_imports(tmp_path: Path) -> None:
    pkg = tmp_path / "csfh"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "low.py").write_text("X = 1\n")
    (pkg / "sub" / "a.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .b import B\n"
    )
    (pkg / "sub" / "b.py").write_text(
        "def f():\n    from . import a\n    from ..low import X\n    return a, X\n"
    )
    graph = import_graph(pkg)
    assert graph["csfh.sub.a"] == {"csfh.sub.b"}
    assert graph["csfh.sub.b"] == {"csfh.sub.a", "csfh.low"}
    assert cycles(graph) == [["csfh.sub.a", "csfh.sub.b"]]


@cache
def package_graph() -> dict[str, set[str]]:
    return import_graph(PACKAGE)


def test_no_import_cycles() -> None:
    graph = package_graph()
    assert len(graph) > 40, "the package was not found"
    assert cycles(graph) == []


@pytest.mark.parametrize("module", sorted(package_graph()))
def test_imports_go_down_the_layers(module: str) -> None:
    mine = part(module)
    for target in sorted(package_graph()[module]):
        theirs = part(target)
        assert theirs == mine or LAYERS[theirs] < LAYERS[mine], (
            f"{module} ({mine}, layer {LAYERS[mine]}) imports {target} "
            f"({theirs}, layer {LAYERS[theirs]})"
        )
