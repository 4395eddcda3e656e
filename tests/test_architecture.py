"""The house rules of docs/design/architecture.md, checked on the import graph and the code's size.

Every import counts, function-local ones too (they are still dependencies, only deferred):
no circles; ``detector`` never imports ``citysim`` or ``experiments``; the detector's runtime
never imports its training package; each citysim stage imports only the stages below it.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("citysim", "detector", "experiments")

#: What each citysim stage may import (besides itself and detector); the order is the pipeline's.
ALLOWED_STAGES = {
    "config": set(),
    "world": {"config"},
    "render": {"config", "world"},
    "control": {"config", "world"},
    "metrics": {"config", "world", "control"},
    "fast": {"config", "world", "control", "metrics"},
    "sim": {"config", "world", "render", "control", "metrics", "fast"},
    "sweep": {"config", "world", "control", "metrics", "fast", "sim"},
    # a year is a table of runs through sim; its report section reads year.json, not the package
    "year": {"config", "world", "control", "metrics", "fast", "sim"},
    # a city is many streets' years on Dask; its report reads city.json, not the package
    "city": {"config", "world", "control", "metrics", "fast", "sim", "year", "gis"},
    "report": {"config", "world", "render", "control", "metrics", "fast", "sim", "sweep"},
    # the importer writes scenario files; it never builds or runs a world
    "gis": {"config"},
}
#: Compiled per-pixel kernels may be long: numba cannot call helpers that cheaply.
LONG_MODULES_ALLOWED = {"citysim/render/kernels.py"}
MAX_MODULE_LINES = 400
MAX_FUNCTION_LINES = 80
MAX_POSITIONAL_PARAMETERS = 8


def module_name(path: Path) -> str:
    parts = list(path.relative_to(REPO).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def source_files() -> list[Path]:
    return sorted(p for pkg in PACKAGES for p in (REPO / pkg).rglob("*.py"))


def imports_of(path: Path, modules: set[str]) -> set[str]:
    """The project modules ``path`` imports anywhere in its body (``from a import b`` counts
    module ``a.b`` when that is a module, else ``a``)."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [f"{node.module}.{a.name}" if f"{node.module}.{a.name}" in modules else node.module
                     for a in node.names]  # fmt: skip
        else:
            continue
        for name in names:
            while name and name not in modules:  # "a.b.c" of a non-module c: its module "a.b"
                name = name.rpartition(".")[0]
            if name:
                found.add(name)
    return found


@pytest.fixture(scope="module")
def graph() -> dict[str, set[str]]:
    files = source_files()
    modules = {module_name(p) for p in files}
    return {module_name(p): imports_of(p, modules) - {module_name(p)} for p in files}


def strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components with more than one module (the import circles)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    circles: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
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
                circles.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return circles


def test_the_checker_finds_a_circle():
    assert strongly_connected({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_import_circles(graph):
    assert strongly_connected(graph) == []


def test_detector_stands_alone(graph):
    bad = {m: sorted(d for d in deps if not d.startswith("detector")) for m, deps in graph.items()
           if m.startswith("detector")}  # fmt: skip
    assert {m: d for m, d in bad.items() if d} == {}


def test_detector_runtime_never_imports_training(graph):
    # the CLI's `train` command trains; general_model trains only when the shipped model file
    # was written by another scikit-learn (tests/detector check that loading it imports no
    # training code)
    trainers = {"detector.train", "detector.__main__", "detector.general_model"}
    bad = {m: sorted(d for d in deps if d.startswith("detector.train")) for m, deps in graph.items()
           if m.startswith("detector") and not any(m == t or m.startswith(t + ".") for t in trainers)}  # fmt: skip
    assert {m: d for m, d in bad.items() if d} == {}


def test_citysim_never_imports_experiments(graph):
    bad = {m: sorted(d for d in deps if d.startswith("experiments")) for m, deps in graph.items()
           if m.startswith("citysim")}  # fmt: skip
    assert {m: d for m, d in bad.items() if d} == {}


def stage_of(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if parts[0] == "citysim" and len(parts) > 1 and parts[1] in ALLOWED_STAGES else None


def test_each_stage_imports_only_the_stages_below_it(graph):
    bad = {}
    for module, deps in graph.items():
        stage = stage_of(module)
        if stage is None:
            continue
        allowed = ALLOWED_STAGES[stage] | {stage}
        above = sorted(d for d in deps if d.startswith("citysim") and stage_of(d) not in allowed)
        if above:
            bad[module] = above
    assert bad == {}


def test_the_stage_rule_would_catch_an_upward_import():
    upward = {"citysim.config.scenario": {"citysim.world.agents"}}
    assert stage_of("citysim.world.agents") not in ALLOWED_STAGES["config"]
    assert any(stage_of(d) not in ALLOWED_STAGES[stage_of(m)] | {stage_of(m)} for m, ds in upward.items() for d in ds)


def test_every_package_init_says_what_it_owns():
    for init in (REPO / "citysim").rglob("__init__.py"):
        doc = ast.get_docstring(ast.parse(init.read_text()))
        assert doc and len(doc) > 40, f"{init.relative_to(REPO)} needs a docstring saying what it owns"


def test_modules_and_functions_stay_small():
    """No module over 400 lines (compiled kernels aside), no function over ~80 lines, and no
    function with more than 8 positional parameters outside the numba kernels."""
    problems = []
    for path in source_files():
        rel = path.relative_to(REPO).as_posix()
        text = path.read_text()
        if len(text.splitlines()) > MAX_MODULE_LINES and rel not in LONG_MODULES_ALLOWED:
            problems.append(f"{rel}: {len(text.splitlines())} lines")
        for node in ast.walk(ast.parse(text)):
            if not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                continue
            compiled = any("jit" in ast.unparse(d) for d in node.decorator_list)
            if compiled:
                continue
            # a docstring is not code: an entry point's numpydoc Parameters/Returns do not count
            first = node.body[0]
            doc_lines = first.end_lineno - first.lineno + 1 if ast.get_docstring(node) is not None else 0
            length = node.end_lineno - node.lineno + 1 - doc_lines
            positional = [a.arg for a in node.args.posonlyargs + node.args.args if a.arg not in ("self", "cls")]
            if length > MAX_FUNCTION_LINES:
                problems.append(f"{rel}:{node.lineno} {node.name}: {length} lines")
            if len(positional) > MAX_POSITIONAL_PARAMETERS:
                problems.append(f"{rel}:{node.lineno} {node.name}: {len(positional)} positional parameters")
    assert problems == []
