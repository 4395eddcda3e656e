"""The committed result files the results pages are made from, and the command that made each.

Each source is a small JSON file kept in experiments/results/ (a run's summary.json, a year's
year.json), copied there from the output folder of the command named beside it. To bring one up
to date, run that command and copy the file it names over the committed one; then `make results`.
"""

from __future__ import annotations

import json
import shutil
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

    def copy_to(self, folder: Path, results_dir: Path = RESULTS_DIR) -> None:
        """Copy the file (or folder of run files) from ``results_dir`` into ``folder``."""
        source = results_dir / self.file
        if source.is_dir():
            shutil.copytree(source, folder / self.file)
        else:
            shutil.copy(source, folder / self.file)


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

# The real street and the real city of the shipped OpenStreetMap extract (docs/guide/import.md,
# docs/guide/city.md, docs/design/city.md).
OSM_STREET = "geisslerweg"
OSM_NIGHT = Source(
    file=f"osm_{OSM_STREET}_night_fast.json",
    command=f"citysim run scenarios/osm/{OSM_STREET}.yaml --fidelity fast --duration 28800 "
            f"--controllers always_on,oracle,pir,detector_located --out runs/{OSM_STREET}_night",
    produced=f"runs/{OSM_STREET}_night/summary.json",
    what="a whole night (22:00-06:00) of the imported Geißlerweg in fast mode, its shipped sensor model",
)
OSM_FULL = Source(
    file=f"osm_{OSM_STREET}_600s_full.json",
    command=f"citysim run scenarios/osm/{OSM_STREET}.yaml --fidelity full --duration 600 "
            f"--controllers always_on,oracle,pir,detector_located --out runs/{OSM_STREET}_600s",
    produced=f"runs/{OSM_STREET}_600s/summary.json",
    what="600 s of the imported Geißlerweg from 22:00 at full fidelity: every judged frame rendered and detected",
)
CITY = Source(
    file="city_duesseldorf_wersten.json",
    command="citysim city experiments/cities/duesseldorf_wersten.yaml --workers 2 --out runs/city_wersten",
    produced="runs/city_wersten/city.json",
    what="a year of every residential street of the shipped extract with at least 4 lamps, fast mode",
)
CITY_90 = Source(
    file="city_duesseldorf_wersten_min90.json",
    command="citysim city experiments/cities/duesseldorf_wersten.yaml --workers 2 --min-lit-on-entry 0.9 "
            "--out runs/city_wersten",
    produced="runs/city_wersten/city.json",
    what="the same city ranked for controllers lighting at least 90 % of zone entries on entry (the same "
         "streets' years, resumed from the folder above: the ranking is made again, no street runs)",
)
CITY_TIMING = Source(
    file="city_duesseldorf_wersten_timing.json",
    command="python -m experiments.results.city_timing runs/w1 runs/w2 runs/b1 runs/b2 runs/c1 runs/c2 (each "
            "folder a city run under /usr/bin/time -v -o DIR.time.log; measurements A and C: --workers 1, then 2; "
            "B: 2, then 1)",
    produced="experiments/results/city_duesseldorf_wersten_timing.json",
    what="wall and CPU time and each worker's memory of the city's year with 1 and with 2 workers",
)
# The street tracker's measurements (docs/design/fusion.md, docs/guide/fusion.md): a folder of run
# files, one per scenario, start hour, seed and fidelity (``experiments.results.fusion_pages`` reads them).
FUSION = Source(
    file="fusion",
    command="python -m experiments.fusion_runs",
    produced="experiments/results/fusion/*.json",
    what="suburban_night_two_way and suburban_night, seeds 1-3, 1,200 s from 22:00 and 02:00, full fidelity and "
         "fast mode, and a whole fast night of each",
)
#: The sources of the generated sections in the guide and design pages.
PAGE_SOURCES = (OSM_NIGHT, OSM_FULL, CITY, CITY_90, CITY_TIMING, FUSION)
