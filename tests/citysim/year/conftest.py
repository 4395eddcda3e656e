"""A toy street for the year tests: two 60 W lamps, a little traffic, tiny samples."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from citysim.config.scenario import scenario_from_mapping
from tests.citysim.streets import two_way_street

REPO = Path(__file__).resolve().parents[3]
CAMERA = REPO / "scenarios" / "cameras" / "scene_a.yaml"


def toy_mapping(**year) -> dict:
    """Two lamps 30 m apart (zones 10..70 m: a 60 m chain) on an 80 m street 10.8 m wide."""
    return {
        "name": "toy", "seed": 3, "duration_s": 60, "street": two_way_street(80),
        "lamps": {"count": 2, "spacing_m": 30, "first_x_m": 25, "y_m": 6.2, "pole_height_m": 5.5,
                  "luminaire": {"rated_power_w": 60}, "camera": {"file": str(CAMERA)}},
        "traffic": {"classes": {"pedestrian": {"rate_per_hour": 120, "hourly_profile": [1.0, 0.5]},
                                "vehicle": {"rate_per_hour": 60}}},
        "controllers": ["always_on", "pir"],
        "year": {"latitude_deg": 52.52, "longitude_deg": 13.405, "timezone": "Europe/Berlin", "year": 2025,
                 "tariff_per_kwh": 0.3, "grid_kg_co2_per_kwh": 0.4, "traffic_levels": [1.0],
                 "sample_s": 30, "warmup_s": 10, "idle_sample_s": 10, **year},
    }  # fmt: skip


@pytest.fixture
def toy():
    return scenario_from_mapping(toy_mapping(), source="toy")


@pytest.fixture
def toy_file(tmp_path) -> Path:
    path = tmp_path / "toy.yaml"
    path.write_text(yaml.safe_dump(toy_mapping()))
    return path
