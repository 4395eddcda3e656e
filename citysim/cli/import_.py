"""`citysim import osm|geojson ... --out SCENARIO.yaml`: a real street into an ordinary scenario file.

`osm FILE --way NAME_OR_ID` reads an OpenStreetMap file (XML, .osm.bz2 or PBF); `geojson --street
FILE --lamps FILE` reads a LineString street and a Point lamp inventory. Both write the commented
scenario (the command that made it at its top) and a top-down picture beside it (SCENARIO.png).
Bad input is one error line naming the argument or file, exit code 2, nothing written.
"""

from __future__ import annotations

import shlex
import sys
from pathlib import Path

from detector.cliargs import USAGE_EXIT, number
from detector.outdir import OutputDirError, check_output_file

ATTRIBUTION = "Map data (c) OpenStreetMap contributors, ODbL 1.0 (https://www.openstreetmap.org/copyright)"


def _rates(pairs: list[str]) -> dict[str, float]:
    """--rate CLASS=PER_HOUR pairs, checked against the road-user classes."""
    from citysim.config.kinds import AGENT_KINDS
    from citysim.gis.errors import GisInputError, nearest_names

    rates = {}
    for pair in pairs or []:
        cls, _, value = pair.partition("=")
        if cls not in AGENT_KINDS:
            hint = nearest_names(cls, list(AGENT_KINDS), 1) or ", ".join(AGENT_KINDS)
            raise GisInputError(f"--rate {pair}: unknown class {cls!r}; valid: {hint}")
        try:
            rates[cls] = float(value)
        except ValueError:
            raise GisInputError(f"--rate {pair}: give CLASS=PER_HOUR with a number >= 0, e.g. vehicle=20") from None
        if not 0 <= rates[cls] <= 20000:
            raise GisInputError(f"--rate {pair}: arrivals per hour must be within 0..20000")
    return rates


def _check_args(args) -> None:
    """Everything about the arguments that can be checked before any file is read."""
    from citysim.gis.errors import GisInputError

    if Path(args.out).suffix not in (".yaml", ".yml"):
        raise GisInputError(f"--out {args.out}: a scenario file name ending in .yaml")
    check_output_file(args.out)
    if args.timezone:
        from zoneinfo import ZoneInfo, ZoneInfoNotFoundError, available_timezones

        try:
            ZoneInfo(args.timezone)
        except (ZoneInfoNotFoundError, ValueError):
            from citysim.gis.errors import nearest_names

            hint = nearest_names(args.timezone, sorted(available_timezones()), 2)
            raise GisInputError(f"--timezone {args.timezone!r}: not an IANA time zone"
                                + (f"; nearest: {hint}" if hint else " (e.g. Europe/Berlin)")) from None
    _rates(args.rate)


def command_line(args) -> str:
    """The `citysim import` command that makes the same file (written at the file's top)."""
    if args.source == "osm":
        words = ["osm", str(args.file), "--way", str(args.way)]
    else:
        words = ["geojson", "--street", str(args.street), "--lamps", str(args.lamps)]
        words += ["--crs", args.crs] if args.crs else []
    words += ["--lamps-within", f"{args.lamps_within:g}"]
    for pair in args.rate or []:
        words += ["--rate", pair]
    words += ["--timezone", args.timezone] if args.timezone else []
    words += ["--clear-poles"] if args.clear_poles else []
    return "citysim import " + shlex.join([*words, "--out", str(args.out)])


def import_text(args):
    """Import what ``args`` name: (the scenario file's text, its data, the imported street)."""
    from citysim.gis.imported import scenario_data
    from citysim.gis.writer import scenario_text

    _check_args(args)
    if args.source == "osm":
        from citysim.gis.osm_street import import_osm

        street = import_osm(args.file, args.way, args.lamps_within, args.clear_poles)
    else:
        from citysim.gis.geojson import import_geojson

        street = import_geojson(args.street, args.lamps, args.crs, args.lamps_within, args.clear_poles)
    data = scenario_data(street, rates=_rates(args.rate), timezone=args.timezone)
    header = [f"{street.name}: imported by", f"  {command_line(args)}", ""]
    if "OpenStreetMap" in street.source:
        header += [ATTRIBUTION, ""]
    header += ["What the import read and assumed (see docs/guide/import.md for the defaults):"]
    header += [f"  - {note}" for note in street.notes]
    header += ["Units are in the field names (_m metres, _s seconds, _deg degrees, _w watts, _kmh speeds)."]
    return scenario_text(data, header), data, street


def cmd_import(args) -> int:
    from citysim.gis.errors import GisInputError
    from citysim.gis.imported import plural
    from citysim.gis.picture import blind_stretches_m, draw_street
    from citysim.gis.writer import write_text

    try:
        text, data, street = import_text(args)
    except (GisInputError, OutputDirError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return USAGE_EXIT
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    picture = out.with_suffix(".png")
    if not args.no_picture:
        draw_street(data, picture, street.context_m)
    write_text(text, out)
    blind, covered = blind_stretches_m(data)
    print(f"{street.name}: {street.length_m:.0f} m, {len(street.poles)} lamps, "
          f"{plural(len(street.entries), 'side entry', 'side entries')}; "
          f"cameras see {covered:.0%} of the centreline within 25 m ({len(blind)} blind stretches)")
    print(f"scenario written to {out}" + ("" if args.no_picture else f"; top-down picture: {picture}"))
    return 0


def _common(p) -> None:
    p.add_argument("--out", type=Path, required=True, help="the scenario file to write (.yaml); "
                   "the picture goes beside it (.png)")
    p.add_argument("--lamps-within", type=number(float, gt=0, le=100, unit="m"), default=15.0, metavar="M",
                   help="take lamps standing at most M m from the centreline")
    p.add_argument("--rate", action="append", metavar="CLASS=PER_HOUR",
                   help="arrivals per hour of a road-user class, replacing the highway class's default (repeat)")
    p.add_argument("--timezone", default=None, help="IANA time zone of the site (writes a `year:` section)")
    p.add_argument("--clear-poles", action="store_true",
                   help="move poles mapped inside the lanes or a sidewalk's walking room to its edge "
                        "(default: every pole stands where it was mapped)")
    p.add_argument("--no-picture", action="store_true", help="do not draw the top-down picture")
    p.set_defaults(func=cmd_import)


def add(sub) -> None:
    imp = sub.add_parser("import", help="a real street (OpenStreetMap or GeoJSON) into a scenario file",
                         description="Import a real street and its lamps into a commented scenario file.")
    srcs = imp.add_subparsers(dest="source", required=True, metavar="SOURCE", parser_class=type(imp),
                              help="where the street comes from: osm or geojson")
    osm = srcs.add_parser("osm", help="a street of an OpenStreetMap file (.osm, .osm.bz2, .pbf)",
                          description="Import a street of an OpenStreetMap file: its ways joined by name, "
                                      "highway=street_lamp nodes, side entries and tags.")
    osm.add_argument("file", type=Path, help="the OpenStreetMap file (.osm, .osm.bz2, .osm.gz, .pbf)")
    osm.add_argument("--way", required=True, metavar="NAME_OR_ID",
                     help="the street's name (consecutive ways of that name are joined) or an OSM way id")
    _common(osm)
    geo = srcs.add_parser("geojson", help="a GeoJSON street (LineString) and lamp inventory (Points)",
                          description="Import a street from a GeoJSON LineString and its lamps from GeoJSON Points.")
    geo.add_argument("--street", type=Path, required=True, help="GeoJSON with the centreline as a LineString")
    geo.add_argument("--lamps", type=Path, required=True, help="GeoJSON with the lamps as Points")
    geo.add_argument("--crs", default=None, help="CRS of both files when they do not say (default EPSG:4326)")
    _common(geo)
