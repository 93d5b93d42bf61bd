"""The package's layout: no import cycles, and every import goes down the layers (cli -> studies
-> batch / cosim -> runners -> model -> foundation), as the package docstring describes; and no
two test modules share a name.

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
    "csfh.errors": 0,  # below the rest of the foundation: every module raises its types
    "csfh.paths": 1,
    "csfh.progress": 1,
    "csfh.interrupts": 1,
    "csfh.scenes": 1,
    "csfh.safepath": 1,  # the output folders' path checks, under output
    "csfh.output": 2,
    "csfh.trajectory": 3,
    "csfh.plotting": 3,
    "csfh.model": 4,
    "csfh.runners": 5,
    "csfh.batch": 6,
    "csfh.cosim": 6,
    "csfh.studies": 7,
    "csfh.cli": 8,
    "csfh": 9,  # the package's face (__init__, __main__)
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


# ------------------------------------------------------------------------------------------
# C: the same rule for the C sources of the FMUs and the libraries. A source file depends on
# another when its object file uses a symbol the other one defines (nm on the build's objects:
# the calls that really link, whatever the headers say); the FMI front-ends -> the
# co-simulation stepper -> the FMI-independent instance -> the model (through its table
# fmu_model) -> the solvers and the physics, never back.

C_LAYERS: dict[str, int] = {
    "fmu_src/common": 0,  # formatting shared by every layer
    "fmu_src/fmu/csfh_vartable.c": 1,  # the value tables the models describe themselves with
    "fmu_src/physics": 1,
    "fmu_src/solvers": 2,
    "fmu_src/models": 3,
    "fmu_src/harness": 4,  # libcsfh_core's ctypes API over the physics and the solvers
    "fmu_src/fmu": 4,  # the instance: life cycle, values, FMU state, model exchange
    "fmu_src/fmu/cosim": 5,  # the co-simulation stepper, its integrators and policy
    "fmu_src/fmu/fmi2": 6,
    "fmu_src/fmu/fmi3": 6,
    "fmu_src/masters": 7,  # load an FMU's binary at run time; link none of the above
}
"""Rank of each part of fmu_src/ (the longest matching folder or file): a source may use only
sources of a lower rank, and of its own part."""

BUILD = PACKAGE.parents[1] / "build"
C_TARGETS = (
    "csfh_core", "csfh_fmu_common", "csfh_fmu", "csfh_fmu3",
    "combdrive_fmu_common", "combdrive_fmu", "combdrive_fmu3", "csfh_batch",
)  # fmt: skip


def c_symbol_graph(objects: dict[str, list[Path]]) -> dict[str, set[str]]:
    """{source: the sources whose global symbols its objects use}, from `nm` (gcc-nm reads
    link-time-optimised objects too) on objects grouped by source."""
    import shutil
    import subprocess

    nm = shutil.which("gcc-nm") or shutil.which("nm")
    if nm is None:
        pytest.skip("no nm")
    defined: dict[str, set[str]] = {}
    used: dict[str, set[str]] = {}
    for source, paths in objects.items():
        for path in paths:
            out = subprocess.run([nm, str(path)], capture_output=True, text=True, check=True)
            for line in out.stdout.splitlines():
                fields = line.split()
                if len(fields) >= 2 and fields[-2] == "U":
                    used.setdefault(source, set()).add(fields[-1])
                elif len(fields) == 3 and fields[1] in "TDBRC":
                    defined.setdefault(source, set()).add(fields[2])
    owner = {sym: src for src, syms in defined.items() for sym in syms}
    return {
        src: {owner[s] for s in syms if s in owner and owner[s] != src}
        for src, syms in {**{s: set() for s in defined}, **used}.items()
    }


def build_objects() -> dict[str, list[Path]]:
    """The build's current object files of fmu_src/ by source (an object older than its source
    is left from another layout of the build and skipped)."""
    found: dict[str, list[Path]] = {}
    root = PACKAGE.parents[1]
    for target in C_TARGETS:
        for obj in sorted((BUILD / "CMakeFiles" / f"{target}.dir" / "fmu_src").rglob("*.o")):
            source = obj.relative_to(BUILD / "CMakeFiles" / f"{target}.dir").with_suffix("")
            src_path = root / source
            if src_path.is_file() and obj.stat().st_mtime >= src_path.stat().st_mtime:
                found.setdefault(str(source), []).append(obj)
    return found


def test_the_c_symbol_graph_finds_a_cycle(tmp_path: Path) -> None:
    import shutil
    import subprocess

    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    (tmp_path / "a.c").write_text("int b(void);\nint a(void) { return b(); }\n")
    (tmp_path / "b.c").write_text(
        "int a(void);\nint b(void) { return 1; }\nint c(void) { return a(); }\n"
    )
    (tmp_path / "d.c").write_text("int a(void);\nint d(void) { return a(); }\n")
    objects = {}
    for name in ("a", "b", "d"):
        subprocess.run([cc, "-c", f"{name}.c", "-o", f"{name}.o"], cwd=tmp_path, check=True)
        objects[f"{name}.c"] = [tmp_path / f"{name}.o"]
    graph = c_symbol_graph(objects)
    assert graph == {"a.c": {"b.c"}, "b.c": {"a.c"}, "d.c": {"a.c"}}
    assert cycles(graph) == [["a.c", "b.c"]]


def c_part(source: str) -> str:
    """The part of C_LAYERS a source belongs to (the longest matching prefix)."""
    parts = source.split("/")
    while "/".join(parts) not in C_LAYERS:
        parts.pop()
        if not parts:
            raise KeyError(f"{source} is in no part of C_LAYERS: add it")
    return "/".join(parts)


@cache
def c_graph() -> dict[str, set[str]]:
    objects = build_objects()
    if "fmu_src/fmu/fmu_instance.c" not in objects:
        pytest.skip(f"no current build of the FMUs in {BUILD}")
    return c_symbol_graph(objects)


def test_no_cycles_between_the_c_sources() -> None:
    graph = c_graph()
    assert len(graph) >= 30, sorted(graph)
    # the front-ends use the stepper, the stepper the instance and its integrators, those the
    # solvers, the instance the model's table
    assert "fmu_src/fmu/cosim/cosimulation.c" in graph["fmu_src/fmu/fmi2/fmi2_glue.c"]
    assert "fmu_src/fmu/cosim/cosimulation.c" in graph["fmu_src/fmu/fmi3/fmi3_glue.c"]
    assert "fmu_src/fmu/fmu_instance.c" in graph["fmu_src/fmu/cosim/cosimulation.c"]
    assert "fmu_src/solvers/rk45.c" in graph["fmu_src/fmu/cosim/integrator_rk45.c"]
    assert any(s.startswith("fmu_src/models/") for s in graph["fmu_src/fmu/fmu_instance.c"])
    assert cycles(graph) == []


def c_layer_violations(graph: dict[str, set[str]]) -> list[str]:
    """Every use of a source of the same or a higher layer in another part."""
    return [
        f"{source} ({c_part(source)}, layer {C_LAYERS[c_part(source)]}) uses {target} "
        f"({c_part(target)}, layer {C_LAYERS[c_part(target)]})"
        for source in sorted(graph)
        for target in sorted(graph[source])
        if c_part(target) != c_part(source) and C_LAYERS[c_part(target)] >= C_LAYERS[c_part(source)]
    ]


def test_the_c_sources_go_down_the_layers() -> None:
    assert c_layer_violations(c_graph()) == []


def test_a_c_source_using_a_higher_layer_is_found() -> None:
    graph = {
        "fmu_src/fmu/cosim/integration.c": {"fmu_src/fmu/fmu_log.c", "fmu_src/solvers/rk45.c"},
        "fmu_src/physics/csfh_model.c": {"fmu_src/fmu/csfh_vartable.c"},
        "fmu_src/fmu/fmu_log.c": {"fmu_src/fmu/fmu_instance.c"},
    }
    assert c_layer_violations(graph) == [
        "fmu_src/physics/csfh_model.c (fmu_src/physics, layer 1) uses "
        "fmu_src/fmu/csfh_vartable.c (fmu_src/fmu/csfh_vartable.c, layer 1)"
    ]
    with pytest.raises(KeyError, match="no part"):
        c_part("elsewhere/a.c")


def test_test_modules_have_unique_names() -> None:
    # pytest imports test modules by basename (no __init__.py under tests/), so two files of one
    # name in different folders stop the whole collection.
    tests = Path(__file__).resolve().parents[1]
    seen: dict[str, Path] = {}
    for path in sorted(tests.rglob("test_*.py")):
        assert path.name not in seen, f"{path} and {seen[path.name]} share a name"
        seen[path.name] = path
