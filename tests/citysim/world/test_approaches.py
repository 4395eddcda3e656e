"""The street before the lamp chain's end zones: without one, not even the oracle lights an entry."""

import csv
import io
from pathlib import Path

import pytest

from citysim.config.motion import MAX_SPEED_MPS
from citysim.config.scenario import ControllerSpec, load_scenario, scenario_from_mapping
from citysim.report.table import comparison_table
from citysim.sim.loop import run_controller
from citysim.world.approaches import approach_needed_m, approaches
from tests.citysim.sim.test_loop import tiny_scenario

SCENARIOS = Path(__file__).resolve().parents[3] / "scenarios"


def car_from_the_start(lamps_x_m: list[float]) -> dict:
    """A 60 km/h car driving in at x = 0 along the tiny street's +x lane, past lamps at ``lamps_x_m``."""
    base = tiny_scenario()
    return tiny_scenario(
        duration_s=12.0,
        lamps={**base["lamps"], "x_m": lamps_x_m},
        traffic={"scripted": [{"cls": "vehicle", "t_s": 1.0, "speed_kmh": 60.0, "direction": 1, "path": 0}]},
        controllers=["always_on", "oracle"],
    )


def oracle_entries(scenario) -> list[list[str]]:
    objects = io.StringIO()
    run_controller(scenario, ControllerSpec(name="oracle"), objects_writer=csv.writer(objects))
    return list(csv.reader(io.StringIO(objects.getvalue())))


def test_without_an_approach_not_even_the_oracle_lights_the_first_zone_on_entry():
    # lamps at 10 and 30 m: zones 0-20 and 20-40 m, the first starting where the car appears
    scenario = scenario_from_mapping(car_from_the_start([10.0, 30.0]))
    assert approaches(scenario).short_ends == ["start"]
    rows = sorted(oracle_entries(scenario), key=lambda r: int(r[3]))
    assert [r[8] for r in rows] == ["0", "1"]  # first zone dark on entry, the next lit


def test_with_an_approach_the_oracle_lights_every_entry():
    # lamps at 20 and 40 m: zones 10-30 and 30-50 m, 10 m of street before the first
    scenario = scenario_from_mapping(car_from_the_start([20.0, 40.0]))
    found = approaches(scenario)
    assert found.first_m == 10.0 and found.short_ends == []
    rows = oracle_entries(scenario)
    assert len(rows) == 2 and all(r[8] == "1" for r in rows)


def test_the_approach_needed_is_what_a_60_kmh_car_covers_in_the_oracles_lead():
    scenario = scenario_from_mapping(tiny_scenario())
    lum = scenario.lamps.luminaire
    lead_s = (1 - lum.dim_level) * lum.ramp_up_s + 2 / 30
    assert approach_needed_m(scenario) == pytest.approx(MAX_SPEED_MPS * lead_s)
    assert 4.0 < approach_needed_m(scenario) < 6.0  # 16.7 m/s for 0.31 s


@pytest.mark.parametrize("name", ["suburban_night", "suburban_night_two_way", "rural_road", "city_street_day"])
def test_every_planners_street_has_approaches(name):
    found = approaches(load_scenario(SCENARIOS / f"{name}.yaml"))
    assert found.short_ends == [], found


def test_the_table_says_when_an_end_has_no_approach():
    summary = {"scenario": "s", "duration_s": 60.0, "seed": 1, "controllers": {}, "approaches": {"first_m": 0.0, "last_m": 30.0, "needed_m": 5.1,
                                                 "short_ends": ["start"]}}  # fmt: skip
    text = comparison_table(summary)
    assert "the street's start (0 m)" in text and "at least 5.1 m" in text
    summary["approaches"]["short_ends"] = []
    assert "note:" not in comparison_table(summary)
