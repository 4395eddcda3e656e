"""Traffic: agent kinds (Table 1 sizes, speeds), Poisson arrivals with hourly profiles, routes."""

import math
from pathlib import Path

import numpy as np
import pytest
import simpy

from citysim.config.kinds import AGENT_KINDS
from citysim.config.motion import MAX_SPEED_MPS, DrawOptions
from citysim.config.scenario import load_scenario, override
from citysim.config.traffic import TRAFFIC_SPECS
from citysim.world.agents import draw_agent
from citysim.world.street import build_street
from citysim.world.traffic import arrivals, draw_arrival, start_traffic

SUBURBAN = Path(__file__).resolve().parents[3] / "scenarios" / "suburban_night.yaml"

# Table 1 of the paper (width, height, depth), and the brief's fox/dog-size animal.
TABLE_1 = {
    "pedestrian": ((0.3, 0.64), (1.15, 2.0), (0.3, 0.79)),
    "cyclist": ((0.3, 0.64), (1.5, 1.9), (1.5, 1.7)),
    "vehicle": ((1.4, 1.8), (1.4, 2.0), (3.7, 4.6)),
    "animal": ((0.2, 0.35), (0.3, 0.7), (0.5, 1.0)),
}


@pytest.fixture(scope="module")
def scenario():
    return load_scenario(SUBURBAN)


@pytest.fixture(scope="module")
def street(scenario):
    return build_street(scenario)


class _Recorder:
    """Stands in for a World: arrivals() only needs .street and .spawn()."""

    def __init__(self, env, street):
        self.env, self.street, self.times, self.agents = env, street, [], []

    def spawn(self, traits, route):
        self.times.append(self.env.now)
        self.agents.append((traits, route))
        return len(self.times) - 1


@pytest.mark.parametrize("cls", sorted(TABLE_1))
def test_sizes_follow_table_1(cls):
    rng = np.random.default_rng(1)
    drawn = [draw_agent(cls, rng) for _ in range(400)]
    for values, (lo, hi) in zip(
        ([t.width_m for t in drawn], [t.height_m for t in drawn], [t.length_m for t in drawn]),
        TABLE_1[cls],
        strict=True,
    ):
        assert lo <= min(values) and max(values) <= hi
        assert max(values) - min(values) > 0.8 * (hi - lo)  # the range is used, not one value
    kind = AGENT_KINDS[cls]
    speeds = [t.desired_speed_mps for t in drawn]
    assert kind.speed.min_mps <= min(speeds) and max(speeds) <= kind.speed.max_mps <= MAX_SPEED_MPS


def test_groups_are_two_to_four_side_by_side():
    rng = np.random.default_rng(2)
    for _ in range(300):
        g = draw_agent("group", rng, DrawOptions(max_group_width_m=3.0))
        assert 2 <= len(g.members) <= 4
        assert 1.5 <= g.height_m <= 2.0  # Table 1 group height: the tallest member
        assert 1.2 - 1e-9 <= g.width_m <= 3.0 + 1e-9  # Table 1 group width
        assert all(m.forward_m == 0 for m in g.members)  # one row when there is room
        lefts = sorted(m.left_m for m in g.members)
        widths = {m.left_m: m.width_m for m in g.members}
        for a, b in zip(lefts[:-1], lefts[1:], strict=True):
            assert b - a >= (widths[a] + widths[b]) / 2  # members never overlap
    # on a narrow path, four people walk in two rows of two
    narrow = [
        draw_agent("group", rng, DrawOptions(group_size=(4, 4), max_group_width_m=1.0))
        for _ in range(50)
    ]
    for g in narrow:
        assert g.width_m <= 1.0 + 1e-9 and len({m.forward_m for m in g.members}) >= 2


def test_running_share_and_speeds():
    rng = np.random.default_rng(3)
    opts = TRAFFIC_SPECS["pedestrian"](running_fraction=0.3).draw_options(night=True)
    drawn = [draw_agent("pedestrian", rng, opts) for _ in range(2000)]
    runners = [t for t in drawn if t.running]
    assert abs(len(runners) / len(drawn) - 0.3) < 0.04
    assert all(2.5 <= t.desired_speed_mps <= 4.0 for t in runners)
    assert all(1.0 <= t.desired_speed_mps <= 1.8 for t in drawn if not t.running)
    assert all(t.stride_m == pytest.approx(2 * t.length_m) for t in drawn)


def test_lights_only_at_night():
    rng = np.random.default_rng(4)
    spec = TRAFFIC_SPECS["vehicle"](rate_per_hour=1.0)
    assert all(
        draw_agent("vehicle", rng, spec.draw_options(night=True)).light_on for _ in range(50)
    )
    assert not any(
        draw_agent("vehicle", rng, spec.draw_options(night=False)).light_on for _ in range(50)
    )


def test_arrival_count_is_poisson(street):
    env = simpy.Environment()
    rec = _Recorder(env, street)
    spec = TRAFFIC_SPECS["vehicle"](rate_per_hour=60.0)
    env.process(arrivals(env, rec, spec, np.random.default_rng(5)))
    hours = 100
    env.run(until=hours * 3600)
    n, expected = len(rec.times), 60.0 * hours
    assert abs(n - expected) < 4 * math.sqrt(expected)
    # counts per 10 minutes: Poisson, so variance ~ mean
    counts = np.bincount((np.array(rec.times) // 600).astype(int), minlength=hours * 6)
    assert 0.75 < counts.var() / counts.mean() < 1.3
    # gaps: exponential, so their coefficient of variation is ~1
    gaps = np.diff(rec.times)
    assert 0.9 < gaps.std() / gaps.mean() < 1.1


def test_arrivals_follow_the_hourly_profile(street):
    counts = np.zeros(4)
    for seed in range(20):
        env = simpy.Environment()
        rec = _Recorder(env, street)
        spec = TRAFFIC_SPECS["pedestrian"](rate_per_hour=200.0, hourly_profile=(1.0, 0.25, 0.0))
        env.process(arrivals(env, rec, spec, np.random.default_rng(seed)))
        env.run(until=4 * 3600)
        counts += np.bincount((np.array(rec.times) // 3600).astype(int), minlength=4)[:4]
    mean = counts / 20
    assert abs(mean[0] - 200) < 4 * math.sqrt(200 / 20)
    assert abs(mean[1] - 50) < 4 * math.sqrt(50 / 20)
    assert mean[2] == mean[3] == 0  # after the list, its last multiplier (0) holds


def test_classes_draw_from_independent_streams(scenario):
    def vehicle_times(s):
        env = simpy.Environment()
        rec = _Recorder(env, build_street(s))
        start_traffic(env, rec, s, np.random.default_rng(6))
        env.run(until=1800)
        return [
            t
            for t, (traits, _) in zip(rec.times, rec.agents, strict=True)
            if traits.cls == "vehicle"
        ]

    base = vehicle_times(scenario)
    assert base and base == vehicle_times(scenario)
    # more pedestrians must not reshuffle the cars
    assert (
        vehicle_times(override(scenario, {"traffic.classes.pedestrian.rate_per_hour": 500})) == base
    )


def test_routes_stay_on_their_paths(scenario, street):
    rng = np.random.default_rng(7)
    classes = scenario.traffic.classes
    crossings, n_walk = 0, 0
    for spec in (classes.pedestrian, classes.group):
        for _ in range(300):
            traits, route = draw_arrival(street, spec, rng)
            legs = route.legs
            n_walk += 1
            crossings += len(legs) == 3
            assert (
                legs[0].start_xy_m[0] < 0 or legs[0].start_xy_m[0] > street.length_m
            )  # enter at an end
            assert (
                legs[-1].end_xy_m[0] < 0 or legs[-1].end_xy_m[0] > street.length_m
            )  # leave at an end
            for leg in legs:
                assert leg.band_m[0] <= leg.pref_m <= leg.band_m[1]
                if not leg.yield_to_traffic:  # a sidewalk leg: the band lies in the walking room
                    sw = min(
                        street.sidewalks, key=lambda s, y=leg.start_xy_m[1]: abs(s.y_center_m - y)
                    )
                    lo, hi = street.walking_room_m(sw)
                    ys = [leg.point(0, o)[1] for o in leg.band_m]
                    assert (
                        lo + traits.width_m / 2 - 1e-9 <= min(ys)
                        and max(ys) <= hi - traits.width_m / 2 + 1e-9
                    )
            if len(legs) == 3:
                assert legs[1].yield_to_traffic and legs[0].end_xy_m == legs[1].start_xy_m
                assert legs[0].start_xy_m[1] * legs[2].start_xy_m[1] < 0  # other side of the road
    share = crossings / n_walk
    assert 0.15 < share < 0.35  # pedestrians 0.3, groups 0.2
    for spec in (classes.cyclist, classes.vehicle):
        for _ in range(100):
            traits, route = draw_arrival(street, spec, rng)
            (leg,) = route.legs
            lane = min(street.lanes, key=lambda ln, y=leg.start_xy_m[1]: abs(ln.y_center_m - y))
            assert np.sign(leg.unit[0]) == lane.direction  # drive on the lane's side
            if spec.kind == "cyclist":
                assert leg.pref_m < -0.5  # near the right edge of the lane
            else:
                assert leg.pref_m == 0.0


def test_a_wandering_animal_can_get_round_the_longest_road_user(scenario, street):
    # An animal crossing meets a car that stopped for it with its body across the animal's line;
    # unless the animal may step aside past the car's whole length, each waits for the other
    # for good (found at ten times suburban_night's traffic with a band of +-1.5 m).
    rng = np.random.default_rng(3)
    spec = scenario.traffic.classes.animal
    longest_m = max(AGENT_KINDS[k].sizes.length_m[1] for k in AGENT_KINDS if AGENT_KINDS[k].road_user)
    for _ in range(50):
        traits, route = draw_arrival(street, spec, rng)
        for leg in route.legs:
            lo_m, hi_m = leg.band_m
            assert min(-lo_m, hi_m) >= longest_m + traits.width_m / 2, (leg.band_m, longest_m)
