"""An imported street (geometry, cross-section, lamps, side entries) and the scenario data it makes.

Both importers (OSM, GeoJSON) end in ``finish_street``, which checks the geometry against the
scenario schema's rules and places the poles, and ``scenario_data``, which lays the street out as
an ordinary scenario (the mapping `write_scenario` writes as commented YAML).
"""

from __future__ import annotations

import dataclasses
import re
import unicodedata
from dataclasses import dataclass

from citysim.gis.entries import SideEntry
from citysim.gis.errors import GisInputError
from citysim.gis.geometry import (
    MAX_TURN_DEG,
    clean_polyline,
    cumulative_s,
    self_intersection,
    sharpest_turn_deg,
)
from citysim.gis.lamps import Pole, clear_poles
from citysim.gis.tags import CrossSection
from citysim.gis.traffic import traffic_classes

#: Shortest street a scenario may have (the schema's street.length_m minimum), m.
MIN_LENGTH_M = 30.0
#: The camera written on every imported lamp: the paper's scene A camera (Logitech C920 without
#: its IR-cut filter; Table 2 intrinsics), inline so the file runs from wherever it is written.
CAMERA = {"name": "scene_a", "focal_mm": 3.67, "sensor_w_mm": 4.8, "sensor_h_mm": 3.6, "width_px": 424,
          "height_px": 240, "fps": 15.0, "tilt_deg": 15.0, "heading_deg": 0.0}
#: Assumed pole height without a surveyed one, m.
DEFAULT_POLE_HEIGHT_M = 5.0
LUMINAIRE = {"rated_power_w": 60.0, "dim_level": 0.2, "standby_power_w": 0.5, "ramp_up_s": 0.3,
             "fade_s": 1.0, "hold_s": 30.0, "sensing_power_w": 5.0}
#: The controllers an imported street's frontier is drawn from.
CONTROLLERS = ["always_on", "oracle", "pir", "detector_located"]


@dataclass(frozen=True)
class ImportedStreet:
    """A street ready to be written: name, centreline (x_m, y_m pairs, local east/north frame),
    origin of that frame (WGS84 deg), source CRS, source text, highway class, cross-section,
    poles, side entries, nearby ways for the picture (local polylines), notes for the file and
    the source's OSM way ids (empty for other sources)."""

    name: str
    centreline_m: tuple[tuple[float, float], ...]
    origin_deg: tuple[float, float]
    crs: str
    source: str
    highway: str
    cross: CrossSection
    poles: tuple[Pole, ...]
    entries: tuple[SideEntry, ...]
    context_m: tuple[tuple[tuple[float, float], ...], ...] = ()
    notes: tuple[str, ...] = ()
    way_ids: tuple[int, ...] = ()

    @property
    def length_m(self) -> float:
        return float(cumulative_s(list(self.centreline_m))[-1])


def checked_centreline(points: list[tuple[float, float]], name: str) -> tuple[tuple[float, float], ...]:
    """The centreline rounded to 1 cm with points < 0.5 m apart merged, or GisInputError when it is
    too short, crosses itself or turns back sharper than the schema allows."""
    if len(points) >= 3 and points[0] == points[-1]:
        raise GisInputError(f"street {name!r} is a closed ring; give one of its ways by id (--way ID)")
    pts = [(round(x, 2), round(y, 2)) for x, y in clean_polyline(points)]
    length = float(cumulative_s(pts)[-1]) if len(pts) > 1 else 0.0
    if length < MIN_LENGTH_M:
        raise GisInputError(f"street {name!r} is {length:.1f} m long; a scenario street needs >= {MIN_LENGTH_M:g} m")
    crossing = self_intersection(pts)
    if crossing is not None:
        raise GisInputError(f"street {name!r} crosses itself near ({crossing[0]:.1f}, {crossing[1]:.1f}) m "
                            "(local frame); import one of its ways (--way ID) or split the line")
    turn, at = sharpest_turn_deg(pts)
    if turn > MAX_TURN_DEG:
        raise GisInputError(f"street {name!r} turns {turn:.0f} deg at point {at}; a street may turn at most "
                            f"{MAX_TURN_DEG:g} deg at one point")
    return tuple(pts)


def plural(count: int, one: str, many: str) -> str:
    """'1 side entry', '4 side entries'."""
    return f"{count} {one if count == 1 else many}"


#: Letters spelled out in ASCII rather than stripped of their marks: German's umlauts and sharp s as
#: German writes them without (Geißlerweg -> Geisslerweg, Südring -> Suedring), and Latin letters
#: that Unicode's NFKD does not take apart into a base letter and a mark (ø, ł, æ, ...).
SPELLED_OUT = {
    "ß": "ss", "ẞ": "SS", "ä": "ae", "ö": "oe", "ü": "ue", "Ä": "Ae", "Ö": "Oe", "Ü": "Ue",
    "æ": "ae", "Æ": "Ae", "œ": "oe", "Œ": "Oe", "ø": "o", "Ø": "O", "ł": "l", "Ł": "L",
    "đ": "d", "Đ": "D", "ð": "d", "Ð": "D", "þ": "th", "Þ": "Th", "ı": "i",
}  # fmt: skip


def ascii_name(name: str) -> str:
    """``name`` in ASCII: the letters of ``SPELLED_OUT`` spelled out, every other accented letter
    without its accents (NFKD: é -> e, č -> c); characters with no ASCII form are dropped."""
    spelled = "".join(SPELLED_OUT.get(ch, ch) for ch in unicodedata.normalize("NFC", str(name)))
    return unicodedata.normalize("NFKD", spelled).encode("ascii", "ignore").decode()


def slug(name: str) -> str:
    """A scenario name from a street name: lower-case ASCII letters, digits and underscores
    (``ascii_name``: 'Geißlerweg' -> 'geisslerweg', 'Südring' -> 'suedring')."""
    return re.sub(r"[^A-Za-z0-9]+", "_", ascii_name(name)).strip("_").lower() or "street"


def finish_street(street: ImportedStreet, clear: bool = False) -> ImportedStreet:
    """The street with a note on the poles mapped inside the lanes or walking room; ``clear``
    moves those poles to the walking room's edge (their mapped offset kept in their ref)."""
    street = dataclasses.replace(street, notes=(*street.notes, _approaches(street)))
    cleared = clear_poles(list(street.poles), street.cross.lanes, street.cross.sidewalks)
    inside = sum(p.d_m != q.d_m for p, q in zip(cleared, street.poles, strict=True))
    if not inside:
        return street
    if clear:
        note = (f"{inside} of {len(cleared)} poles were mapped inside the lanes or walking room and stand at "
                "its edge here (--clear-poles; their mapped offset is in their ref)")
        return dataclasses.replace(street, poles=tuple(cleared), notes=(*street.notes, note))
    note = (f"{inside} of {len(cleared)} poles stand inside the lanes or walking room as mapped (a narrower "
            "street than the defaults, or a centreline drawn off-centre); --clear-poles moves them to its edge")
    return dataclasses.replace(street, notes=(*street.notes, note))


def _approaches(street: ImportedStreet) -> str:
    """A note on the stretches before the first lamp zone and after the last (half-way cuts)."""
    from citysim.gis.picture import zone_bounds_m

    zones = zone_bounds_m([p.s_m for p in street.poles], street.length_m)
    before, after = zones[0][0], street.length_m - zones[-1][1]
    short = " (road users entering at a street end with no approach appear inside a lamp zone)" \
        if min(before, after) < 1.0 else ""
    return f"approaches: {before:.1f} m before the first lamp zone, {after:.1f} m after the last{short}"


def _poles(street: ImportedStreet) -> list[dict]:
    out = []
    for p in street.poles:
        pole = {"s_m": p.s_m, "d_m": p.d_m}
        if p.height_m is not None:
            pole["height_m"] = p.height_m
        if p.rated_power_w is not None:
            pole["rated_power_w"] = p.rated_power_w
        out.append({**pole, "ref": p.ref})
    return out


def scenario_data(street: ImportedStreet, rates: dict[str, float] | None = None, timezone: str | None = None,
                  duration_s: float = 3600.0) -> dict:
    """The scenario mapping of an imported street (the scenario schema's fields, in file order).

    Parameters
    ----------
    street : the imported street.
    rates : arrivals per hour by road-user class replacing the highway class's defaults.
    timezone : IANA time zone of the site; when given, a `year:` section is written.
    duration_s : simulated seconds of a run, s.
    """
    lat, lon = street.origin_deg
    data = {
        "name": slug(street.name),
        "description": f"{street.name}, {street.length_m:.0f} m ({street.highway}), {len(street.poles)} surveyed "
                       f"lamps, {plural(len(street.entries), 'side entry', 'side entries')}; imported from {street.source}.",
        "seed": 1, "duration_s": duration_s, "start_hour": 22.0, "physics_hz": 30,
        "street": {
            "length_m": round(street.length_m, 2),
            "centreline_m": [list(p) for p in street.centreline_m],
            "origin": {"latitude_deg": round(lat, 7), "longitude_deg": round(lon, 7), "crs": street.crs},
            "source": street.source,
            "lanes": [{"y_center_m": d, "width_m": w, "direction": k} for d, w, k in street.cross.lanes],
            "sidewalks": [{"y_center_m": d, "width_m": w} for d, w in street.cross.sidewalks],
            "crossings_x_m": [],
            "side_entries": [{"s_m": e.s_m, "side": e.side, "name": e.name, "kind": e.kind, "share": dict(e.share)}
                             for e in street.entries],
        },
        "lamps": {"poles": _poles(street), "pole_height_m": DEFAULT_POLE_HEIGHT_M, "luminaire": dict(LUMINAIRE),
                  "camera": dict(CAMERA)},
        "traffic": {"classes": traffic_classes(street.highway, street.cross.maxspeed_kmh, rates)},
        "simulation": {"idle_frame_stride": 15},
        "controllers": list(CONTROLLERS),
    }
    if timezone:
        data["year"] = {"latitude_deg": round(lat, 5), "longitude_deg": round(lon, 5), "timezone": timezone}
    return data
