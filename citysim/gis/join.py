"""Choosing a street's ways in an OSM file and joining them into one chain of nodes.

OSM splits a street into several ways wherever a tag changes; consecutive ways of one name (and a
road class) that share an end node are joined, turning ways drawn the other way round. When the
name's ways form branches or separate pieces, the longest simple chain is taken.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from citysim.gis.errors import GisInputError, nearest_names
from citysim.gis.osm import OsmData, OsmWay

#: Highway classes that are streets a lamp chain may light (joined by name); others join only
#: ways of their own class.
ROAD_CLASSES = ("residential", "living_street", "unclassified", "tertiary", "secondary", "primary",
                "tertiary_link", "secondary_link", "primary_link", "road")
#: The sharpest turn from one way into the next that still continues the street, deg.
MAX_JOIN_TURN_DEG = 120.0
#: Most ways searched when a name's ways branch (a longer search takes the greedy chain).
MAX_SEARCH_STEPS = 20000


@dataclass(frozen=True)
class JoinedStreet:
    """A street's chain: its name, the ways in order (each with True when it runs reversed in the
    chain) and the node ids along the chain."""

    name: str
    ways: tuple[tuple[OsmWay, bool], ...]
    node_ids: tuple[int, ...]

    @property
    def way_ids(self) -> tuple[int, ...]:
        """The OSM way ids along the chain, each once."""
        return tuple(dict.fromkeys(w.id for w, _ in self.ways))


def way_length_m(data: OsmData, way: OsmWay) -> float:
    """A way's length on a sphere (m): a ranking figure only, not the imported geometry."""
    total = 0.0
    for a, b in zip(way.node_ids, way.node_ids[1:], strict=False):
        (lon1, lat1), (lon2, lat2) = data.nodes[a], data.nodes[b]
        dx = math.radians(lon2 - lon1) * math.cos(math.radians((lat1 + lat2) / 2))
        total += 6371008.8 * math.hypot(dx, math.radians(lat2 - lat1))
    return total


def split_at_shared(ways: list[OsmWay]) -> list[OsmWay]:
    """The ways cut at every inner node another of them also passes (a T or a loop of one name
    becomes pieces that join end to end); each piece keeps its way's id and tags."""
    count: dict[int, int] = {}
    for w in ways:
        for n in set(w.node_ids):
            count[n] = count.get(n, 0) + 1
    pieces = []
    for w in ways:
        start = 0
        for i in range(1, len(w.node_ids) - 1):
            if count[w.node_ids[i]] > 1:
                pieces.append(OsmWay(w.id, w.tags, w.node_ids[start:i + 1]))
                start = i
        pieces.append(OsmWay(w.id, w.tags, w.node_ids[start:]))
    return pieces


def _turn_deg(data: OsmData, a: int, b: int, c: int) -> float:
    """The change of direction (deg) at node b going a -> b -> c (local scale of longitude)."""
    (x1, y1), (x2, y2), (x3, y3) = (data.nodes[n] for n in (a, b, c))
    k = math.cos(math.radians(y2))
    h1, h2 = math.atan2(y2 - y1, (x2 - x1) * k), math.atan2(y3 - y2, (x3 - x2) * k)
    return abs(math.degrees((h2 - h1 + math.pi) % (2 * math.pi) - math.pi))


def _chains(ways: list[OsmWay], data: OsmData | None = None) -> list[list[tuple[OsmWay, bool]]]:
    """Every maximal simple chain through ways joined end to end, no node passed twice
    (depth-first, bounded)."""
    found: list[list[tuple[OsmWay, bool]]] = []
    steps = 0

    def extend(chain: list[tuple[OsmWay, bool]], used: set[int]) -> None:
        nonlocal steps
        steps += 1
        way, rev = chain[-1]
        end = way.node_ids[0] if rev else way.node_ids[-1]
        seen = {n for piece, _ in chain for n in piece.node_ids}
        nexts = [(w, w.node_ids[-1] == end) for w in ways
                 if id(w) not in used and end in (w.node_ids[0], w.node_ids[-1])
                 and not seen.intersection(w.node_ids[:-1] if w.node_ids[-1] == end else w.node_ids[1:])]
        if data is not None:  # a street goes on across a junction; it does not turn back into a branch
            before = way.node_ids[1] if rev else way.node_ids[-2]
            nexts = [(w, r) for w, r in nexts
                     if _turn_deg(data, before, end, w.node_ids[-2] if r else w.node_ids[1]) <= MAX_JOIN_TURN_DEG]
        if not nexts or steps > MAX_SEARCH_STEPS:
            found.append(list(chain))
            return
        for w, r in nexts[: 1 if steps > MAX_SEARCH_STEPS // 2 else None]:
            extend([*chain, (w, r)], used | {id(w)})

    for w in ways:
        for rev in (False, True):
            extend([(w, rev)], {id(w)})
    return found


def _nodes_of(chain: list[tuple[OsmWay, bool]]) -> tuple[int, ...]:
    nodes: list[int] = []
    for way, rev in chain:
        ids = way.node_ids[::-1] if rev else way.node_ids
        nodes.extend(ids if not nodes else ids[1:])
    return tuple(nodes)


def _select_ways(data: OsmData, way: str) -> tuple[str, list[OsmWay]]:
    """The name and the candidate ways ``way`` (a name or a way id) stands for."""
    if way.strip().isdigit():
        chosen = data.way_by_id(int(way))
        if chosen is None:
            raise GisInputError(f"--way {way}: no highway way with that id in {data.path}")
        if not chosen.name:
            return f"way {chosen.id}", [chosen]
        return chosen.name, [w for w in data.ways if w.name == chosen.name and _same_family(w, chosen)]
    named = [w for w in data.ways if w.name.casefold() == way.strip().casefold()]
    if not named:
        names = sorted({w.name for w in data.ways if w.name and w.highway in ROAD_CLASSES})
        hint = nearest_names(way, names)
        raise GisInputError(f"--way {way!r}: no highway of that name in {data.path}; "
                            + (f"nearest names: {hint}" if hint else f"{len(names)} named streets, e.g. {names[:3]}"))
    roads = [w for w in named if w.highway in ROAD_CLASSES]
    if roads:
        return roads[0].name, roads
    return named[0].name, [w for w in named if w.highway == named[0].highway]


def _same_family(w: OsmWay, chosen: OsmWay) -> bool:
    if chosen.highway in ROAD_CLASSES:
        return w.highway in ROAD_CLASSES
    return w.highway == chosen.highway


def join_street(data: OsmData, way: str) -> JoinedStreet:
    """The street ``way`` names (a name, case-insensitive, or a way id) as one chain of ways.

    A way id takes the longest chain of same-name ways through that way. A name takes the longest
    chain of its ways. Raises GisInputError naming the nearest names when the name is not found.
    """
    name, whole = _select_ways(data, way)
    ways = split_at_shared(whole)
    must = int(way) if way.strip().isdigit() else None
    lengths = {id(w): way_length_m(data, w) for w in ways}
    best: list[tuple[OsmWay, bool]] = []
    best_key = (-1.0, 0)
    for chain in _chains(ways, data):
        if must is not None and must not in {w.id for w, _ in chain}:
            continue
        # longest first; of a chain and its reverse, the one with fewer ways running backwards
        key = (round(sum(lengths[id(w)] for w, _ in chain), 6), -sum(r for _, r in chain))
        if key > best_key:
            best, best_key = chain, key
    return JoinedStreet(name, tuple(best), _nodes_of(best))
