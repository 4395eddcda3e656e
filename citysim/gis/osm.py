"""Reading an OpenStreetMap file (XML .osm, .osm.bz2, .osm.gz or PBF) into highways and street lamps.

pyosmium (`osmium`), the Python binding of libosmium maintained by the OSM tooling community, reads
all these formats with one call and streams them, so a city-sized PBF needs no XML parser of ours.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from citysim.gis.errors import GisInputError

#: File name endings pyosmium reads.
OSM_SUFFIXES = (".osm", ".osm.bz2", ".osm.gz", ".pbf", ".osm.pbf")


@dataclass(frozen=True)
class OsmWay:
    """One OSM way tagged highway=*: its id, tags and node ids in the way's own order."""

    id: int
    tags: dict[str, str] = field(hash=False)
    node_ids: tuple[int, ...]

    @property
    def highway(self) -> str:
        return self.tags.get("highway", "")

    @property
    def name(self) -> str:
        return self.tags.get("name", "")


@dataclass(frozen=True)
class OsmLamp:
    """One highway=street_lamp node: id, WGS84 position (deg) and tags."""

    id: int
    lon_deg: float
    lat_deg: float
    tags: dict[str, str] = field(hash=False)


@dataclass(frozen=True)
class OsmData:
    """What the importer needs of an OSM file: node positions (id -> (lon_deg, lat_deg)), the
    highway ways whose nodes are all present, and the street lamps."""

    path: Path
    nodes: dict[int, tuple[float, float]] = field(hash=False)
    ways: tuple[OsmWay, ...]
    lamps: tuple[OsmLamp, ...]

    def way_by_id(self, way_id: int) -> OsmWay | None:
        return next((w for w in self.ways if w.id == way_id), None)


def read_osm(path: str | Path) -> OsmData:
    """Read the highways and street lamps of an OSM file.

    Parameters
    ----------
    path : an OSM XML (.osm, .osm.bz2, .osm.gz) or PBF (.pbf) file.

    Returns
    -------
    OsmData; ways that reference nodes missing from the file keep only the nodes present.
    """
    import osmium

    path = Path(path)
    if not path.is_file():
        raise GisInputError(f"OSM file {str(path)!r} not found")
    if not str(path).lower().endswith(OSM_SUFFIXES):
        raise GisInputError(f"OSM file {str(path)!r}: unknown format; valid endings: {', '.join(OSM_SUFFIXES)}")
    nodes: dict[int, tuple[float, float]] = {}
    ways: list[OsmWay] = []
    lamps: list[OsmLamp] = []
    try:
        for obj in osmium.FileProcessor(str(path), osmium.osm.NODE | osmium.osm.WAY):
            if obj.is_node():
                if not obj.location.valid():
                    continue
                nodes[obj.id] = (obj.location.lon, obj.location.lat)
                if obj.tags.get("highway") == "street_lamp":
                    lamps.append(OsmLamp(obj.id, obj.location.lon, obj.location.lat, dict(obj.tags)))
            elif obj.is_way() and "highway" in obj.tags:
                ways.append(OsmWay(obj.id, dict(obj.tags), tuple(n.ref for n in obj.nodes)))
    except RuntimeError as exc:
        raise GisInputError(f"OSM file {str(path)!r} cannot be read ({exc})") from None
    present = tuple(
        OsmWay(w.id, w.tags, kept) for w in ways if len(kept := tuple(n for n in w.node_ids if n in nodes)) >= 2
    )
    if not present:
        raise GisInputError(f"OSM file {str(path)!r} holds no highway ways")
    return OsmData(path, nodes, present, tuple(lamps))
