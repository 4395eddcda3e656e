"""Side entries: the share of each class that joins and leaves mid-street, and how it gets there."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from citysim.config.scenario import load_scenario
from citysim.world.physics import World
from citysim.world.side_entries import SIDE_ROAD_M, TURN_M, WALK_STUB_M
from citysim.world.street import build_street
from citysim.world.traffic import draw_arrival

SCENARIO = load_scenario(Path(__file__).resolve().parents[3] / "scenarios" / "curved_bend.yaml")
STREET = build_street(SCENARIO)  # footpath on the left at s = 120 m, side street on the right at 240 m
N = 4000


def draws(kind: str, street=STREET, seed: int = 1):
    spec = getattr(SCENARIO.traffic.classes, kind)
    rng = np.random.default_rng(seed)
    return [draw_arrival(street, spec, rng) for _ in range(N)], rng


def binomial_ok(count: int, share: float) -> bool:
    """Within 4 standard deviations of N draws at ``share``."""
    return abs(count - N * share) <= 4.0 * np.sqrt(N * share * (1 - share))


def test_walkers_join_and_leave_at_the_entries_in_their_shares():
    routes = [route for _, route in draws("pedestrian")[0]]
    joined = {j: [r for r in routes if r.entry_key == f"side{j}sidewalk"] for j in (0, 1)}
    assert binomial_ok(len(joined[0]), 0.2) and binomial_ok(len(joined[1]), 0.1)
    # the footpath's walkers come in from the left verge, square to the street at s = 120 m
    for route in joined[0]:
        stub = route.legs[0]
        assert stub.start_xy_m == (120.0, STREET.y_max_m + WALK_STUB_M)
        assert stub.end_xy_m[0] == 120.0 and stub.end_xy_m[1] in (-4.3, 4.3)
        # crossing the road to the right-hand sidewalk, they yield to traffic
        assert stub.yield_to_traffic == (stub.end_xy_m[1] < 0)
        assert route.legs[1].start_xy_m == stub.end_xy_m
    left = [r for r in routes if r.legs[-1].end_xy_m[1] in (STREET.y_max_m + WALK_STUB_M, STREET.y_min_m - WALK_STUB_M)]
    at_entry = {s: sum(r.legs[-1].end_xy_m[0] == s for r in left) for s in (120.0, 240.0)}
    # the same share leaves as joins, but for those drawn to leave where they joined (they only join)
    assert binomial_ok(at_entry[120.0], 0.2 * (1 - 0.2)) and binomial_ok(at_entry[240.0], 0.1 * (1 - 0.1))


def test_vehicles_turn_in_from_the_side_street():
    routes = [route for _, route in draws("vehicle")[0]]
    joined = [r for r in routes if r.entry_key == "side1lane"]
    assert binomial_ok(len(joined), 0.15)
    for route in joined:
        turn, along = route.legs[0], route.legs[1]
        assert turn.start_xy_m == (240.0, STREET.y_min_m - SIDE_ROAD_M)  # the side street is on the right
        lane_y = along.start_xy_m[1]
        direction = 1 if along.end_xy_m[0] > along.start_xy_m[0] else -1
        # into a lane of its direction, TURN_M along the street from the entry
        assert any(lane.y_center_m == lane_y and lane.direction == direction for lane in STREET.lanes)
        assert turn.end_xy_m == (240.0 + direction * TURN_M, lane_y)


def test_classes_without_a_share_and_streets_without_entries_draw_as_before():
    plain = replace(STREET, side_entries=())
    for kind in ("animal", "pedestrian"):
        with_entries, rng_a = draws(kind)
        without, rng_b = draws(kind, street=plain)
        if kind == "animal":  # no share: the same routes and the same random stream
            assert [r for _, r in with_entries] == [r for _, r in without]
            assert rng_a.random() == rng_b.random()
        else:
            assert [r for _, r in with_entries] != [r for _, r in without]
    again, _ = draws("pedestrian")
    assert [r for _, r in again] == [r for _, r in draws("pedestrian")[0]]  # same seed, same routes


def test_joiners_walk_and_drive_their_routes_to_the_end_in_the_world():
    world = World(STREET, np.random.default_rng(0))
    spawned = {}
    for kind in ("pedestrian", "vehicle"):
        routes = [(t, r) for t, r in draws(kind)[0] if r.entry_key in ("side0sidewalk", "side1lane")][:3]
        for traits, route in routes:
            spawned[world.spawn(traits, route)] = route
    first_seen = {}
    for _ in range(int(400 * 30)):
        world.step(1.0 / 30.0)
        for a in world.states():
            first_seen.setdefault(a.object_id, (a.x_m, a.y_m))
        if world.removed_count == len(spawned):
            break
    assert world.removed_count == len(spawned)  # every one reached its route's end
    for oid, route in spawned.items():  # and entered where its stub or turn starts
        assert first_seen[oid] == pytest.approx(route.legs[0].start_xy_m, abs=0.5)
