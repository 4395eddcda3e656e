"""Importing a street and its lamp inventory from GeoJSON: a LineString street and Point lamps.

Coordinates are longitude/latitude (EPSG:4326, RFC 7946) unless the file's (pre-RFC 7946) `crs`
member or the ``crs`` argument names a projected CRS, such as a municipal inventory's ETRS89 / UTM.
Lamp properties read, first match wins: pole height from height_m, pole_height_m, height;
luminaire power from rated_power_w, power_w, wattage; label from ref, id, name.
"""

from __future__ import annotations

import json
from pathlib import Path

from citysim.gis.errors import GisInputError
from citysim.gis.imported import ImportedStreet, checked_centreline, finish_street
from citysim.gis.lamps import LampPoint, match_lamps
from citysim.gis.projection import WGS84, LocalFrame, crs_of, to_lonlat
from citysim.gis.tags import cross_section

HEIGHT_KEYS = ("height_m", "pole_height_m", "height")
POWER_KEYS = ("rated_power_w", "power_w", "wattage")
REF_KEYS = ("ref", "id", "name")


def _read(path: Path) -> dict:
    if not path.is_file():
        raise GisInputError(f"GeoJSON file {str(path)!r} not found")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, UnicodeDecodeError) as exc:
        raise GisInputError(f"GeoJSON file {str(path)!r} is not JSON ({exc})") from None
    if not isinstance(data, dict) or "type" not in data:
        raise GisInputError(f"GeoJSON file {str(path)!r} must be a GeoJSON object with a 'type'")
    return data


def _features(data: dict) -> list[tuple[dict, dict]]:
    """(geometry, properties) of every feature (a FeatureCollection, a Feature or a bare geometry)."""
    if data["type"] == "FeatureCollection":
        return [(f.get("geometry") or {}, f.get("properties") or {}) for f in data.get("features", [])]
    if data["type"] == "Feature":
        return [(data.get("geometry") or {}, data.get("properties") or {})]
    return [(data, {})]


def _file_crs(data: dict, path: Path, given: str | None):
    if given:
        return crs_of(given, "--crs")
    named = ((data.get("crs") or {}).get("properties") or {}).get("name")
    return crs_of(named, f"{path}: crs member") if named else crs_of(WGS84, "default")


def _number(props: dict, keys: tuple[str, ...], path: Path, i: int) -> float | None:
    for key in keys:
        if props.get(key) is not None:
            try:
                return float(props[key])
            except (TypeError, ValueError):
                raise GisInputError(f"{path}: lamp {i} property {key}={props[key]!r} is not a number") from None
    return None


def _street_line(path: Path, crs: str | None) -> tuple[list, str, dict]:
    data = _read(path)
    lines = [(g, p) for g, p in _features(data) if g.get("type") == "LineString"]
    if not lines:
        kinds = sorted({g.get("type", "none") for g, _ in _features(data)})
        raise GisInputError(f"--street {path}: no LineString feature (found: {', '.join(kinds) or 'nothing'}); "
                            "the street must be one LineString along its centreline")
    geom, props = lines[0]
    source_crs = _file_crs(data, path, crs)
    coords = [tuple(c[:2]) for c in geom.get("coordinates", [])]
    return _checked(to_lonlat(coords, source_crs), path, coords), source_crs.to_string(), props


def _checked(lonlat: list, path: Path, given: list) -> list:
    """``lonlat`` unless a point lies off the Earth (numbers of a projected CRS read as degrees)."""
    for (lon, lat), raw in zip(lonlat, given, strict=True):
        if not (-180 <= lon <= 180 and -90 <= lat <= 90):
            raise GisInputError(f"{path}: point {list(raw)} is not a longitude/latitude; name the file's CRS "
                                "(a `crs` member or --crs, e.g. EPSG:25832)")
    return lonlat


def import_geojson(street_path: str | Path, lamps_path: str | Path, crs: str | None = None,
                   lamps_within_m: float = 15.0, clear_poles: bool = False) -> ImportedStreet:
    """Import a street (GeoJSON LineString) and its lamps (GeoJSON Points).

    Parameters
    ----------
    street_path : GeoJSON with the street's centreline as its first LineString feature; its
        properties may carry name, highway and the OSM cross-section tags (lanes, width, ...).
    lamps_path : GeoJSON of Point lamps (a FeatureCollection); properties as the module says.
    crs : the CRS of both files when they do not say (default EPSG:4326, lon/lat).
    lamps_within_m : the farthest a lamp may stand from the centreline, m.
    clear_poles : move poles mapped inside the lanes or walking room to its edge.
    """
    street_path, lamps_path = Path(street_path), Path(lamps_path)
    lonlat, crs_name, props = _street_line(street_path, crs)
    name = str(props.get("name") or street_path.stem)
    frame = LocalFrame(latitude_deg=lonlat[0][1], longitude_deg=lonlat[0][0]) if lonlat else None
    if frame is None or len(lonlat) < 2:
        raise GisInputError(f"--street {street_path}: the LineString needs at least 2 points")
    centreline = checked_centreline(frame.to_local(lonlat), name)
    data = _read(lamps_path)
    lamp_crs = _file_crs(data, lamps_path, crs)
    points = [(g, p) for g, p in _features(data) if g.get("type") == "Point"]
    raw = [tuple(g["coordinates"][:2]) for g, _ in points]
    lonlats = _checked(to_lonlat(raw, lamp_crs), lamps_path, raw)
    lamps = []
    for i, ((_, p), xy) in enumerate(zip(points, frame.to_local(lonlats), strict=True)):
        ref = next((f"{k} {p[k]}" for k in REF_KEYS if p.get(k) is not None), f"lamp {i}")
        lamps.append(LampPoint(ref, xy[0], xy[1], _number(p, HEIGHT_KEYS, lamps_path, i),
                               _number(p, POWER_KEYS, lamps_path, i)))
    poles = match_lamps(list(centreline), lamps, lamps_within_m, name)
    highway = str(props.get("highway") or "residential")
    cross = cross_section({k: str(v) for k, v in props.items()}, highway, False)
    notes = (f"street: {street_path.name} ({crs_name}), lamps: {lamps_path.name}", *cross.notes,
             f"lamps: {len(poles)} of {len(lamps)} within {lamps_within_m:g} m of the centreline")
    street = ImportedStreet(name=name, centreline_m=centreline, origin_deg=(lonlat[0][1], lonlat[0][0]),
                            crs=crs_name, source=f"GeoJSON {street_path.name} and {lamps_path.name}",
                            highway=highway, cross=cross, poles=tuple(poles), entries=(), notes=notes)
    return finish_street(street, clear_poles)
