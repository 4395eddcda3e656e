"""The docs site builds with every warning an error, and its pages render in a real browser.

`mkdocs build --strict` into a temporary folder (the reference pages are written from the code
by the build's hook); then headless Chromium opens the landing page and a guide page as files,
screenshots each, and the DOM it prints must hold the page's own text and the site's navigation.
Skipped with the reason when Chromium or MkDocs is absent (the docs extra: pip install -e '.[docs]').
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.citysim.report.test_report_browser import find_chromium
from tests.docs.commands import ROOT

CHROMIUM = find_chromium()
pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(importlib.util.find_spec("mkdocs") is None,
                       reason="MkDocs not installed (the docs extra: pip install -e '.[docs]')"),
]


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "PYTHONPATH": str(ROOT), "NO_MKDOCS_2_WARNING": "1"}
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d", str(out)], cwd=ROOT,
                          capture_output=True, text=True, timeout=600, env=env)  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]
    return out


def test_strict_build_writes_every_page(site: Path):
    for page in ("index.html", "getting-started.html", "guide/run.html", "concepts.html", "results/index.html",
                 "design/architecture.html", "reference/cli.html", "reference/scenario.html",
                 "reference/python.html", "changes.html"):
        assert (site / page).exists(), page
    cli = (site / "reference/cli.html").read_text()
    assert "citysim year" in cli and "--sample-s" in cli
    python = (site / "reference/python.html").read_text()
    assert "run_comparison" in python and "CameraRenderer" in python


def dump_dom(page: Path, profile: Path, screenshot: Path) -> str:
    """Open ``page`` in headless Chromium; its DOM after load (and a screenshot)."""
    common = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
              "--disable-component-update", "--disable-sync", "--no-first-run", f"--user-data-dir={profile}",
              "--virtual-time-budget=5000"]  # fmt: skip
    subprocess.run([*common, f"--screenshot={screenshot}", "--window-size=1280,900", page.as_uri()],
                   capture_output=True, timeout=180, check=False)  # fmt: skip
    done = subprocess.run([*common, "--dump-dom", page.as_uri()], capture_output=True, text=True, timeout=180)
    return done.stdout


@pytest.mark.skipif(CHROMIUM is None, reason="no headless Chromium (Debian: apt-get install chromium)")
@pytest.mark.parametrize(("page", "expected"), [
    ("index.html", ("citysim", "Getting started", "Guide", "Reference")),
    ("guide/run.html", ("A run", "summary.json", "objects.csv", "Concepts")),
])  # fmt: skip
def test_page_renders_in_chromium(site: Path, tmp_path, page: str, expected: tuple[str, ...]):
    shot = tmp_path / "page.png"
    dom = dump_dom(site / page, tmp_path / "profile", shot)
    assert "<nav" in dom and 'class="md-content"' in dom, "Material's layout was not rendered"
    for text in expected:
        assert text in dom, f"{page}: {text!r} not in the rendered page"
    assert shot.exists() and shot.stat().st_size > 10_000, "the screenshot is a page, not a blank"


@pytest.mark.skipif(CHROMIUM is None, reason="no headless Chromium (Debian: apt-get install chromium)")
def test_a_missing_page_is_not_taken_for_a_page(site: Path, tmp_path):
    """The browser check can fail: a file that is not there gives no Material layout."""
    dom = dump_dom(site / "no-such-page.html", tmp_path / "profile", tmp_path / "x.png")
    assert 'class="md-content"' not in dom
