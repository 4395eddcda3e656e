"""Import of real streets into scenario files: OpenStreetMap ways and street lamps, GeoJSON lamp inventories.

Owns reading GIS files, projecting them to a local east/north frame, and writing commented scenario YAML."""

from citysim.gis.candidates import StreetCandidate, select_streets
from citysim.gis.errors import GisInputError
from citysim.gis.geojson import import_geojson
from citysim.gis.imported import ImportedStreet, scenario_data
from citysim.gis.osm_street import import_osm, import_street
from citysim.gis.writer import write_scenario

__all__ = [
    "GisInputError",
    "ImportedStreet",
    "StreetCandidate",
    "import_geojson",
    "import_osm",
    "import_street",
    "scenario_data",
    "select_streets",
    "write_scenario",
]
