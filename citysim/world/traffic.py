"""Traffic: who arrives when (Poisson per class and hour) and which way they go.

``arrivals(env, world, spec, rng)`` is a simpy process: a non-homogeneous
Poisson process (thinning, Lewis & Shedler 1979) at the class rate times its
hourly profile; each arrival is drawn (``draw_arrival``) and spawned into the
world. Routes, by planner name (``ROUTE_PLANNERS``; each kind's record names its
planner, ``citysim.config.kinds.AgentKind.route``):

* "sidewalk" (pedestrians, groups): enter at either street end on either sidewalk and
  keep right; a share crosses the road, at a marked crossing or anywhere,
  some diagonally, then walks on (or back) on the other sidewalk;
* "road_edge" (cyclists): ride near the right edge of a lane in its direction;
* "lane" (vehicles): keep a lane in its direction;
* "verge_wander" (animals): come out of the verge, wander across the street and leave.

Conventions: world frame of docs/design/architecture.md; leg offsets are metres to the left of
the direction of travel (see ``citysim.world.geometry``).
"""

from __future__ import annotations

from collections.abc import Callable, Generator
from dataclasses import replace

import numpy as np
import simpy

from citysim.config.kinds import AGENT_KINDS
from citysim.config.motion import KMH_PER_MPS, DrawOptions, SpeedDistribution
from citysim.config.scenario import Scenario
from citysim.config.traffic import TrafficClassSpec
from citysim.world.agents import AgentTraits, draw_agent
from citysim.world.geometry import Leg, Route
from citysim.world.physics import World
from citysim.world.side_entries import side_route
from citysim.world.street import Lane, Sidewalk, Street

__all__ = ["ROUTE_PLANNERS", "arrivals", "draw_arrival", "start_traffic"]

#: Walkers enter and leave this far beyond the street ends (fully outside), m.
ENTRY_MARGIN_M = 0.3
#: Clearance walkers keep from a sidewalk's edges when not passing anyone, m.
EDGE_CLEARANCE_M = 0.05
#: Half-width of the strip a crossing walker keeps to, m; ...
CROSSING_HALF_WIDTH_M = 0.8
#: ... and how far aside its centre may step to get round a car stopped in its way, m.
CROSSING_DETOUR_M = 2.5


def _along_x(street: Street, y_m: float, direction: int, reach_m: float) -> tuple[tuple, tuple]:
    """Start and end points of a whole-street leg at height ``y_m``."""
    x0, x1 = -reach_m, street.length_m + reach_m
    return ((x0, y_m), (x1, y_m)) if direction > 0 else ((x1, y_m), (x0, y_m))


def _offsets(y_lo: float, y_hi: float, y_line: float, direction: int) -> tuple[float, float]:
    """World y-interval -> offset interval (left of travel) for a leg along +-x at ``y_line``."""
    a, b = (y_lo - y_line) * direction, (y_hi - y_line) * direction
    return (min(a, b), max(a, b))


def _sidewalk_leg(
    street: Street,
    sw: Sidewalk,
    start_x: float,
    end_x: float,
    width_m: float,
    rng: np.random.Generator,
) -> Leg:
    direction = 1 if end_x > start_x else -1
    room_lo, room_hi = street.walking_room_m(sw)
    half = width_m / 2
    band = _offsets(room_lo + half, room_hi - half, sw.y_center_m, direction)
    c_lo = sw.y_center_m - sw.width_m / 2 + half + EDGE_CLEARANCE_M
    c_hi = sw.y_center_m + sw.width_m / 2 - half - EDGE_CLEARANCE_M
    if c_lo > c_hi:  # wider than the sidewalk: comfortable only in its middle
        c_lo = c_hi = sw.y_center_m
    comfort = _offsets(c_lo, c_hi, sw.y_center_m, direction)
    # keep right: the middle of the right half, give or take
    pref = float(np.clip(-sw.width_m / 4 + rng.uniform(-0.15, 0.15), *comfort))
    return Leg((start_x, sw.y_center_m), (end_x, sw.y_center_m), band, comfort, pref)


def _walker_route(
    street: Street, spec: TrafficClassSpec, rng: np.random.Generator, night: bool
) -> tuple[AgentTraits, Route]:
    i = int(rng.integers(len(street.sidewalks)))
    sw = street.sidewalks[i]
    room_lo, room_hi = street.walking_room_m(sw)
    # two groups must be able to pass each other in the walking room
    traits = draw_agent(
        spec.kind,
        rng,
        spec.draw_options(night=night, max_group_width_m=(room_hi - room_lo) / 2 - 0.1),
    )
    direction = 1 if rng.random() < 0.5 else -1
    reach = max(traits.length_m, traits.width_m) / 2 + ENTRY_MARGIN_M
    (x_in, _), (x_out, _) = _along_x(street, sw.y_center_m, direction, reach)
    entry = f"sidewalk{i}{'+' if direction > 0 else '-'}"
    center = street.road_center_y_m
    across = [s for s in street.sidewalks if (s.y_center_m - center) * (sw.y_center_m - center) < 0]
    if not across or rng.random() >= spec.crossing_fraction:
        return traits, Route((_sidewalk_leg(street, sw, x_in, x_out, traits.width_m, rng),), entry)

    other = min(across, key=lambda s: abs(s.y_center_m - sw.y_center_m))
    lo, hi = 10.0, street.length_m - 10.0
    if street.crossings_x_m and rng.random() < spec.marked_crossing_fraction:
        x_cross = float(rng.choice(street.crossings_x_m))
        x_land = x_cross
    else:
        x_cross = float(rng.uniform(lo, hi))
        # half of those crossing anywhere cut the corner, diagonally up to 6 m
        x_land = x_cross + direction * float(rng.uniform(0.0, 6.0)) * (rng.random() < 0.5)
        x_land = float(np.clip(x_land, lo, hi))
    onward = direction if rng.random() < 0.7 else -direction
    x_end = street.length_m + reach if onward > 0 else -reach
    comfort = min(0.3, max(0.0, CROSSING_HALF_WIDTH_M - traits.width_m / 2))
    crossing = Leg(
        (x_cross, sw.y_center_m), (x_land, other.y_center_m),
        (-CROSSING_DETOUR_M, CROSSING_DETOUR_M), (-comfort, comfort),
        float(np.clip(-0.2, -comfort, comfort)), yield_to_traffic=True,
    )  # fmt: skip
    legs = (
        _sidewalk_leg(street, sw, x_in, x_cross, traits.width_m, rng),
        crossing,
        _sidewalk_leg(street, other, x_land, x_end, traits.width_m, rng),
    )
    return traits, Route(legs, entry)


def _lane_leg(street: Street, lane: Lane, traits: AgentTraits, band, comfort, pref) -> Leg:
    reach = traits.length_m / 2 + ENTRY_MARGIN_M
    start, end = _along_x(street, lane.y_center_m, lane.direction, reach)
    return Leg(start, end, band, comfort, pref)


def _road_edge_route(street: Street, spec: TrafficClassSpec, rng: np.random.Generator, night: bool):
    i = int(rng.integers(len(street.lanes)))
    lane = street.lanes[i]
    traits = draw_agent(spec.kind, rng, spec.draw_options(night=night))
    edge = -lane.width_m / 2  # the right edge of the lane, as an offset
    lo = edge + traits.width_m / 2 + 0.15
    pref = edge + max(0.6, traits.width_m / 2 + 0.3)
    leg = _lane_leg(street, lane, traits, (lo, 0.3), (lo, -0.2), pref)
    return traits, Route((leg,), f"lane{i}")


def _lane_route(street: Street, spec: TrafficClassSpec, rng: np.random.Generator, night: bool):
    i = int(rng.integers(len(street.lanes)))
    lane = street.lanes[i]
    traits = draw_agent(spec.kind, rng, spec.draw_options(night=night))
    slack = max(0.0, lane.width_m / 2 - traits.width_m / 2 - 0.1)
    # may swing up to 0.3 m over the centre line to pass a cyclist
    leg = _lane_leg(street, lane, traits, (-slack, slack + 0.4), (-slack, slack), 0.0)
    return traits, Route((leg,), f"lane{i}")


#: Half-width of a wandering animal's band, m: room to get round the longest road user stopped
#: across its path, either way (with +-1.5 m, an animal and a car that stopped for it each waited
#: for the other for good: a dead-lock found at ten times suburban_night's traffic).
WANDER_HALF_BAND_M = max(k.sizes.length_m[1] for k in AGENT_KINDS.values() if k.road_user) + 1.0


def _verge_wander_route(street: Street, spec: TrafficClassSpec, rng: np.random.Generator, night: bool):
    traits = draw_agent(spec.kind, rng, spec.draw_options(night=night))
    edges = [(s.y_center_m - s.width_m / 2, s.y_center_m + s.width_m / 2) for s in street.sidewalks]
    edges += [
        (ln.y_center_m - ln.width_m / 2, ln.y_center_m + ln.width_m / 2) for ln in street.lanes
    ]
    y_lo, y_hi = min(e[0] for e in edges), max(e[1] for e in edges)
    side = 1.0 if rng.random() < 0.5 else -1.0
    verge = {1.0: y_hi + 1.5, -1.0: y_lo - 1.5}
    x = float(rng.uniform(10.0, street.length_m - 10.0))
    points = [(x, verge[side])]
    for _ in range(int(rng.integers(1, 3))):
        x = float(np.clip(x + rng.uniform(-8.0, 8.0), 2.0, street.length_m - 2.0))
        points.append((x, float(rng.uniform(y_lo, y_hi))))
    end_side = -side if rng.random() < 0.7 else side
    points.append(
        (float(np.clip(x + rng.uniform(-5.0, 5.0), 2.0, street.length_m - 2.0)), verge[end_side])
    )
    legs = tuple(
        Leg(a, b, (-WANDER_HALF_BAND_M, WANDER_HALF_BAND_M), (-0.1, 0.1), 0.0)
        for a, b in zip(points[:-1], points[1:], strict=True)
        if a != b
    )
    return traits, Route(legs, "verge")  # one entry queue for all that come out of the verge


#: Route planners by name (``AgentKind.route``): (street, spec, rng, night) -> (traits, route).
ROUTE_PLANNERS: dict[str, Callable[..., tuple[AgentTraits, Route]]] = {
    "sidewalk": _walker_route,
    "road_edge": _road_edge_route,
    "lane": _lane_route,
    "verge_wander": _verge_wander_route,
}


def draw_arrival(
    street: Street, spec: TrafficClassSpec, rng: np.random.Generator, *, night: bool = True
) -> tuple[AgentTraits, Route]:
    """One arriving agent of ``spec``'s class: its looks, speed and route (joining or leaving at a
    side entry for the street's share of its class, ``world.side_entries``)."""
    traits, route = ROUTE_PLANNERS[AGENT_KINDS[spec.kind].route](street, spec, rng, night)
    if street.side_entries:
        route = side_route(street, spec.kind, route, rng)
    return traits, route


def arrivals(
    env: simpy.Environment,
    world: World,
    spec: TrafficClassSpec,
    rng: np.random.Generator,
    *,
    night: bool = True,
) -> Generator:
    """simpy process: Poisson arrivals of one class at ``spec.rate_per_s(env.now)``, spawned into ``world``.

    Thinning: candidate events at the peak rate, each kept with probability
    rate(t) / peak, which is exact for a piecewise-constant hourly profile.
    """
    peak = spec.max_rate_per_s
    if peak <= 0:
        return
    while True:
        yield env.timeout(float(rng.exponential(1.0 / peak)))
        if rng.random() * peak < spec.rate_per_s(env.now):
            world.spawn(*draw_arrival(world.street, spec, rng, night=night))


def scripted_arrival(street: Street, agent, night: bool) -> tuple[AgentTraits, Route]:
    """The traits and route of one scripted agent (``citysim.config.traffic.ScriptedAgent``).

    Its looks are the middle of its class's Table 1 ranges, so a scripted run is the same
    whatever the random traffic does; it keeps its lane or sidewalk from end to end.
    """
    kind = AGENT_KINDS[agent.cls]
    speed_mps = agent.speed_kmh / KMH_PER_MPS
    # the typical agent of its kind: lit at night when most of its kind are
    light = (night and kind.lit_share >= 0.5) if agent.light_on is None else agent.light_on
    fixed = np.random.default_rng(0)  # the looks of a scripted agent never depend on the scenario seed
    drawn = draw_agent(agent.cls, fixed, DrawOptions(speed=SpeedDistribution(speed_mps, speed_mps), night=night))
    traits = replace(
        drawn,
        # a group's width is its formation's, drawn with its members
        width_m=float(np.mean(kind.width_m)) if kind.body.recipe != "group" else drawn.width_m,
        height_m=float(np.mean(kind.height_m)),
        desired_speed_mps=speed_mps,
        light_on=light,
    )
    if kind.road_user:
        lane = replace(street.lanes[agent.path], direction=agent.direction)
        band = (-0.2, 0.2)
        leg = _lane_leg(street, lane, traits, band, band, 0.0)
        return traits, Route((leg,), f"lane{agent.path}")
    sw = street.sidewalks[agent.path]
    reach = max(traits.length_m, traits.width_m) / 2 + ENTRY_MARGIN_M
    (x_in, _), (x_out, _) = _along_x(street, sw.y_center_m, agent.direction, reach)
    leg = _sidewalk_leg(street, sw, x_in, x_out, traits.width_m, fixed)
    return traits, Route((leg,), f"sidewalk{agent.path}{'+' if agent.direction > 0 else '-'}")


def scripted_arrivals(env: simpy.Environment, world: World, scenario: Scenario) -> Generator:
    """simpy process: spawn the scenario's scripted agents at their times."""
    for agent in sorted(scenario.traffic.scripted, key=lambda a: a.t_s):
        yield env.timeout(max(0.0, agent.t_s - env.now))
        world.spawn(*scripted_arrival(world.street, agent, scenario.night))


def start_traffic(
    env: simpy.Environment, world: World, scenario: Scenario, rng: np.random.Generator
) -> list[simpy.Process]:
    """Start one arrival process per class with traffic, each on its own child generator
    (so adding a class, or a renderer drawing noise, never reshuffles another class)."""
    specs = scenario.traffic.classes.all()
    children = rng.spawn(len(specs))
    processes = [
        env.process(arrivals(env, world, spec, child, night=scenario.night))
        for spec, child in zip(specs, children, strict=True)
        if spec.rate_per_hour > 0
    ]
    if scenario.traffic.scripted:
        processes.append(env.process(scripted_arrivals(env, world, scenario)))
    return processes
