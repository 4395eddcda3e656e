"""Side entries of an OSM street: the nodes it shares with other highways, where road users join and
leave mid-street, each with the share of each class that uses it.

The kind of an entry comes from the other way's highway class (a registry, KIND_OF_HIGHWAY); the
shares from its kind (SHARES). An entry is on the side of the street the other way leaves toward;
a way crossing the street gives one entry on each side.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from citysim.gis.geometry import point_at, project
from citysim.gis.join import ROAD_CLASSES
from citysim.gis.osm import OsmData

#: The kind of side entry each highway class makes; other classes make none.
KIND_OF_HIGHWAY = {
    **{h: "junction" for h in ROAD_CLASSES},
    **{h: "path" for h in ("footway", "path", "cycleway", "pedestrian", "steps", "bridleway", "track")},
    "service": "driveway",
}
#: Assumed share of each class's arrivals that join at one entry of a kind (the same share leaves
#: there): a side street brings a tenth of everyone, a path a twentieth of those on foot or bike, a
#: driveway a few cars. Guesses to be replaced with counts.
SHARES = {
    "junction": {"pedestrian": 0.1, "group": 0.1, "cyclist": 0.1, "vehicle": 0.1, "e_scooter": 0.1},
    "path": {"pedestrian": 0.05, "group": 0.05, "cyclist": 0.05, "e_scooter": 0.05},
    "driveway": {"pedestrian": 0.02, "vehicle": 0.05},
}
#: Most of one class's arrivals the entries together may take (the scenario schema's limit).
MAX_SHARE_SUM = 0.9
#: Entries closer than this to a street end are the end itself, m.
END_MARGIN_M = 1.0


@dataclass(frozen=True)
class SideEntry:
    """Where road users join and leave: s_m (m along the centreline), side (left | right), the
    entry's name, kind (junction | path | driveway) and each class's share of arrivals."""

    s_m: float
    side: str
    name: str
    kind: str
    share: tuple[tuple[str, float], ...]


def _side(heading_rad: float, dx: float, dy: float) -> str:
    cross = math.cos(heading_rad) * dy - math.sin(heading_rad) * dx
    return "left" if cross > 0 else "right"


def raw_entries(data: OsmData, chain_nodes: tuple[int, ...], own_ways: set[int], frame, centreline) -> list[dict]:
    """Entries at the street's inner nodes shared with other highways (before shares are set):
    dicts of s_m, side, name, kind."""
    inner = set(chain_nodes[1:-1])
    length = project(centreline, centreline[-1])[0]
    found: dict[tuple[float, str, str], set[str]] = {}
    for way in data.ways:
        kind = KIND_OF_HIGHWAY.get(way.highway)
        if way.id in own_ways or kind is None or not inner.intersection(way.node_ids):
            continue
        for i, node in enumerate(way.node_ids):
            if node not in inner:
                continue
            here = frame.to_local([data.nodes[node]])[0]
            s, _, _ = project(centreline, here)
            if s < END_MARGIN_M or s > length - END_MARGIN_M:
                continue
            heading = point_at(centreline, s)[2]
            for j in (i - 1, i + 1):
                if 0 <= j < len(way.node_ids) and way.node_ids[j] not in chain_nodes:
                    there = frame.to_local([data.nodes[way.node_ids[j]]])[0]
                    side = _side(heading, there[0] - here[0], there[1] - here[1])
                    name = way.name or f"{way.highway} way {way.id}"
                    found.setdefault((round(s, 1), side, kind), set()).add(name)
    return [{"s_m": s, "side": side, "kind": kind, "name": " / ".join(sorted(names))}
            for (s, side, kind), names in sorted(found.items())]


def with_shares(entries: list[dict]) -> list[SideEntry]:
    """The entries with their kinds' shares, scaled down per class so no class's shares sum above
    MAX_SHARE_SUM."""
    totals: dict[str, float] = {}
    for e in entries:
        for cls, share in SHARES[e["kind"]].items():
            totals[cls] = totals.get(cls, 0.0) + share
    scale = {cls: min(1.0, MAX_SHARE_SUM / total) for cls, total in totals.items()}
    return [SideEntry(e["s_m"], e["side"], e["name"], e["kind"],
                      tuple((cls, math.floor(share * scale[cls] * 1000) / 1000) for cls, share in SHARES[e["kind"]].items()))
            for e in entries]
