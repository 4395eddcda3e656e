"""The world: paths, speed limits, no overlaps, giving way, gait, determinism, flat memory."""

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
import simpy

from citysim.config.motion import MAX_SPEED_MPS
from citysim.config.scenario import load_scenario, override
from citysim.world.agents import AgentTraits
from citysim.world.geometry import oriented_overlaps
from citysim.world.physics import Leg, Route, World, physics_process
from citysim.world.street import build_street
from citysim.world.traffic import start_traffic

SUBURBAN = Path(__file__).resolve().parents[3] / "scenarios" / "suburban_night.yaml"
BUSY = 5.0  # traffic multiplier over the suburban weeknight
DT_S = 0.25  # coarse physics step: the behaviour must hold at 4 Hz too


@pytest.fixture(scope="module")
def scenario():
    s = load_scenario(SUBURBAN)
    c = s.traffic.classes
    return override(
        s,
        {f"traffic.classes.{k}.rate_per_hour": getattr(c, k).rate_per_hour * BUSY for k in
         ("pedestrian", "group", "cyclist", "vehicle", "animal")}
        | {f"traffic.classes.{k}.hourly_profile": [] for k in ("pedestrian", "group", "cyclist", "vehicle")},
    )  # fmt: skip


@dataclass
class Record:
    world: World
    steps: int = 0
    overlapping_steps: int = 0
    max_agents: int = 0
    seen: dict = field(default_factory=dict)  # id -> class
    too_fast: list = field(default_factory=list)
    off_path: list = field(default_factory=list)
    left_at: dict = field(default_factory=dict)  # id -> last state before removal
    crossed: set = field(default_factory=set)


def _check_path(world: World, a, rec: Record) -> None:
    street = world.street
    leg = world.route_leg(a.object_id)
    if a.cls in ("pedestrian", "group") and not leg.yield_to_traffic:
        sw = min(street.sidewalks, key=lambda s: abs(s.y_center_m - leg.start_xy_m[1]))
        lo, hi = street.walking_room_m(sw)
        if not lo - 1e-6 <= a.y_m - a.width_m / 2 and a.y_m + a.width_m / 2 <= hi + 1e-6:
            rec.off_path.append((a.object_id, a.cls, a.y_m))
    elif a.cls in ("vehicle", "cyclist"):
        lane = min(street.lanes, key=lambda ln: abs(ln.y_center_m - leg.start_xy_m[1]))
        left = lane.direction  # +y is the left of a lane toward +x
        rel = (a.y_m - lane.y_center_m) * left  # offset to the left of travel
        half = a.width_m / 2 + 0.05  # a swerving body's corner pokes out a little
        # inside the lane, but for swinging out up to 0.4 m over the centre line
        if (
            not -lane.width_m / 2 - 0.05 <= rel - half
            and rel + half <= lane.width_m / 2 + 0.4 + 0.05
        ):
            rec.off_path.append((a.object_id, a.cls, a.y_m))
    elif a.cls == "pedestrian" and leg.yield_to_traffic:
        rec.crossed.add(a.object_id)


@pytest.fixture(scope="module")
def busy_hour(scenario):
    """One simulated hour of five times the suburban traffic, checked at every step."""
    rng = np.random.default_rng(scenario.seed)
    world = World(build_street(scenario), rng.spawn(1)[0])
    env = simpy.Environment()
    start_traffic(env, world, scenario, rng)
    rec = Record(world)
    last = {}
    for k in range(int(3600 / DT_S)):
        env.run(until=(k + 1) * DT_S)
        world.step(DT_S)
        states = world.states()
        rec.steps += 1
        rec.max_agents = max(rec.max_agents, len(states))
        now = {a.object_id: a for a in states}
        for oid in last.keys() - now.keys():
            rec.left_at[oid] = last[oid]
        last = now
        for a in states:
            rec.seen[a.object_id] = a.cls
            limit = world.traits_of(a.object_id).desired_speed_mps
            if a.speed_mps > limit + 1e-9 or a.speed_mps > MAX_SPEED_MPS + 1e-9:
                rec.too_fast.append((a.object_id, a.cls, a.speed_mps, limit))
            _check_path(world, a, rec)
        if len(states) > 1:
            xy = np.array([(a.x_m, a.y_m) for a in states])
            th = np.array([a.heading_rad for a in states])
            ln = np.array([a.length_m for a in states])
            wd = np.array([a.width_m for a in states])
            # "never overlap": not even by a micrometre
            rec.overlapping_steps += bool(oriented_overlaps(xy, th, ln, wd, margin_m=-1e-6).any())
    return rec


def test_busy_hour_is_busy(busy_hour):
    counts = {}
    for cls in busy_hour.seen.values():
        counts[cls] = counts.get(cls, 0) + 1
    assert counts.get("pedestrian", 0) > 120 and counts.get("vehicle", 0) > 60
    assert {"group", "cyclist"} <= counts.keys()
    assert busy_hour.max_agents >= 20
    assert len(busy_hour.crossed) > 20  # pedestrians did cross the road


def test_no_two_agents_ever_overlap(busy_hour):
    assert busy_hour.overlapping_steps == 0


def test_agents_stay_on_their_paths(busy_hour):
    assert busy_hour.off_path == []


def test_agents_keep_under_their_speed_limits(busy_hour):
    assert busy_hour.too_fast == []


def test_nobody_gets_stuck_and_all_leave_at_the_ends(busy_hour):
    world = busy_hour.world
    assert world.stuck_agents(min_still_s=30.0) == []
    assert world.pending_count < 5  # entries never jam
    length = world.street.length_m
    for oid, a in busy_hour.left_at.items():
        if a.cls != "animal":  # animals leave into the verge
            assert a.x_m < 3.0 or a.x_m > length - 3.0, (oid, a)


def test_memory_stays_flat(busy_hour):
    world = busy_hour.world
    assert world.spawned_count - world.removed_count == world.agent_count
    assert len(world.space.bodies) == world.agent_count == len(world.space.shapes)
    assert world.removed_count > 0.9 * world.spawned_count


def _run(scenario, seconds: float, hz: float) -> list:
    rng = np.random.default_rng(scenario.seed)
    world = World(build_street(scenario), rng.spawn(1)[0])
    env = simpy.Environment()
    start_traffic(env, world, scenario, rng)
    env.process(physics_process(env, world, hz))
    trace = []
    for k in range(int(seconds)):
        env.run(until=k + 1)
        trace.append(tuple(world.states()))
    return trace


def test_same_seed_same_trajectories(scenario):
    a, b = _run(scenario, 120, 30), _run(scenario, 120, 30)
    assert sum(len(s) for s in a) > 200
    assert a == b  # bit for bit: dataclass equality compares the floats exactly
    c = _run(override(scenario, {"seed": scenario.seed + 1}), 120, 30)
    assert c != a


# ----------------------------------------------------------- scripted situations
def _traits(cls, speed, width=0.5, length=0.5, height=1.7, stride=1.0):
    return AgentTraits(cls, width, height, length, speed, stride)


@pytest.fixture
def street(scenario):
    return build_street(scenario)


def _lane_leg(street, x0, x1, lane_i=0):
    y = street.lanes[lane_i].y_center_m
    return Leg((x0, y), (x1, y), (-0.7, 0.7), (-0.7, 0.7), 0.0)


def test_car_follows_slower_car_without_touching(street):
    world = World(street, np.random.default_rng(0))
    slow = world.spawn(
        _traits("vehicle", 8.0, 1.7, 4.4, 1.5), Route((_lane_leg(street, -3, 340),), "lane0")
    )
    world.step(1 / 30)
    for _ in range(30 * 3):
        world.step(1 / 30)
    fast = world.spawn(
        _traits("vehicle", 16.0, 1.7, 4.4, 1.5), Route((_lane_leg(street, -3, 340),), "lane0")
    )
    gaps = []
    for _ in range(30 * 30):
        world.step(1 / 30)
        s = {a.object_id: a for a in world.states()}
        if slow in s and fast in s:
            gaps.append(s[slow].x_m - s[fast].x_m - 4.4)
    assert min(gaps) > 2.0  # IDM keeps at least its minimum gap
    s = {a.object_id: a for a in world.states()}
    assert abs(s[fast].speed_mps - s[slow].speed_mps) < 0.2  # settled behind the leader
    assert s[fast].speed_mps < 16.0 - 5


def test_car_gives_way_to_a_pedestrian_on_the_road(street):
    world = World(street, np.random.default_rng(0))
    x_cross = 60.0
    # a slow walker already in the middle of the car's lane, crossing
    walk = Leg((x_cross, -1.8), (x_cross, 4.3), (-0.3, 0.3), (-0.3, 0.3), 0.0)
    ped = world.spawn(_traits("pedestrian", 0.15), Route((walk,), "test-ped"))
    car = world.spawn(
        _traits("vehicle", 14.0, 1.7, 4.4, 1.5), Route((_lane_leg(street, -3, 340),), "lane0")
    )
    min_gap, slowest_near = math.inf, math.inf
    for _ in range(30 * 40):
        world.step(1 / 30)
        s = {a.object_id: a for a in world.states()}
        if ped in s and car in s:
            gap = s[ped].x_m - 0.25 - (s[car].x_m + 2.2)
            if abs(s[ped].y_m - s[car].y_m) < (1.7 + 0.5) / 2:  # the walker is in the car's path
                min_gap = min(min_gap, gap)
            if 0 < gap < 10:
                slowest_near = min(slowest_near, s[car].speed_mps)
    assert min_gap > 1.0  # never closer than that while the walker was in its way
    assert slowest_near < 2.0  # down to walking pace before squeezing by
    s = {a.object_id: a for a in world.states()}
    assert car not in s and world.removed_count == 1  # then drove on and out of the street


def test_pedestrian_waits_at_the_kerb_then_crosses(street):
    world = World(street, np.random.default_rng(0))
    x_cross = 40.0
    sw0, sw1 = street.sidewalks
    legs = (
        Leg(
            (x_cross - 6, sw0.y_center_m), (x_cross, sw0.y_center_m), (-0.5, 0.5), (-0.5, 0.5), 0.0
        ),
        Leg(
            (x_cross, sw0.y_center_m),
            (x_cross, sw1.y_center_m),
            (-0.3, 0.3),
            (-0.3, 0.3),
            0.0,
            yield_to_traffic=True,
        ),
        Leg(
            (x_cross, sw1.y_center_m), (x_cross + 20, sw1.y_center_m), (-0.5, 0.5), (-0.5, 0.5), 0.0
        ),
    )
    ped = world.spawn(_traits("pedestrian", 1.4), Route(legs, "test-ped"))
    car = world.spawn(
        _traits("vehicle", 12.0, 1.7, 4.4, 1.5), Route((_lane_leg(street, -3, 340),), "lane0")
    )
    road_y = street.lanes[0].y_center_m - street.lanes[0].width_m / 2
    crossed_at = None
    for k in range(30 * 40):
        world.step(1 / 30)
        s = {a.object_id: a for a in world.states()}
        if car in s and ped in s and s[car].x_m - 2.2 < x_cross + 0.5:
            # while the car has not passed the crossing, the walker stays off the road
            assert s[ped].y_m - 0.25 < road_y + 1e-6
        if ped in s and s[ped].y_m > street.lanes[1].y_center_m and crossed_at is None:
            crossed_at = k / 30
    assert crossed_at is not None  # and then crossed


@pytest.mark.parametrize("keep_m", [-0.4, 0.4], ids=["keep-right", "keep-left"])
def test_wide_groups_pass_each_other_on_one_sidewalk(street, keep_m):
    # keeping left, both step aside when they meet and, once beside each other,
    # both want back into the same gap: neither may block the other for good
    world = World(street, np.random.default_rng(0))
    sw = street.sidewalks[0]
    lo, hi = street.walking_room_m(sw)
    # wider than traffic draws them, so the gap left between them (0.1 m) is under
    # the clearance walkers keep (0.12 m) and both want it
    width = (hi - lo) / 2 - 0.05
    ids = []
    for direction in (1, -1):
        x0, x1 = (-1.0, 80.0) if direction > 0 else (80.0, -1.0)
        half = (hi - lo) / 2 - width / 2
        leg = Leg((x0, sw.y_center_m), (x1, sw.y_center_m), (-half, half), (-0.4, 0.4), keep_m)
        ids.append(
            world.spawn(
                _traits("group", 1.3, width=width, length=0.7), Route((leg,), f"g{direction}")
            )
        )
    for _ in range(5 * 120):
        world.step(0.2)  # coarse steps: one sidestep (0.12 m) is more than half the gap left
    assert world.agent_count == 0 and world.removed_count == 2  # both walked through and left


def test_gait_phase_advances_with_distance(street):
    world = World(street, np.random.default_rng(0))
    sw = street.sidewalks[1]
    leg = Leg((-1.0, sw.y_center_m), (200.0, sw.y_center_m), (-0.5, 0.5), (-0.5, 0.5), 0.0)
    world.spawn(
        AgentTraits("pedestrian", 0.5, 1.7, 0.6, 1.4, stride_m=1.2, gait_phase_rad=0.3),
        Route((leg,), "p"),
    )
    world.step(0.1)
    (a,) = world.states()
    travelled = 0.0
    prev = a
    for _ in range(200):
        world.step(0.1)
        (b,) = world.states()
        travelled += math.hypot(b.x_m - prev.x_m, b.y_m - prev.y_m)
        prev = b
    expected = (a.gait_phase_rad + 2 * math.pi * travelled / 1.2) % (2 * math.pi)
    assert prev.gait_phase_rad == pytest.approx(expected, abs=1e-6)
    assert travelled == pytest.approx(1.4 * 20.0, rel=0.01)


def test_bad_input(street):
    world = World(street, np.random.default_rng(0))
    leg = _lane_leg(street, -3, 340)
    with pytest.raises(ValueError, match="unknown agent class 'truck'"):
        world.spawn(_traits("truck", 10.0), Route((leg,), "lane0"))
    with pytest.raises(ValueError, match="dt_s must be > 0"):
        world.step(0.0)
