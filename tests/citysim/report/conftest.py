"""A real run folder for the report tests: a tiny scenario through the real simulator, once per session.

Written from a scenario file (not a mapping) so summary.json names it, as ``citysim run`` does:
the report reads the start hour and the schedule steps from it.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import yaml

from citysim.config.scenario import load_scenario
from citysim.report.run_plots import plot_run
from citysim.report.topdown import plot_coverage_map
from citysim.sim.compare import run_comparison
from citysim.world.street import build_street
from tests.citysim.streets import two_way_street

REPO = Path(__file__).resolve().parents[3]
#: the schedule dims only from 23:00: a 20 s run from 22:00 sees it save nothing
SCHEDULE_STEPS = [{"start_hour": 23, "level": 0.6}, {"start_hour": 5, "level": 1.0}]
SCENARIO = {
    "name": "tiny_plots",
    "seed": 11,
    "duration_s": 20,
    "start_hour": 22.0,
    "street": two_way_street(60),
    "lamps": {
        "count": 2, "spacing_m": 30, "first_x_m": 15, "y_m": 6.2, "pole_height_m": 5.5,
        "camera": {"file": str(REPO / "scenarios" / "cameras" / "scene_a.yaml"), "tilt_deg": 15},
    },
    "traffic": {"classes": {"pedestrian": {"rate_per_hour": 500, "crossing_fraction": 0},
                            "vehicle": {"rate_per_hour": 300}}},
    "controllers": ["always_on", {"name": "pir", "hold_s": 4},
                    {"name": "schedule", "schedule": SCHEDULE_STEPS}],
}  # fmt: skip


def write_scenario(folder: Path, **changes) -> Path:
    """SCENARIO (with top-level ``changes``) as a YAML file in ``folder``; returns its path."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "tiny_plots.yaml"
    path.write_text(yaml.safe_dump({**SCENARIO, **changes}))
    return path


@pytest.fixture(scope="session")
def scenario_file(tmp_path_factory) -> Path:
    return write_scenario(tmp_path_factory.mktemp("scenario"))


@pytest.fixture(scope="session")
def run_dir(tmp_path_factory, scenario_file) -> Path:
    """The run folder (summary.json, objects.csv, lamps.csv, plots/) of SCENARIO; not to be
    written to (tests that write take ``run_copy``)."""
    out = tmp_path_factory.mktemp("run") / "run"
    scenario = load_scenario(scenario_file)
    run_comparison(scenario, out_dir=out, scenario_file=str(scenario_file))
    # as `citysim run` does after the simulation
    plot_coverage_map(build_street(scenario), out / "plots" / "coverage.png")
    plot_run(out)
    return out


@pytest.fixture
def run_copy(run_dir, tmp_path) -> Path:
    """A copy of the run folder for a test that writes plots or report.html into it."""
    return Path(shutil.copytree(run_dir, tmp_path / "run"))
