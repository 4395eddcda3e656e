"""`python -m experiments.results` (`make results`): the results page and its figures, from committed files.

Writes docs/results/index.md, docs/results/frontier_year.png (also the README's headline picture)
and docs/results/frontier_night.png from the result files in experiments/results/, the figures of
the shipped OpenStreetMap street and city beside them, and the generated sections of the pages
that show those (``experiments.results.sections``). With ``--check`` it writes nothing and exits
1 naming every file that differs from what it would write (CI runs it so).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

from experiments.results.figures import frontier_png
from experiments.results.pages import results_page
from experiments.results.sections import DOCS_DIR, stale_sections, write_sections
from experiments.results.sources import NIGHT, RESULTS_DIR, YEAR
from experiments.results.street_pages import street_figures

#: docs/results/ of the project.
DOCS_RESULTS = RESULTS_DIR.parents[1] / "docs" / "results"
YEAR_FIGURE = "frontier_year.png"
NIGHT_FIGURE = "frontier_night.png"


def write_results(out_dir: Path, results_dir: Path = RESULTS_DIR) -> list[Path]:
    """Write the page and figures into ``out_dir`` from the files in ``results_dir``; the paths written."""
    year, night = YEAR.load(results_dir), NIGHT.load(results_dir)
    captions = {
        YEAR_FIGURE: f"Savings against lit on entry, a year of {year['scenario']}, every controller; "
                     "the oracle (star) is the most any controller can save with everyone lit.",
        NIGHT_FIGURE: f"Savings against lit on entry, one whole night of {night.get('scenario', 'suburban_night')}.",
    }
    out_dir.mkdir(parents=True, exist_ok=True)
    written = [frontier_png(year["controllers"], f"{year['scenario']}: a year", out_dir / YEAR_FIGURE),
               frontier_png(night["controllers"], "suburban_night: one whole night", out_dir / NIGHT_FIGURE)]
    page = out_dir / "index.md"
    page.write_text(results_page(year, night, captions))
    return [page, *written, *street_figures(out_dir, results_dir)]


def stale_files(docs_results: Path = DOCS_RESULTS, results_dir: Path = RESULTS_DIR) -> list[str]:
    """Names of the committed generated files that differ from a fresh generation (or are missing)."""
    with tempfile.TemporaryDirectory() as tmp:
        fresh = write_results(Path(tmp), results_dir)
        return [f.name for f in fresh
                if not (docs_results / f.name).exists() or (docs_results / f.name).read_bytes() != f.read_bytes()]


def main(argv: list[str] | None = None) -> int:
    """Write (or with --check, compare) the results page and figures; the exit code."""
    p = argparse.ArgumentParser(prog="python -m experiments.results", description=__doc__.splitlines()[0])
    p.add_argument("--check", action="store_true",
                   help="write nothing; exit 1 when a committed page or figure is out of date")
    args = p.parse_args(argv)
    if args.check:
        stale = [f"{DOCS_RESULTS}/{name}" for name in stale_files()] + [f"{DOCS_DIR}/{p}" for p in stale_sections()]
        if stale:
            print(f"out of date: {', '.join(stale)} (run: make results)", file=sys.stderr)
            return 1
        print(f"{DOCS_RESULTS} and the generated sections of {DOCS_DIR}: up to date")
        return 0
    for path in [*write_results(DOCS_RESULTS), *write_sections()]:
        print(f"written: {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
