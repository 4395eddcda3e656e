"""Sensor models are keyed by camera and environment, and shared by the streets that match."""

from __future__ import annotations

from pathlib import Path

import pytest

from citysim.city import models
from citysim.city.models import camera_key, city_models
from citysim.city.streets import StreetJob
from citysim.config.scenario import load_scenario, override
from citysim.config.year import YearSpec

REPO = Path(__file__).resolve().parents[3]
YEAR = YearSpec(latitude_deg=51.0, longitude_deg=7.0, timezone="Europe/Berlin")


def _job(scenario, name=None, controllers=("detector_located",)) -> StreetJob:
    return StreetJob(name or scenario.name, "x.yaml", scenario, YEAR, controllers, "fast")


@pytest.fixture(scope="module")
def suburb():
    return load_scenario(REPO / "scenarios" / "suburban_night.yaml")


def test_streets_of_one_camera_and_environment_share_a_key(suburb):
    longer = override(suburb, {"street.length_m": 520.0, "lamps.count": 14, "name": "longer", "seed": 99})
    busier = override(suburb, {"traffic.classes.pedestrian.rate_per_hour": 300.0})
    rainy = override(suburb, {"environment.weather": "rain"})
    tilted = override(suburb, {"lamps.camera.tilt_deg": suburb.lamps.camera.tilt_deg + 5})
    key = camera_key(_job(suburb))
    assert camera_key(_job(longer)) == key and camera_key(_job(busier)) == key
    assert camera_key(_job(rainy)) != key and camera_key(_job(tilted)) != key


def test_a_city_finds_the_shipped_model_for_all_its_matching_streets(suburb, monkeypatch, tmp_path):
    def no_calibration(*args, **kwargs):
        raise AssertionError("calibrated although a street of the key had a model")

    monkeypatch.setattr(models, "sensor_model_for", no_calibration)
    longer = override(suburb, {"street.length_m": 520.0, "lamps.count": 14, "name": "longer"})
    jobs = [_job(longer), _job(suburb), _job(suburb, name="light", controllers=("pir",))]
    keys, found = city_models(jobs, cache_dir=tmp_path, progress=False)
    assert set(keys) == {"longer", "suburban_night"}  # the pir street needs no model
    assert len(found) == 1 and keys["longer"] == keys["suburban_night"]
    assert found[keys["longer"]].key.startswith("suburban_night-")  # the shipped one, used for both
