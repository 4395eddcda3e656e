"""Camera coverage of a street, and cameras set per lamp (headings_deg)."""

from pathlib import Path

import pytest

from citysim.config.base import ScenarioError
from citysim.config.scenario import load_scenario, override
from citysim.world.coverage import camera_coverage
from citysim.world.street import build_street

SUBURBAN = Path(__file__).resolve().parents[3] / "scenarios" / "suburban_night.yaml"


@pytest.fixture(scope="module")
def suburban():
    return load_scenario(SUBURBAN)


def test_suburban_cameras_leave_the_stretch_under_each_pole_blind(suburban):
    cov = camera_coverage(build_street(suburban))
    assert 0.45 < cov.street_seen < 0.6
    poles = suburban.lamps.positions_x_m
    # the cameras look along +x and see 6-25 m ahead: under every later pole nobody looks
    for x in poles[1:]:
        assert any(a <= x <= b for a, b in cov.blind_stretches_m), x
    # ... and the approach to the first zone's start
    assert cov.blind_stretches_m[0][0] == pytest.approx(min(s.zone_start_m for s in build_street(suburban).lamps))


def test_headings_per_lamp_turn_each_camera(suburban):
    n = len(suburban.lamps.positions_x_m)
    alternating = override(suburban, {"lamps.camera.headings_deg": [-8.0 if i % 2 == 0 else 188.0 for i in range(n)]})
    street = build_street(alternating)
    assert street.lamps[0].camera.heading_unit[0] > 0 > street.lamps[1].camera.heading_unit[0]
    # facing pairs look at the same stretch twice: less of the street is seen
    assert camera_coverage(street).street_seen < camera_coverage(build_street(suburban)).street_seen - 0.1


def test_headings_need_one_per_lamp(suburban):
    with pytest.raises(ScenarioError, match="lamps.camera.headings_deg: one heading per lamp"):
        override(suburban, {"lamps.camera.headings_deg": [0.0, 180.0]})
