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


def test_a_backward_camera_on_every_pole_sees_the_street_start_but_not_under_the_poles(suburban):
    two_way = load_scenario(SUBURBAN.with_name("suburban_night_two_way.yaml"))
    one, two = camera_coverage(build_street(suburban)), camera_coverage(build_street(two_way))
    # the first pole's backward camera sees the approach and the first zone's first 20 m ...
    assert two.zone_seen[0] > one.zone_seen[0] + 0.25
    assert two.blind_stretches_m[0][0] > one.blind_stretches_m[0][0] + 5.0
    # ... but each backward camera looks along the stretch the previous pole's forward camera sees
    # (6.3-25 m from its pole; more of its width, from the other end): with 30 m spacing and 25 m
    # range the 10 m under every pole stay blind
    for x in two_way.lamps.positions_x_m[1:]:
        assert any(a <= x <= b for a, b in two.blind_stretches_m), x
    # the same stretches within one cell of the 0.5 m sampling grid
    assert len(two.blind_stretches_m) == len(one.blind_stretches_m)
    for (a2, b2), (a1, b1) in zip(two.blind_stretches_m[1:], one.blind_stretches_m[1:], strict=True):
        assert abs(a2 - a1) <= 0.5 and abs(b2 - b1) <= 0.5
    assert all(b >= a for a, b in zip(one.zone_seen, two.zone_seen, strict=True))
