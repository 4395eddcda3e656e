"""Fast mode's geometry, the located controller's ground points and per-lamp energy on a curved street.

scenarios/curved_bend.yaml: the bend at s = 180 m; lamp 4's camera at world (161.9, 6.2), heading
-8 deg (tests/citysim/world/test_curved_street.py derives these by hand).
"""

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from citysim.config.scenario import ControllerSpec, load_scenario, override
from citysim.fast.geometry import CameraGeometry
from citysim.sim.loop import run_controller
from citysim.world.agents import AgentState
from citysim.world.street import build_street

SCENARIO = load_scenario(Path(__file__).resolve().parents[3] / "scenarios" / "curved_bend.yaml")
STREET = build_street(SCENARIO)


def test_candidates_are_placed_through_the_centreline():
    geometry = CameraGeometry(STREET)
    walker = AgentState(1, "pedestrian", 180.0, 4.3, 0.0, 1.4, 0.3, 0.5, 1.75)  # s, d: world (175.7, 4.3)
    cand = geometry.candidates([walker])
    yaw = math.radians(-8.0)
    forward_m = (175.7 - 161.9) * math.cos(yaw) + (4.3 - 6.2) * math.sin(yaw)
    assert cand.forward_m[0, 4] == pytest.approx(forward_m, abs=1e-9)
    assert cand.seen[0, 4] and not cand.seen[0, 2] and not cand.seen[0, 5]
    # the same from columns (the replayed chunks' path)
    cols = geometry.candidates_at(np.array([[180.0, 4.3]]), np.array([False]), None)
    assert np.array_equal(cols.forward_m, cand.forward_m) and np.array_equal(cols.seen, cand.seen)
    # its box stands on its footprint: the box's bottom centre back on the ground is the walker's place
    x, y, w, h = geometry.box_px(4, walker)
    ground = STREET.lamps[4].camera.pixel_to_ground(np.array([[x + w / 2 - 0.5, y + h - 0.5]]))[0]
    assert ground[:2] == pytest.approx((175.7, 4.3), abs=0.15)  # a pixel's rounding at 14 m
    # nearest lamps are nearest along the street (s), not in the world
    assert geometry.nearest_lamp(np.array([181.0, 179.0])).tolist() == [5, 4]


def test_the_located_controller_puts_world_ground_points_on_the_street():
    from citysim.control.located import DetectorLocated

    located = DetectorLocated.__new__(DetectorLocated)  # only its street conversion is asked
    located.ctx = SimpleNamespace(street=STREET)
    # moving north at 5 m/s just past the bend: along the street (+s), 5 m/s
    detection = SimpleNamespace(velocity_x_mps=0.0, velocity_y_mps=5.0)
    s_m, d_m, vs_mps = located._on_street(177.0, 3.1, detection)
    assert (s_m, d_m) == pytest.approx((180.0 + 30.0 * 0.1 / 27.0, 3.0), abs=1e-9)
    assert vs_mps == pytest.approx(5.0)
    # before the bend the same world velocity is across the street: no speed along it
    assert located._on_street(100.0, 2.0, detection) == pytest.approx((100.0, 2.0, 0.0))


def test_each_surveyed_lamp_pays_for_its_own_power():
    scenario = override(SCENARIO, {"duration_s": 10.0, "traffic.scripted": []})
    result = run_controller(scenario, ControllerSpec(name="always_on"))
    powers_w = [lamp.rated_power_w for lamp in STREET.lamps]
    assert powers_w.count(40.0) == 1 and powers_w.count(60.0) == 9
    assert result["energy_kwh"] * 3.6e6 == pytest.approx(sum(powers_w) * 10.0, rel=1e-9)
    assert result["savings_vs_always_on"] == pytest.approx(0.0, abs=1e-12)
