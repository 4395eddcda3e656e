"""The generated sections of the guide and design pages (the shipped OpenStreetMap street and city)
are what `make results` makes of the committed files, and the check can fail."""

from __future__ import annotations

import json
import shutil

import pytest

from experiments.results.city_timing import parse_time_log
from experiments.results.sections import (
    DOCS_DIR,
    SECTIONS,
    begin_marker,
    end_marker,
    replace_section,
    stale_sections,
)
from experiments.results.sources import CITY_90, CITY_TIMING, PAGE_SOURCES, RESULTS_DIR
from experiments.results.street_pages import timing_section


def _copies(tmp_path):
    """Copies of the result files and of the pages with sections, to change one without touching the repo."""
    results, docs = tmp_path / "results", tmp_path / "docs"
    results.mkdir()
    for source in PAGE_SOURCES:
        source.copy_to(results)
    for section in SECTIONS:
        (docs / section.page).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(DOCS_DIR / section.page, docs / section.page)
    return results, docs


def test_committed_sections_are_current():
    assert stale_sections() == [], "run `make results` and commit the pages it names"


def test_a_changed_city_result_makes_the_city_page_stale(tmp_path):
    results, docs = _copies(tmp_path)
    assert stale_sections(docs, results) == []
    city = json.loads((results / CITY_90.file).read_text())
    city["ranking"][0]["payback_years"] = 123.4
    (results / CITY_90.file).write_text(json.dumps(city))
    assert stale_sections(docs, results) == ["guide/city.md"]


def test_the_sections_name_their_source_commands():
    for section in SECTIONS:
        body = section.body(RESULTS_DIR)
        assert any(f"`{source.command}`" in body for source in PAGE_SOURCES), section.name


def test_only_the_text_between_the_markers_is_replaced():
    page = f"intro\n{begin_marker('x')}\nold table\n{end_marker('x')}\noutro\n"
    assert replace_section(page, "x", "new table") == (
        f"intro\n{begin_marker('x')}\n\nnew table\n\n{end_marker('x')}\noutro\n")
    with pytest.raises(ValueError, match="guide/a.md: no generated section 'y'"):
        replace_section(page, "y", "body", "guide/a.md")


GNU_TIME_LOG = """\
\tCommand being timed: "citysim city c.yaml --workers 2 --out d"
\tUser time (seconds): 100.50
\tSystem time (seconds): 4.25
\tPercent of CPU this job got: 150%
\tElapsed (wall clock) time (h:mm:ss or m:ss): 1:10.05
\tMaximum resident set size (kbytes): 204800
"""


def test_a_gnu_time_report_is_read():
    facts = parse_time_log(GNU_TIME_LOG)
    assert facts["wall_s"] == pytest.approx(70.05)
    assert facts["user_s"] + facts["system_s"] == pytest.approx(104.75)
    assert facts["max_rss_kb"] == 204800 and facts["workers"] == 2
    with pytest.raises(ValueError, match="wall_s"):
        parse_time_log("User time (seconds): 1.0")


def _run(workers, wall_s):
    return {"workers": workers, "wall_s": wall_s, "cpu_s": 100.0, "command_peak_rss_mb": 200.0,
            "load_average_1_5_15_min_before": [1.0, 2.0, 3.0],
            "per_worker": [{"worker": 1, "streets": [{"street": "a", "wall_s": 1.0, "cpu_s": 1.0, "peak_rss_mb": 250.0}]}]}


@pytest.mark.parametrize(("wall_1_s", "wall_2_s", "wall_verdict", "scaling_verdict"), [
    (200.0, 120.0, "met", "met"),      # 1.67x = 83 % of linear, 120 s <= 300 s
    (200.0, 140.0, "met", "missed"),   # 1.43x = 71 %
    (700.0, 400.0, "missed", "met"),   # 1.75x, but 400 s > 300 s
])
def test_the_timing_section_says_met_or_missed(tmp_path, wall_1_s, wall_2_s, wall_verdict, scaling_verdict):
    (tmp_path / CITY_TIMING.file).write_text(json.dumps({"runs": [_run(1, wall_1_s), _run(2, wall_2_s)]}))
    line = [line for line in timing_section(tmp_path).splitlines() if line.startswith("- A:")][0]
    assert f"target of 300 s: **{wall_verdict}**." in line
    assert f"of linear against the target of 80 %: **{scaling_verdict}**." in line
