"""report.html in a real browser: headless Chromium loads every image and logs no console error.

The page is opened with a small probe script added to a copy of it: the probe records every
<img>'s load state and every error event into the DOM, which Chromium's --dump-dom prints;
Chromium's own log (--enable-logging=stderr) gives the console messages. The same probe run
on a page with a broken image and a console error must see both, so a silent harness cannot
pass the test. Skipped with the reason when Chromium is not installed (Debian: apt-get
install chromium).
"""

from __future__ import annotations

import html
import json
import re
import shutil
import subprocess
from pathlib import Path

import cv2
import pytest

from citysim.report.html import write_report
from citysim.report.run_plots import RUN_PLOTS


def find_chromium() -> str | None:
    for name in ("chromium", "chromium-browser"):
        found = shutil.which(name)
        if found:
            return found
    return "/usr/bin/chromium" if Path("/usr/bin/chromium").exists() else None


CHROMIUM = find_chromium()
pytestmark = pytest.mark.skipif(
    CHROMIUM is None, reason="no headless Chromium (chromium on PATH or /usr/bin/chromium); "
    "Debian: apt-get install chromium"
)

#: Goes first in <head>: errors of anything loaded after it reach the listeners.
PROBE = """<script>
(() => {
  const errors = [];
  const original = console.error;
  console.error = (...args) => { errors.push(args.join(" ")); original.apply(console, args); };
  window.addEventListener("error", (e) => {
    const t = e.target;
    errors.push(e.message || ("failed to load " + ((t && (t.src || t.href)) || "?").slice(0, 80)));
  }, true);
  window.addEventListener("load", () => {
    const images = [...document.images].map((i) => ({alt: i.alt, complete: i.complete,
                                                      width: i.naturalWidth, height: i.naturalHeight}));
    const out = document.createElement("pre");
    out.id = "citysim-probe";
    out.textContent = JSON.stringify({images, errors});
    document.body.appendChild(out);
  });
})();
</script>"""
PROBE_OUT = re.compile(r'<pre id="citysim-probe">(.*?)</pre>', re.S)
#: Chromium's log line for a console message of the page, e.g.
#: [1:1:1201/194640.702259:INFO:CONSOLE:2] "boom", source: file:///tmp/x.html (2)
CONSOLE_LINE = re.compile(r":CONSOLE(?::\d+)?\] (.*)")


def open_in_chromium(page: Path, profile: Path) -> tuple[dict, list[str]]:
    """Load a copy of ``page`` with the probe; returns (probe record, console messages)."""
    text = page.read_text()
    head = text.index("<head>") + len("<head>")
    probed = page.with_name(page.stem + ".probe.html")
    probed.write_text(text[:head] + PROBE + text[head:])
    result = subprocess.run(
        [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run", f"--user-data-dir={profile}",
         "--enable-logging=stderr", "--v=0", "--virtual-time-budget=5000", "--dump-dom",
         probed.resolve().as_uri()],
        capture_output=True, text=True, timeout=180,  # a hung browser fails the test, not the suite
    )  # fmt: skip
    found = PROBE_OUT.search(result.stdout)
    assert found, f"no probe output from Chromium (exit {result.returncode}):\n{result.stderr[-2000:]}"
    console = [m.group(1) for m in map(CONSOLE_LINE.search, result.stderr.splitlines()) if m]
    return json.loads(html.unescape(found.group(1))), console


def test_report_loads_every_image_without_console_errors(run_copy, tmp_path):
    report = write_report(run_copy)
    probe, console = open_in_chromium(report, tmp_path / "profile")
    assert probe["errors"] == [] and console == []
    images = {i["alt"]: i for i in probe["images"]}
    assert set(images) == set(RUN_PLOTS)
    for name, image in images.items():
        on_disk = cv2.imread(str(run_copy / "plots" / name))
        assert image["complete"] and image["width"] > 0, name
        # the browser decoded the very PNG that is on disk
        assert (image["height"], image["width"]) == on_disk.shape[:2], name


def test_the_probe_sees_a_broken_image_and_a_console_error(tmp_path):
    page = tmp_path / "broken.html"
    page.write_text(
        '<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>x</title></head><body>'
        '<img alt="broken.png" src="data:image/png;base64,bm90IGEgcG5n">'
        '<script>console.error("something broke")</script></body></html>'
    )
    probe, console = open_in_chromium(page, tmp_path / "profile")
    assert [i["width"] for i in probe["images"]] == [0]
    assert "something broke" in probe["errors"]
    assert any("something broke" in line for line in console)
