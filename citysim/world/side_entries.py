"""Side entries: road users who join the street mid-way from the side, or leave it there.

A scenario's ``street.side_entries`` give, per entry, the share of each class's arrivals that join
there and the same share that leaves there (``config.street_layout.SideEntrySpec``). An arrival's
route is first planned as if it came in at a street end (``world.traffic``); ``side_route`` then
draws, for a class with side shares, whether it joins at one of the entries (one uniform draw against
the cumulative shares) and, independently, whether it leaves at one (a second draw). A walker then
walks in from the verge on the entry's side along a short stub square to the street (crossing the
road, yielding, when its sidewalk is on the other side), and walks along its sidewalk; a road user
turns in from the side into its lane over ``TURN_M`` of street. Leaving is the same in reverse.
Animals (``verge_wander``) keep their own routes. Classes without side shares draw no random numbers,
so a street without side entries has the traffic it had without them.

Conventions: street coordinates (x read as s along the centreline, y as d to its left), metres;
leg offsets to the left of the direction of travel (``world.geometry``).
"""

from __future__ import annotations

import numpy as np

from citysim.config.kinds import AGENT_KINDS
from citysim.world.geometry import Leg, Route
from citysim.world.street import Street

#: A walker's stub from the verge starts this far beyond the street's outermost strip, m.
WALK_STUB_M = 3.0
#: A road user turning in starts this far beyond the street's outermost strip, m ...
SIDE_ROAD_M = 6.0
#: ... and reaches its lane this far along the street from the entry, m.
TURN_M = 6.0
#: Half-width of the band of a stub or a turn (room to get round someone), m.
STUB_HALF_BAND_M = 1.5
#: Route planners whose arrivals may use side entries.
SIDE_PLANNERS = ("sidewalk", "road_edge", "lane")


def _pick(shares: list[float], u: float) -> int | None:
    """The entry whose cumulative share first exceeds ``u`` (0..1), or None (a street end)."""
    total = 0.0
    for j, share in enumerate(shares):
        total += share
        if u < total:
            return j
    return None


def side_route(street: Street, kind: str, route: Route, rng: np.random.Generator) -> Route:
    """``route`` (planned from street end to street end) turned into one that joins and/or leaves
    at a side entry, drawn from the class ``kind``'s shares; ``route`` itself when neither is drawn,
    when the class has no side share, or when the entries leave no room to move along the street."""
    planner = AGENT_KINDS[kind].route
    shares = [entry.share.get(kind, 0.0) for entry in street.side_entries]
    if planner not in SIDE_PLANNERS or sum(shares) <= 0.0:
        return route
    join, leave = _pick(shares, float(rng.random())), _pick(shares, float(rng.random()))
    if join is None and leave is None:
        return route
    if join == leave:
        leave = None  # in and straight out again: it only joins
    first = route.legs[0]
    (x0, y0), (x1, _) = first.start_xy_m, first.end_xy_m
    direction = 1 if x1 > x0 else -1
    reach = -x0 if direction > 0 else x0 - street.length_m
    s_in = x0 if join is None else street.side_entries[join].s_m
    if leave is not None:
        s_out = street.side_entries[leave].s_m
        direction = 1 if s_out > s_in else -1
    else:
        s_out = street.length_m + reach if direction > 0 else -reach
    y_line, band, comfort, pref = y0, first.band_m, first.comfort_m, first.pref_m
    if direction != (1 if x1 > x0 else -1):
        if planner == "sidewalk":  # the other way along its sidewalk: the band mirrored, still keeping right
            band, comfort = (-band[1], -band[0]), (-comfort[1], -comfort[0])
            pref = float(np.clip(pref, *comfort))
        else:  # a lane of the other direction, if the street has one
            lanes = [lane for lane in street.lanes if lane.direction == direction]
            if not lanes:
                return route
            y_line = lanes[0].y_center_m
    return _legs(street, planner, (s_in, s_out, direction, y_line), (band, comfort, pref), (join, leave)) or route


def _legs(street: Street, planner: str, line: tuple, bands: tuple, ends: tuple) -> Route | None:
    """The route along ``line`` (s_in, s_out, direction, d of the path) with the leg ``bands`` (band,
    comfort, pref), a stub or turn at each side entry of ``ends`` (join, leave; None: a street end)."""
    s_in, s_out, direction, y_line = line
    join, leave = ends
    walker = planner == "sidewalk"
    ahead = 0.0 if walker else TURN_M
    along_in = s_in + direction * ahead if join is not None else s_in
    along_out = s_out - direction * ahead if leave is not None else s_out
    if (along_out - along_in) * direction < 1.0:
        return None
    legs = []
    if join is not None:
        legs.append(_side_leg(street, join, (s_in, y_line), (along_in, y_line), walker, inward=True))
    legs.append(Leg((along_in, y_line), (along_out, y_line), *bands))
    if leave is not None:
        legs.append(_side_leg(street, leave, (along_out, y_line), (s_out, y_line), walker, inward=False))
    key = f"side{join}{planner}" if join is not None else None
    return Route(tuple(legs), key or _end_key(planner, y_line, direction))


def _end_key(planner: str, y_line: float, direction: int) -> str:
    """The entry queue of a route that comes in at a street end and leaves at a side entry."""
    return f"{planner}{y_line:g}{'+' if direction > 0 else '-'}"


def _side_leg(street: Street, entry: int, at: tuple, along: tuple, walker: bool, inward: bool) -> Leg:
    """The stub (walker) or turn (road user) between side entry ``entry`` at (s, d) ``at`` and the
    point ``along`` on the agent's path; toward the street when ``inward``, else away from it."""
    spec = street.side_entries[entry]
    sign = spec.side_sign
    edge = street.y_max_m if sign > 0 else street.y_min_m
    outside = (at[0], edge + sign * (WALK_STUB_M if walker else SIDE_ROAD_M))
    start, end = (outside, along) if inward else (along, outside)
    crosses_road = walker and bool(street.lanes) and (along[1] - street.road_center_y_m) * sign < 0
    comfort = (-0.3, 0.3)
    return Leg(start, end, (-STUB_HALF_BAND_M, STUB_HALF_BAND_M), comfort, 0.0, yield_to_traffic=crosses_road)
