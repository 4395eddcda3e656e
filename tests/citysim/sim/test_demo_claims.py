"""What the demo scenario must show (scenarios/suburban_night.yaml), on a short stretch of its night.

A 60 km/h car driving toward the cameras is lit zone by zone before it enters under
``detector_network`` (the naive threshold's false on-time: ``test_demo_false_on``). The street, lamps, cameras, noise and walkers are the demo's; only the
car comes earlier and the run is shorter.
"""

import csv
import io
from pathlib import Path

import pytest

from citysim.config.scenario import ControllerSpec, load_scenario, override
from citysim.sim.loop import run_controller

pytestmark = pytest.mark.slow  # real simulation or footage: tens of seconds

REPO = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def short_demo():
    demo = load_scenario(REPO / "scenarios" / "suburban_night.yaml")
    car = next(a for a in demo.traffic.scripted if a.cls == "vehicle")
    assert car.speed_kmh == 60.0
    return override(demo, {
        "duration_s": 45.0,
        "traffic.classes.vehicle.rate_per_hour": 0.0,  # the scripted car is the only vehicle
        "traffic.scripted": [{**car.model_dump(), "t_s": 10.0}],
    })


def run(scenario, name):
    objects = io.StringIO()
    summary = run_controller(scenario, ControllerSpec(name=name), objects_writer=csv.writer(objects))
    rows = [r for r in csv.reader(io.StringIO(objects.getvalue()))]
    return summary, rows


def test_a_60_kmh_car_under_detector_network_crosses_no_unlit_zone(short_demo):
    summary, rows = run(short_demo, "detector_network")
    car_rows = [r for r in rows if r[2] == "vehicle"]
    assert len(car_rows) == 11, "the car crosses every zone of the 11-lamp chain"
    lags = [float(r[6]) for r in car_rows]
    assert all(r[8] == "1" for r in car_rows), f"zones not lit on entry, lags {lags}"
    assert summary["per_class"]["vehicle"]["unlit_crossings"] == 0
    assert summary["network"]["delivered"] > 0
