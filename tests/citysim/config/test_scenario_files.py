"""Every shipped scenario and camera file loads, validates and builds a usable street."""

from pathlib import Path

import pytest

from citysim.config.scenario import load_scenario
from citysim.control.registry import CONTROLLERS
from citysim.world.street import build_street
from detector.camera import CameraModel

ROOT = Path(__file__).resolve().parents[3] / "scenarios"
SCENARIOS = sorted(ROOT.glob("*.yaml"))
CAMERAS = sorted((ROOT / "cameras").glob("*.yaml"))


def test_there_are_scenarios():
    assert SCENARIOS, f"no scenario files in {ROOT}"


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.name)
def test_scenario_loads_and_builds(path):
    scenario = load_scenario(path)
    street = build_street(scenario)
    assert len(street.lamps) == len(scenario.lamps.positions_x_m) >= 1
    # zones tile the lamp chain in lamp order, within the street; an end lamp reaches half a
    # spacing beyond itself (what lies further is an approach lit by other streets)
    first, last = street.lamps[0], street.lamps[-1]
    assert 0.0 <= first.zone_start_m <= first.along_m and last.along_m <= last.zone_end_m <= street.length_m
    if len(street.lamps) > 1:
        assert first.along_m - first.zone_start_m == pytest.approx(min(first.along_m, (street.lamps[1].along_m - first.along_m) / 2))
    for a, b in zip(street.lamps[:-1], street.lamps[1:], strict=True):
        assert a.zone_end_m == b.zone_start_m
        assert a.zone_start_m <= a.along_m <= a.zone_end_m
    for lamp in street.lamps:
        cam = lamp.camera
        assert (cam.x_m, cam.y_m) == (lamp.x_m, lamp.y_m)
        assert cam.bottom_row_depression_deg > 0  # sees the ground
    unknown = [c.name for c in scenario.controllers if c.name not in CONTROLLERS]
    assert not unknown, f"{path.name}: controllers {unknown} are not in {sorted(CONTROLLERS)}"


@pytest.mark.parametrize("path", CAMERAS, ids=lambda p: p.name)
def test_camera_file_loads(path):
    cam = CameraModel.from_yaml(path)
    assert cam.bottom_row_depression_deg > 0
