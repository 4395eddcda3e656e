"""The e-scooter kind, added as data: it draws within its ranges and speeds, rides a lane
like a cyclist, and a scenario can ask for it (random and scripted)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import simpy

from citysim.config.base import ScenarioError
from citysim.config.kinds import AGENT_KINDS
from citysim.config.motion import KMH_PER_MPS
from citysim.config.scenario import load_scenario, override
from citysim.config.traffic import TRAFFIC_SPECS
from citysim.sim.night import build_night
from citysim.world.agents import draw_agent
from citysim.world.street import build_street
from citysim.world.traffic import draw_arrival, start_traffic

SUBURBAN = Path(__file__).resolve().parents[3] / "scenarios" / "suburban_night.yaml"
#: The brief's e-scooter: width, height, length (m) and speed (km/h) ranges.
WIDTH_M, HEIGHT_M, LENGTH_M, SPEED_KMH = (0.4, 0.6), (1.6, 2.0), (1.0, 1.2), (15.0, 25.0)


@pytest.fixture(scope="module")
def scenario():
    return load_scenario(SUBURBAN)


def test_draws_within_its_ranges_and_speeds() -> None:
    rng = np.random.default_rng(7)
    drawn = [draw_agent("e_scooter", rng) for _ in range(400)]
    for values, (lo, hi) in (
        ([t.width_m for t in drawn], WIDTH_M),
        ([t.height_m for t in drawn], HEIGHT_M),
        ([t.length_m for t in drawn], LENGTH_M),
        ([t.desired_speed_mps * KMH_PER_MPS for t in drawn], SPEED_KMH),
    ):
        assert lo - 1e-9 <= min(values) and max(values) <= hi + 1e-9
        assert max(values) - min(values) > 0.8 * (hi - lo)  # the range is used, not one value
    assert all(t.cls == "e_scooter" and not t.members for t in drawn)
    kind = AGENT_KINDS["e_scooter"]
    assert kind.is_target and kind.road_user and kind.detector_class == "cyclist"


def test_rides_the_right_edge_of_a_lane_like_a_cyclist(scenario) -> None:
    street = build_street(scenario)
    spec = TRAFFIC_SPECS["e_scooter"](rate_per_hour=10.0)
    rng = np.random.default_rng(8)
    for _ in range(50):
        traits, route = draw_arrival(street, spec, rng)
        (leg,) = route.legs
        lane = next(ln for ln in street.lanes if ln.y_center_m == leg.start_xy_m[1])
        assert route.entry_key.startswith("lane")
        assert np.sign(leg.end_xy_m[0] - leg.start_xy_m[0]) == lane.direction
        # near the right edge: its preferred offset is right of the lane's centre line
        assert -lane.width_m / 2 < leg.pref_m < 0.0


def test_in_the_world_it_stays_on_the_road_and_walkers_give_way(scenario) -> None:
    busy = override(
        scenario,
        {f"traffic.classes.{k}.rate_per_hour": 0.0 for k in AGENT_KINDS}
        | {"traffic.classes.e_scooter.rate_per_hour": 600.0, "traffic.scripted": []},
    )
    night = build_night(busy)
    street, world = night.street, night.world
    night.start_physics()
    road_lo = min(ln.y_center_m - ln.width_m / 2 for ln in street.lanes)
    road_hi = max(ln.y_center_m + ln.width_m / 2 for ln in street.lanes)
    dt, seen = 1.0 / busy.physics_hz, set()
    for k in range(1, int(60 * busy.physics_hz) + 1):
        night.run_until(k * dt + 1e-6)
        for a in night.agents:
            assert a.cls == "e_scooter"
            assert road_lo <= a.y_m - a.width_m / 2 and a.y_m + a.width_m / 2 <= road_hi
            assert a.speed_mps <= SPEED_KMH[1] / KMH_PER_MPS + 1e-9
            seen.add(a.object_id)
    assert len(seen) >= 5
    assert world.stuck_agents() == []
    assert world._agents and all(m.road_user for m in world._agents.values())


class _Recorder:
    """Stands in for the world: records what arrives, and when."""

    def __init__(self, env: simpy.Environment, street) -> None:
        self.env, self.street, self.arrived = env, street, []

    def spawn(self, traits, route) -> int:
        self.arrived.append((self.env.now, traits, route))
        return len(self.arrived) - 1


def _arrivals(scenario, hours: float = 2.0) -> list:
    env = simpy.Environment()
    rec = _Recorder(env, build_street(scenario))
    start_traffic(env, rec, scenario, np.random.default_rng(scenario.seed))
    env.run(until=hours * 3600.0)
    return rec.arrived


def test_e_scooters_leave_the_other_classes_arrivals_as_they_were(scenario) -> None:
    """Each class draws from its own stream, the e-scooter's after the others': without
    traffic it draws nothing, and with traffic it changes no other class's arrivals."""
    without = _arrivals(override(scenario, {"traffic.classes.e_scooter.rate_per_hour": 0.0}))
    with_ = _arrivals(override(scenario, {"traffic.classes.e_scooter.rate_per_hour": 30.0}))
    scooters = [a for a in with_ if a[1].cls == "e_scooter"]
    assert not [a for a in without if a[1].cls == "e_scooter"] and len(scooters) >= 20
    assert [a for a in with_ if a[1].cls != "e_scooter"] == without


def test_scripted_e_scooter_keeps_a_lane(scenario) -> None:
    ok = override(scenario, {"traffic.scripted": [
        {"cls": "e_scooter", "t_s": 1.0, "speed_kmh": 20.0, "direction": -1, "path": 1}]})  # fmt: skip
    (agent,) = ok.traffic.scripted
    assert agent.cls == "e_scooter"
    with pytest.raises(ScenarioError, match=r"traffic\.scripted\.0\.path: .*street\.lanes"):
        override(scenario, {"traffic.scripted": [
            {"cls": "e_scooter", "t_s": 1.0, "speed_kmh": 20.0, "path": 5}]})  # fmt: skip


def test_unknown_field_is_rejected_naming_it(scenario) -> None:
    with pytest.raises(ScenarioError, match=r"traffic\.classes\.e_scooter\.wheels: unknown field"):
        override(scenario, {"traffic.classes.e_scooter.wheels": 2})
