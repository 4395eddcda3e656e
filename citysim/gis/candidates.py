"""Finding the streets of an OSM file worth importing: named streets of given classes with lamps."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from citysim.gis.errors import GisInputError
from citysim.gis.osm import read_osm
from citysim.gis.osm_street import street_from_data

#: The classes a city's lit residential streets usually have.
RESIDENTIAL_CLASSES = ("residential", "living_street", "unclassified", "tertiary")


@dataclass(frozen=True)
class StreetCandidate:
    """A street of an OSM file that imports: its name, OSM way ids, highway class, length (m),
    number of lamps matched and side entries."""

    name: str
    way_ids: tuple[int, ...]
    highway: str
    length_m: float
    lamp_count: int
    side_entry_count: int


def select_streets(osm_path: str | Path, highway_classes: tuple[str, ...] = RESIDENTIAL_CLASSES,
                   min_lamps: int = 4, lamps_within_m: float = 15.0) -> list[StreetCandidate]:
    """The named streets of ``osm_path`` that import with at least ``min_lamps`` lamps.

    Parameters
    ----------
    osm_path : an OSM XML (.osm, .osm.bz2) or PBF file.
    highway_classes : the highway classes of the ways considered.
    min_lamps : fewest lamps a street must have.
    lamps_within_m : the farthest a lamp may stand from a centreline, m.

    Returns
    -------
    The candidates, most lamps first (then by name). Streets that do not import (too short,
    crossing themselves, no lamps in range) are left out.
    """
    data = read_osm(osm_path)
    names = sorted({w.name for w in data.ways if w.name and w.highway in highway_classes})
    found = []
    for name in names:
        try:
            street = street_from_data(data, name, lamps_within_m, context=False)
        except GisInputError:
            continue
        if len(street.poles) >= min_lamps and street.highway in highway_classes:
            found.append(StreetCandidate(street.name, street.way_ids, street.highway, round(street.length_m, 1),
                                         len(street.poles), len(street.entries)))
    return sorted(found, key=lambda c: (-c.lamp_count, c.name))
