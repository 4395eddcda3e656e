"""The committed results page and figures are exactly what `make results` makes of the committed files."""

from __future__ import annotations

import json

from experiments.results.__main__ import DOCS_RESULTS, stale_files, write_results
from experiments.results.sources import PAGE_SOURCES, SOURCES


def test_committed_results_are_current():
    assert stale_files() == [], "run `make results` and commit docs/results/"


def test_a_changed_result_file_makes_the_page_stale(tmp_path):
    """The check can fail: one controller's saving changed in a copy of the result files."""
    results = tmp_path / "results"
    results.mkdir()
    for source in SOURCES + PAGE_SOURCES:
        source.copy_to(results)
    year_file = results / SOURCES[0].file
    year = json.loads(year_file.read_text())
    year["controllers"]["oracle"]["savings_vs_always_on"] += 0.01
    year_file.write_text(json.dumps(year))
    assert set(stale_files(DOCS_RESULTS, results)) >= {"index.md", "frontier_year.png"}


def test_the_page_names_each_source_command_and_figure(tmp_path):
    page = write_results(tmp_path)[0].read_text()
    for source in SOURCES:
        assert f"`{source.command}`" in page and source.file in page
    assert "![" in page and "frontier_year.png" in page and "make results" in page


def test_same_files_give_the_same_bytes(tmp_path):
    first = [p.read_bytes() for p in write_results(tmp_path / "a")]
    second = [p.read_bytes() for p in write_results(tmp_path / "b")]
    assert first == second


def test_no_share_of_an_oracle_that_saves_nothing_on_the_page():
    from experiments.results.pages import night_table

    def row(kind: str, saving: float) -> dict:
        return {"controller": kind, "savings_vs_always_on": saving, "lit_on_entry_rate": 1.0}

    for oracle_saving in (-0.061, 0.004):  # at or below zero, and a few tenths of a percent
        lines = night_table({"controllers": {"oracle": row("oracle", oracle_saving), "pir": row("pir", 0.171)}})
        assert lines[-1].startswith("| pir | 17.1 % | - |")
    lines = night_table({"controllers": {"oracle": row("oracle", 0.342), "pir": row("pir", 0.171)}})
    assert lines[-1].startswith("| pir | 17.1 % | 50 % |")
