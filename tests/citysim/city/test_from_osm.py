"""The city file's `osm:` selection through the OpenStreetMap import (citysim.gis)."""

from __future__ import annotations

import yaml

from citysim.city.from_osm import safe_name, unique_name
from citysim.city.layout import lamp_sd_m
from citysim.city.run import CityOptions, city_jobs
from citysim.city.spec import load_city

#: One residential way of 200 m running east at 51.2 N with 5 street lamps 8 m north of it, and a
#: footway with none (which the selection must leave out).
TINY_OSM = """<?xml version='1.0' encoding='UTF-8'?>
<osm version="0.6" generator="citysim tests">
  <node id="1" lat="51.2000000" lon="6.8000000"/>
  <node id="2" lat="51.2000000" lon="6.8028700"/>
  <node id="3" lat="51.2010000" lon="6.8000000"/>
  <node id="4" lat="51.2010000" lon="6.8010000"/>
  {lamps}
  <way id="100"><nd ref="1"/><nd ref="2"/><tag k="highway" v="residential"/><tag k="name" v="{name}"/></way>
  <way id="101"><nd ref="3"/><nd ref="4"/><tag k="highway" v="footway"/></way>
</osm>
"""


def test_street_names_become_safe_file_names():
    assert safe_name("Dopplerweg / Am Hang") == "Dopplerweg_Am_Hang"
    assert safe_name("***") == "street"


def test_german_and_accented_letters_are_spelled_in_ascii():
    assert safe_name("Geißlerweg") == "Geisslerweg"  # not Gei_lerweg
    assert safe_name("Südring") == "Suedring" and safe_name("Öhrweg") == "Oehrweg"
    assert safe_name("Äußere Straße") == "Aeussere_Strasse"
    assert safe_name("Rue de l'Église") == "Rue_de_l_Eglise" and safe_name("Łódź") == "Lodz"
    # the same name typed with combining marks (NFD, as some editors save it) gives the same file
    assert safe_name("Su\u0308dring") == "Suedring"


def test_names_stay_unique_also_where_case_is_ignored():
    taken: set[str] = set()
    names = [unique_name(safe_name(n), taken) for n in ("Müllerweg", "Muellerweg", "MUELLERWEG", "Müllerweg-2")]
    assert names == ["Muellerweg", "Muellerweg-2", "MUELLERWEG-3", "Muellerweg-2-2"]
    assert len({n.casefold() for n in names}) == 4


def tiny_osm_city(tmp_path, street_name: str):
    """A city file over a hand-written extract: one residential street named ``street_name`` with five
    lamps along it, and a footway without lamps."""
    lamps = "\n  ".join(
        f'<node id="{10 + i}" lat="51.2000720" lon="{6.8002 + i * 0.0006:.7f}"><tag k="highway" v="street_lamp"/></node>'
        for i in range(5)
    )
    (tmp_path / "tiny.osm").write_text(TINY_OSM.format(lamps=lamps, name=street_name))
    city_file = tmp_path / "city.yaml"
    city_file.write_text(yaml.safe_dump({
        "osm": {"file": "tiny.osm", "highway": ["residential"], "min_lamps": 4},
        "site": {"latitude_deg": 51.2, "longitude_deg": 6.8, "timezone": "Europe/Berlin"},
    }))  # fmt: skip
    return city_file


def test_an_osm_city_imports_the_selected_ways_as_scenario_files(tmp_path):
    city_file = tiny_osm_city(tmp_path, "Elm Street")
    out = tmp_path / "out"
    jobs = city_jobs(load_city(city_file), city_file, out, CityOptions(controllers=("pir",)))
    assert len(jobs) == 1  # the footway has no lamps
    assert (out / "osm_streets").is_dir() and len(list((out / "osm_streets").glob("*.yaml"))) == 1
    assert len(lamp_sd_m(jobs[0].scenario)) == 5  # surveyed poles or a count: five lamps


def test_an_osm_street_with_a_sharp_s_is_written_under_its_spelled_name(tmp_path):
    city_file = tiny_osm_city(tmp_path, "Geißlerweg")
    out = tmp_path / "out"
    (out / "osm_streets").mkdir(parents=True)
    (out / "osm_streets" / "Gei_lerweg.yaml").write_text("an earlier import's copy\n")
    jobs = city_jobs(load_city(city_file), city_file, out, CityOptions(controllers=("pir",)))
    assert [p.name for p in (out / "osm_streets").glob("*.yaml")] == ["Geisslerweg.yaml"]
    assert jobs[0].source.endswith("Geisslerweg.yaml")
    assert jobs[0].name == "geisslerweg"  # the scenario's name: the street's folder under streets/
