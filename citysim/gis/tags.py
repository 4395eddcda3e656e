"""A street's cross-section and speed limit from its OSM tags, with documented defaults.

Tags read (https://wiki.openstreetmap.org/wiki/Key:highway and the keys below):
lanes, width (carriageway, m), oneway, sidewalk / sidewalk:both / sidewalk:left / sidewalk:right,
sidewalk:width, maxspeed. Left and right are relative to the OSM way's own direction; the importer
swaps them for a way that runs reversed in the joined street.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from citysim.config.motion import MAX_SPEED_KMH
from citysim.config.street import MIN_LANE_WIDTH_M

#: Lane width without a width tag, by highway class, m (German RASt 06 residential lanes are
#: 2.75-3.25 m; a shared living street or service road is narrower).
LANE_WIDTH_M = {"living_street": 2.75, "service": 2.75, "tertiary": 3.25, "secondary": 3.25, "primary": 3.5}
DEFAULT_LANE_WIDTH_M = 3.0
#: Sidewalks without a sidewalk tag: on both sides, except where there usually are none.
NO_SIDEWALK_CLASSES = ("service", "track")
SIDEWALK_WIDTH_M = 2.0
#: Speed limit without a maxspeed tag, by highway class, km/h (German defaults: 50 in town,
#: walking pace on a living street, taken as 7 km/h).
MAXSPEED_KMH = {"living_street": 7.0, "service": 20.0}
DEFAULT_MAXSPEED_KMH = 50.0
#: maxspeed values that are words, km/h.
MAXSPEED_WORDS = {"walk": 7.0, "de:living_street": 7.0, "de:urban": 50.0, "de:zone30": 30.0,
                  "de:zone:30": 30.0, "de:bicycle_road": 30.0, "de:rural": 100.0}


@dataclass(frozen=True)
class CrossSection:
    """What the tags say about the street: lanes (d of centre m, width m, direction +1 toward
    increasing s), sidewalks (d of centre m, width m) and the speed limit (km/h)."""

    lanes: tuple[tuple[float, float, int], ...]
    sidewalks: tuple[tuple[float, float], ...]
    maxspeed_kmh: float
    notes: tuple[str, ...]


def metres(value: str | None) -> float | None:
    match = re.match(r"^\s*([0-9]+(?:\.[0-9]+)?)\s*(m)?\s*$", value or "")
    return float(match.group(1)) if match else None


def maxspeed_kmh(tags: dict[str, str], highway: str) -> tuple[float, str]:
    """The speed limit (km/h) from ``maxspeed`` and where it came from."""
    raw = tags.get("maxspeed", "").strip().lower()
    if match := re.match(r"^([0-9]+(?:\.[0-9]+)?)\s*(mph)?$", raw):
        value = float(match.group(1)) * (1.609344 if match.group(2) else 1.0)
        return value, f"maxspeed={tags['maxspeed']}"
    if raw in MAXSPEED_WORDS:
        return MAXSPEED_WORDS[raw], f"maxspeed={tags['maxspeed']}"
    zone = re.match(r"^[a-z]{2}:zone:?([0-9]+)$", raw)
    if zone:
        return float(zone.group(1)), f"maxspeed={tags['maxspeed']}"
    return MAXSPEED_KMH.get(highway, DEFAULT_MAXSPEED_KMH), f"default for highway={highway}"


def _sidewalk_sides(tags: dict[str, str], highway: str) -> tuple[bool, bool, str]:
    """(left, right, source) in the way's own direction; 'separate' sidewalks count as present."""
    yes = ("yes", "separate")
    side = tags.get("sidewalk", "").lower()
    if side in ("both", "left", "right", "no", "none", "separate"):
        if side == "separate":
            return True, True, "sidewalk=separate (mapped as footways; modelled beside the street)"
        return side in ("both", "left"), side in ("both", "right"), f"sidewalk={side}"
    both = tags.get("sidewalk:both", "").lower()
    left, right = tags.get("sidewalk:left", both).lower(), tags.get("sidewalk:right", both).lower()
    if left or right:
        return left in yes, right in yes, f"sidewalk:left={left or 'no'}, sidewalk:right={right or 'no'}"
    present = highway not in NO_SIDEWALK_CLASSES
    return present, present, f"default for highway={highway}"


def cross_section(tags: dict[str, str], highway: str, reversed_way: bool) -> CrossSection:
    """The cross-section of a street from the tags of its main way.

    Parameters
    ----------
    tags : the OSM tags of the way that makes up most of the street.
    highway : its highway class.
    reversed_way : True when that way runs against increasing s (left and right swap).
    """
    oneway = tags.get("oneway", "no").lower()
    one_dir = {"yes": 1, "true": 1, "1": 1, "-1": -1}.get(oneway)
    if one_dir is not None and reversed_way:
        one_dir = -one_dir
    count = int(tags["lanes"]) if tags.get("lanes", "").isdigit() and int(tags["lanes"]) > 0 else (1 if one_dir else 2)
    width = metres(tags.get("width"))
    lane_w = width / count if width else LANE_WIDTH_M.get(highway, DEFAULT_LANE_WIDTH_M)
    lane_w = round(min(max(lane_w, MIN_LANE_WIDTH_M), 6.0), 2)
    notes = [f"lanes: {count} ({'lanes=' + tags['lanes'] if 'lanes' in tags else 'default'}), "
             f"{lane_w:g} m wide ({'width=' + tags['width'] if width else 'default for highway=' + highway})"]
    half = count * lane_w / 2
    lanes = []
    for k in range(count):
        d = round(half - (k + 0.5) * lane_w, 2)
        # two-way: right-hand traffic, lanes right of the centreline (d < 0) run toward +s
        lanes.append((d, lane_w, one_dir if one_dir else (1 if d < 0 else -1)))
    left, right, source = _sidewalk_sides(tags, highway)
    if reversed_way:
        left, right = right, left
    walk_w = metres(tags.get("sidewalk:width")) or SIDEWALK_WIDTH_M
    walk_w = min(max(walk_w, 1.0), 10.0)
    sidewalks = [(sign * round(half + walk_w / 2, 2), walk_w) for sign, on in ((-1, right), (1, left)) if on]
    notes.append(f"sidewalks: {'left' if left else ''}{' and ' if left and right else ''}{'right' if right else ''}"
                 f"{'none' if not (left or right) else ''} ({source}), {walk_w:g} m wide")
    speed, speed_source = maxspeed_kmh(tags, highway)
    notes.append(f"speed limit {speed:g} km/h ({speed_source}); simulated vehicles keep to <= {MAX_SPEED_KMH:g} km/h")
    return CrossSection(tuple(lanes), tuple(sidewalks), speed, tuple(notes))
