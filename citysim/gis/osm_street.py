"""Importing one street of an OpenStreetMap file: its joined ways, lamps, side entries and tags."""

from __future__ import annotations

from pathlib import Path

from citysim.gis.entries import raw_entries, with_shares
from citysim.gis.imported import (
    ImportedStreet,
    checked_centreline,
    finish_street,
    plural,
    scenario_data,
)
from citysim.gis.join import JoinedStreet, join_street, way_length_m
from citysim.gis.lamps import LampPoint, match_lamps
from citysim.gis.osm import OsmData, read_osm
from citysim.gis.projection import WGS84, LocalFrame
from citysim.gis.tags import cross_section, metres

#: Nearby ways drawn in the picture reach this far beyond the street's bounding box, m.
CONTEXT_MARGIN_M = 60.0


def _lamp_points(data: OsmData, frame: LocalFrame) -> list[LampPoint]:
    xy = frame.to_local([(lamp.lon_deg, lamp.lat_deg) for lamp in data.lamps])
    points = []
    for lamp, (x, y) in zip(data.lamps, xy, strict=True):
        kind = lamp.tags.get("lamp_type") or lamp.tags.get("light:method")
        ref = f"osm node {lamp.id}" + (f" ({kind})" if kind else "")
        points.append(LampPoint(ref, x, y, metres(lamp.tags.get("height")), None, lamp.tags.get("object:street")))
    return points


def _context(data: OsmData, frame: LocalFrame, centreline, own: set[int]) -> tuple:
    """Every other highway near the street, as local polylines (for the picture); ``own`` are the
    node ids of the street itself."""
    xs, ys = zip(*centreline, strict=True)
    lo_x, hi_x = min(xs) - CONTEXT_MARGIN_M, max(xs) + CONTEXT_MARGIN_M
    lo_y, hi_y = min(ys) - CONTEXT_MARGIN_M, max(ys) + CONTEXT_MARGIN_M
    out = []
    for way in data.ways:
        if own.issuperset(way.node_ids):
            continue
        pts = frame.to_local([data.nodes[n] for n in way.node_ids])
        if any(lo_x <= x <= hi_x and lo_y <= y <= hi_y for x, y in pts):
            out.append(tuple((round(x, 2), round(y, 2)) for x, y in pts))
    return tuple(out)


def _main_way(data: OsmData, joined: JoinedStreet):
    """The way making up most of the street, and whether it runs reversed in it (its tags rule)."""
    return max(joined.ways, key=lambda wr: (way_length_m(data, wr[0]), -wr[0].id))


def import_osm(osm_path: str | Path, way: str, lamps_within_m: float = 15.0, clear_poles: bool = False) -> ImportedStreet:
    """Import one street of an OSM file.

    Parameters
    ----------
    osm_path : an OSM XML (.osm, .osm.bz2) or PBF file.
    way : the street's name (case-insensitive; consecutive ways of that name are joined) or a way
        id (the chain of same-name ways through it).
    lamps_within_m : the farthest a highway=street_lamp node may stand from the centreline, m.
    clear_poles : move poles mapped inside the lanes or walking room to its edge.

    Returns
    -------
    ImportedStreet in a transverse Mercator frame whose origin is the street's first node.
    """
    return street_from_data(read_osm(osm_path), way, lamps_within_m, clear_poles=clear_poles)


def street_from_data(data: OsmData, way: str, lamps_within_m: float = 15.0, context: bool = True,
                     clear_poles: bool = False) -> ImportedStreet:
    """``import_osm`` on an OSM file already read (``read_osm``); ``context`` False leaves out the
    nearby ways (only the picture needs them)."""
    joined = join_street(data, str(way))
    lonlat = [data.nodes[n] for n in joined.node_ids]
    frame = LocalFrame(latitude_deg=lonlat[0][1], longitude_deg=lonlat[0][0])
    centreline = checked_centreline(frame.to_local(lonlat), joined.name)
    main, reversed_way = _main_way(data, joined)
    cross = cross_section(main.tags, main.highway, reversed_way)
    poles = match_lamps(list(centreline), _lamp_points(data, frame), lamps_within_m, joined.name)
    own = set(joined.way_ids)
    entries = with_shares(raw_entries(data, joined.node_ids, own, frame, list(centreline)))
    pieces = [f"{w.id}{' (reversed)' if r else ''}" for w, r in joined.ways]
    ways_text = ", ".join(p for i, p in enumerate(pieces) if i == 0 or p != pieces[i - 1])
    notes = (f"street: OSM way{'s' if len(joined.ways) > 1 else ''} {ways_text}, highway={main.highway}",
             *cross.notes,
             f"lamps: {len(poles)} highway=street_lamp nodes within {lamps_within_m:g} m of the centreline",
             f"side entries: {plural(len(entries), 'node', 'nodes')} shared with other highways")
    street = ImportedStreet(
        name=joined.name, centreline_m=centreline, origin_deg=(lonlat[0][1], lonlat[0][0]), crs=WGS84,
        source=f"OpenStreetMap way{'s' if len(joined.ways) > 1 else ''} {', '.join(map(str, joined.way_ids))} "
               "(Map data (c) OpenStreetMap contributors, ODbL 1.0)",
        highway=main.highway, cross=cross, poles=tuple(poles), entries=tuple(entries),
        context_m=_context(data, frame, centreline, set(joined.node_ids)) if context else (), notes=notes,
        way_ids=joined.way_ids)
    return finish_street(street, clear_poles)


def import_street(osm_path: str | Path, way_name_or_id: str, lamps_within_m: float = 15.0) -> dict:
    """The scenario data of one OSM street (see ``import_osm``; ``scenario_data`` for the layout)."""
    return scenario_data(import_osm(osm_path, way_name_or_id, lamps_within_m))
