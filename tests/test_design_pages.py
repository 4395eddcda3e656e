"""Module docstrings point to design pages that exist, and to no DESIGN.md the repository lacks."""

from __future__ import annotations

import ast
import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("citysim", "detector", "experiments")
PAGE = re.compile(r"docs/design/[a-z0-9-]+\.md")
#: A module whose docstring points to a design page says its role in a few lines; the reasoning is on the page.
MAX_LINES_WITH_PAGE = 15


def module_docstrings() -> dict[str, str]:
    out = {}
    for pkg in PACKAGES:
        for path in sorted((REPO / pkg).rglob("*.py")):
            doc = ast.get_docstring(ast.parse(path.read_text()), clean=False)
            if doc:
                out[str(path.relative_to(REPO))] = doc
    return out


def page_exists(page: str) -> bool:
    if (REPO / page).exists():
        return True
    # the architecture page is docs/ARCHITECTURE.md until the docs site moves it under docs/design/
    return page == "docs/design/architecture.md" and (REPO / "docs" / "ARCHITECTURE.md").exists()


def test_every_design_page_a_docstring_names_exists():
    missing = {path: page for path, doc in module_docstrings().items() for page in PAGE.findall(doc)
               if not page_exists(page)}  # fmt: skip
    assert missing == {}


def test_no_docstring_points_to_a_design_md_the_repository_lacks():
    assert [path for path, doc in module_docstrings().items() if "DESIGN.md" in doc] == []


def test_a_module_with_a_design_page_keeps_its_docstring_short():
    long = {path: len(doc.splitlines()) for path, doc in module_docstrings().items()
            if "Design: docs/design/" in doc and len(doc.splitlines()) > MAX_LINES_WITH_PAGE}  # fmt: skip
    assert long == {}


def test_the_page_pattern_finds_a_page_name():
    # the checks above rest on the pattern: it must find a page in a docstring's last line
    assert PAGE.findall("Design: docs/design/steep-cameras.md (Jumps)") == ["docs/design/steep-cameras.md"]


def _entry_points():
    from citysim.render.camera import CameraRenderer
    from citysim.sim.compare import run_comparison
    from citysim.sim.loop import ControllerRun
    from citysim.year.run import run_year
    from detector.detector import Detector

    # (what the docstring documents, the callable whose parameters it must name, needs a Returns section)
    return [(ControllerRun, ControllerRun.__init__, False), (ControllerRun.summary, ControllerRun.summary, True),
            (run_comparison, run_comparison, True), (Detector, Detector.__init__, False),
            (Detector.process, Detector.process, True), (CameraRenderer, CameraRenderer.__init__, False),
            (CameraRenderer.render, CameraRenderer.render, True), (run_year, run_year, True)]  # fmt: skip


def test_the_python_entry_points_document_every_parameter_numpydoc_style():
    import inspect

    missing = {}
    for documented, signed, returns in _entry_points():
        doc = inspect.getdoc(documented) or ""
        names = [p for p in inspect.signature(signed).parameters if p != "self"]
        lacking = [n for n in names if not re.search(rf"^\s*(\w+, )*{n}(, \w+)* :", doc, re.MULTILINE)]
        if names and "Parameters\n----------" not in doc:
            lacking.append("Parameters section")
        if returns and "Returns\n-------" not in doc:
            lacking.append("Returns section")
        if lacking:
            missing[documented.__qualname__] = lacking
    assert missing == {}
