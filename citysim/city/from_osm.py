"""The city file's ``osm:`` selection, through the OpenStreetMap import (``citysim.gis``).

``osm_street_files`` asks ``citysim.gis.select_streets(osm_path, highway_classes, min_lamps)`` for
the candidate streets (each with a ``name`` and its ``way_ids``), imports each by its first way's id
with ``citysim.gis.import_street(osm_path, way_id, lamps_within_m)`` into scenario data and writes it with ``citysim.gis.write_scenario(data,
path)`` to DIR/osm_streets/<name>.yaml: ordinary scenario files the planner can read and edit,
which the city then runs like the files it lists under ``streets:``. Names are made file-safe in
ASCII (``safe_name``: Geißlerweg -> Geisslerweg.yaml) and unique, also where the file system ignores
case (``-2``, ``-3``, ... in the order the import returns them). The copy an earlier import wrote
under the older rule (any letter outside A-Z as ``_``: Gei_lerweg.yaml) is removed, so a resumed city
folder holds one file per street; its streets/NAME/ folders (the scenario's name) are unchanged.
"""

from __future__ import annotations

import re
from pathlib import Path

from citysim.city.spec import OsmSelection, street_path
from citysim.gis import import_street, select_streets, write_scenario
from citysim.gis.imported import ascii_name

OSM_DIR = "osm_streets"


def safe_name(name: str) -> str:
    """A file name from a street's name: ASCII letters, digits and ``_ . -`` only, German letters
    spelled out and accents dropped (``citysim.gis.imported.ascii_name``), other runs of characters
    as one ``_``."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", ascii_name(name)).strip("_") or "street"


def legacy_name(name: str) -> str:
    """The file name an earlier import gave ``name`` (every character outside A-Z a-z 0-9 _ . - as
    ``_``, Geißlerweg -> Gei_lerweg): what ``osm_street_files`` replaces in an earlier city folder."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", str(name)).strip("_") or "street"


def unique_name(name: str, taken: set[str]) -> str:
    """``name``, or ``name-2``, ``name-3``, ... the first not in ``taken`` ignoring case (a file
    system that ignores case would write two such files as one); adds it to ``taken``."""
    candidate, count = name, 1
    while candidate.casefold() in taken:
        count += 1
        candidate = f"{name}-{count}"
    taken.add(candidate.casefold())
    return candidate


def osm_street_files(selection: OsmSelection, city_file: Path, out_dir: Path) -> list[Path]:
    """Import the selected ways of the extract into DIR/osm_streets/*.yaml; their paths, in import order."""
    osm_path = street_path(city_file, selection.file)
    folder = Path(out_dir) / OSM_DIR
    folder.mkdir(parents=True, exist_ok=True)
    paths: list[Path] = []
    taken: set[str] = set()
    counts: dict[str, int] = {}  # the earlier import's names: a repeated name got -2, -3, ...
    legacy: list[str] = []
    for candidate in select_streets(osm_path, tuple(selection.highway), selection.min_lamps,
                                    selection.lamps_within_m):
        street = getattr(candidate, "name", None) or "street"
        path = folder / f"{unique_name(safe_name(street), taken)}.yaml"
        old = legacy_name(street)
        counts[old] = counts.get(old, 0) + 1
        legacy.append(old if counts[old] == 1 else f"{old}-{counts[old]}")
        # by the way's id, not the name: two streets of one name elsewhere in the extract stay apart
        write_scenario(import_street(osm_path, str(candidate.way_ids[0]), selection.lamps_within_m), path)
        paths.append(path)
    for old in legacy:  # an earlier import's copy under the older name, unless a street has that name now
        if old.casefold() not in taken:
            (folder / f"{old}.yaml").unlink(missing_ok=True)
    return paths
