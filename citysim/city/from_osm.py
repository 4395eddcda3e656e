"""The city file's ``osm:`` selection, through the OpenStreetMap import (``citysim.gis``).

``osm_street_files`` asks ``citysim.gis.select_streets(osm_path, highway_classes, min_lamps)`` for
the candidate streets (each with a ``name`` and its ``way_ids``), imports each by its first way's id
with ``citysim.gis.import_street(osm_path, way_id, lamps_within_m)`` into scenario data and writes it with ``citysim.gis.write_scenario(data,
path)`` to DIR/osm_streets/<name>.yaml: ordinary scenario files the planner can read and edit,
which the city then runs like the files it lists under ``streets:``. Names are made file-safe and
unique (``-2``, ``-3``, ... in the order the import returns them).
"""

from __future__ import annotations

import re
from pathlib import Path

from citysim.city.spec import OsmSelection, street_path
from citysim.gis import import_street, select_streets, write_scenario

OSM_DIR = "osm_streets"


def safe_name(name: str) -> str:
    """A file and scenario name from a street's name: letters, digits, ``_ . -`` only."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", str(name)).strip("_") or "street"


def osm_street_files(selection: OsmSelection, city_file: Path, out_dir: Path) -> list[Path]:
    """Import the selected ways of the extract into DIR/osm_streets/*.yaml; their paths, in import order."""
    osm_path = street_path(city_file, selection.file)
    folder = Path(out_dir) / OSM_DIR
    folder.mkdir(parents=True, exist_ok=True)
    paths: list[Path] = []
    taken: dict[str, int] = {}
    for candidate in select_streets(osm_path, tuple(selection.highway), selection.min_lamps,
                                    selection.lamps_within_m):
        name = safe_name(getattr(candidate, "name", None) or "street")
        taken[name] = taken.get(name, 0) + 1
        if taken[name] > 1:
            name = f"{name}-{taken[name]}"
        path = folder / f"{name}.yaml"
        # by the way's id, not the name: two streets of one name elsewhere in the extract stay apart
        write_scenario(import_street(osm_path, str(candidate.way_ids[0]), selection.lamps_within_m), path)
        paths.append(path)
    return paths
