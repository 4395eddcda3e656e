"""The committed result files the results pages are made from, and the command that made each.

Each source is a small JSON file kept in experiments/results/ (a run's summary.json, a year's
year.json), copied there from the output folder of the command named beside it. To bring one up
to date, run that command and copy the file it names over the committed one; then `make results`.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

#: experiments/results/, where the committed result files live.
RESULTS_DIR = Path(__file__).resolve().parent


@dataclass(frozen=True)
class Source:
    """One committed result file.

    Parameters
    ----------
    file : str
        Its name in experiments/results/.
    command : str
        The shell command that produced it.
    produced : str
        The file the command wrote, copied to ``file``.
    what : str
        One line on what it holds.
    """

    file: str
    command: str
    produced: str
    what: str

    def load(self, results_dir: Path = RESULTS_DIR) -> dict:
        """The file's contents; ``results_dir`` is the folder holding it."""
        return json.loads((results_dir / self.file).read_text())


YEAR = Source(
    file="suburban_night_year.json",
    command="citysim year scenarios/suburban_night.yaml --out results/year",
    produced="results/year/year.json",
    what="a year of suburban_night for every controller of the scenario, the camera controllers in fast mode "
         "(900 s samples per traffic level)",
)
NIGHT = Source(
    file="demo_night_summary.json",
    command="python -m experiments.demo",
    produced="results/demo/night/summary.json",
    what="the whole night of suburban_night (22:00-06:00) in fast mode, `make demo`'s controllers",
)
SOURCES = (YEAR, NIGHT)
