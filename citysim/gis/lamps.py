"""Matching surveyed lamps to a street: each lamp projected onto the centreline as (s, d).

A lamp belongs to the street when it stands within ``within_m`` of the centreline, its foot lies
between the street's ends (a lamp beyond an end belongs to the street that continues there), and,
when it names a street itself (OSM ``object:street``), it names this one. Poles must stand clear
of the lanes and of the sidewalks' walking room: a mapped centreline is drawn to 1-2 m, so a pole
that would stand in the road is moved out to the edge of the walking room and its mapped offset
kept in its label.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from citysim.config.street import ROAD_STEP_M, VERGE_STEP_M
from citysim.gis.errors import GisInputError
from citysim.gis.geometry import project

#: Closest two poles may stand along the street (the scenario schema's rule), m.
MIN_POLE_GAP_M = 1.0
#: Clearance kept beyond the walking room when a pole is moved out of it, m.
POLE_CLEARANCE_M = 0.2


@dataclass(frozen=True)
class LampPoint:
    """A surveyed lamp in the local frame: label, position (x_m, y_m east/north), optional pole
    height (m), rated power (W) and the street it says it belongs to."""

    ref: str
    x_m: float
    y_m: float
    height_m: float | None = None
    rated_power_w: float | None = None
    street: str | None = None


@dataclass(frozen=True)
class Pole:
    """A lamp on the street: s_m along the centreline, d_m to its left (m), optional height (m)
    and power (W), and its label."""

    s_m: float
    d_m: float
    height_m: float | None
    rated_power_w: float | None
    ref: str


def _walking_room(lanes, sidewalks) -> list[tuple[float, float]]:
    """The d intervals (m) a pole may not stand in: lanes, sidewalks and their step-aside strips."""
    room = [(c - w / 2, c + w / 2) for c, w, _ in lanes]
    for c, w in sidewalks:
        out_step, in_step = (VERGE_STEP_M, ROAD_STEP_M)
        room.append((c - w / 2 - (in_step if c > 0 else out_step), c + w / 2 + (out_step if c > 0 else in_step)))
    return room


def clear_offset(d_m: float, lanes, sidewalks) -> float:
    """``d_m`` (m), or the nearest offset on the same side beyond the walking room when the pole
    would stand in a lane or on a sidewalk."""
    room = _walking_room(lanes, sidewalks)
    if not any(lo < d_m < hi for lo, hi in room):
        return d_m
    if d_m >= 0:
        return round(max(hi for _, hi in room) + POLE_CLEARANCE_M, 2)
    return round(min(lo for lo, _ in room) - POLE_CLEARANCE_M, 2)


def match_lamps(centreline, lamps: list[LampPoint], within_m: float, street_name: str) -> list[Pole]:
    """The lamps of the street, ordered by s, at least 1 m apart along it.

    Parameters
    ----------
    centreline : the street's polyline, (x_m, y_m) pairs in the local frame.
    lamps : every candidate lamp, in the same frame.
    within_m : the farthest a lamp may stand from the centreline, m.
    street_name : the street's name (lamps naming another street are left out).

    Raises GisInputError saying how far the nearest lamp is when none is in range.
    """
    if not lamps:
        raise GisInputError(f"no street lamps in the input to match to {street_name!r}")
    poles, nearest = [], math.inf
    for lamp in lamps:
        s, d, beyond = project(centreline, (lamp.x_m, lamp.y_m))
        named_other = lamp.street is not None and lamp.street.casefold() != street_name.casefold()
        if beyond > 0 or named_other:
            continue
        nearest = min(nearest, abs(d))
        if abs(d) <= within_m:
            poles.append(Pole(round(s, 2), round(d, 2), lamp.height_m, lamp.rated_power_w, lamp.ref))
    if not poles:
        far = (f"the nearest beside it stands {nearest:.1f} m from the centreline (--lamps-within "
               f"{math.ceil(nearest * 10 + 1e-6) / 10:g} would take it)") if nearest < math.inf else "none stands beside it (between its ends)"
        raise GisInputError(f"no street lamp within {within_m:g} m of {street_name!r}'s centreline; {far}")
    poles.sort(key=lambda p: (p.s_m, p.d_m, p.ref))
    spaced = [poles[0]]
    for p in poles[1:]:
        if p.s_m - spaced[-1].s_m < MIN_POLE_GAP_M:
            moved = round(spaced[-1].s_m + MIN_POLE_GAP_M, 2)
            p = Pole(moved, p.d_m, p.height_m, p.rated_power_w, f"{p.ref}, moved {moved - p.s_m:.2f} m along")
        spaced.append(p)
    return spaced


def clear_poles(poles: list[Pole], lanes, sidewalks) -> list[Pole]:
    """The poles with each one standing in a lane or on a sidewalk moved out beyond it (its
    mapped offset kept in its label)."""
    out = []
    for p in poles:
        d = clear_offset(p.d_m, lanes, sidewalks)
        ref = p.ref if d == p.d_m else f"{p.ref}, mapped at d {p.d_m:g} m"
        out.append(Pole(p.s_m, d, p.height_m, p.rated_power_w, ref))
    return out
