"""README.md is a front page: short, its links inside the repository, no history, no typed figures."""

from __future__ import annotations

import re

from tests.docs.commands import ROOT

README = (ROOT / "README.md").read_text()
LINK = re.compile(r"\]\(([^)\s]+)\)")
#: The only places outside the repository the README may send a reader: the paper and the licence.
OUTSIDE_ALLOWED = ("https://doi.org/10.3390/smartcities3010006", "https://opensource.org/license/mit")


def test_readme_is_at_most_150_lines():
    assert len(README.splitlines()) <= 150


def test_readme_links_resolve_inside_the_repository():
    links = LINK.findall(README)
    assert any(link.startswith("docs/") for link in links), "the README links into the docs"
    for link in links:
        if link.startswith("http"):
            assert link in OUTSIDE_ALLOWED, f"README sends the reader outside the repository: {link}"
            continue
        assert (ROOT / link.split("#")[0]).exists(), f"README link to a missing file: {link}"


def test_readme_shows_the_generated_headline_figure():
    assert "docs/results/frontier_year.png" in README
    assert (ROOT / "docs/results/frontier_year.png").exists()


def test_readme_holds_no_history_and_no_typed_figures():
    for word in ("this round", "before:", "tried and not kept", "last round"):
        assert word not in README.lower()
    assert not re.search(r"\d\s?%", README), "a percentage typed into the README (figures come from results)"
    assert not re.search(r"\d+(\.\d+)?\s?(min|minutes|s)\b[^/]", README), "a duration typed into the README"
