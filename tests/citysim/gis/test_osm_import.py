"""Importing the hand-written OSM street (fixtures/teststrasse.osm).

The fixture's nodes lie at known local metres (x east, y north) from (51 N, 7 E): Teststraße runs
east 100 m from (0, 0) to (100, 0) (way 10), then north 80 m to (100, 80) (way 11, drawn from its
north end, so it is joined reversed). Its lamps stand at (30, 7), (70, -6.5), (107, 40); a lamp at
(50, 40) is 40 m away, one at (20, 7) says it belongs to Querstraße, and one at (85, 2) stands in
the road. Querstraße leaves south at (50, 0), a footway north at (50, 0), a service road east at
(100, 40). Hand-computed (s, d): s along, d left of the centreline (m).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from citysim.gis import GisInputError, import_osm, import_street, select_streets
from citysim.gis.osm import read_osm
from citysim.gis.osm_street import street_from_data

FIXTURE = Path(__file__).parent / "fixtures" / "teststrasse.osm"
#: Tolerance of a position against the hand computation: the fixture's degrees were made with
#: metres-per-degree figures good to ~1e-4, and the projection differs from them by < 1 cm here.
TOL_M = 0.5


@pytest.fixture(scope="module")
def street():
    return import_osm(FIXTURE, "Teststraße", lamps_within_m=15.0)


def test_two_ways_of_one_name_are_joined_with_the_reversed_one_turned(street):
    assert street.name == "Teststraße"
    assert "OSM ways 10, 11 (reversed)" in street.notes[0]
    xy = street.centreline_m
    assert xy[0] == (0.0, 0.0)
    assert xy[-1][0] == pytest.approx(100.0, abs=TOL_M) and xy[-1][1] == pytest.approx(80.0, abs=TOL_M)
    assert street.length_m == pytest.approx(180.0, abs=TOL_M)


def test_lamps_within_range_are_taken_at_their_hand_computed_s_and_d(street):
    expected = [(30.0, 7.0), (70.0, -6.5), (85.0, 2.0), (140.0, -7.0)]
    assert len(street.poles) == len(expected)
    for pole, (s, d) in zip(street.poles, expected, strict=True):
        assert pole.s_m == pytest.approx(s, abs=TOL_M) and pole.d_m == pytest.approx(d, abs=TOL_M)
    assert "osm node 101" in street.poles[0].ref
    assert street.poles[1].height_m == pytest.approx(4.5)  # the node's height tag


def test_a_lamp_mapped_in_the_road_stands_where_mapped_and_the_file_says_so(street):
    pole = street.poles[2]
    assert "osm node 106" in pole.ref and pole.d_m == pytest.approx(2.0, abs=TOL_M)
    assert "1 of 4 poles stand inside the lanes or walking room as mapped" in street.notes[-1]


def test_clear_poles_moves_a_lamp_mapped_in_the_road_to_the_walking_rooms_edge():
    moved = import_osm(FIXTURE, "Teststraße", clear_poles=True).poles[2]
    assert "osm node 106" in moved.ref and "mapped at d 2" in moved.ref
    # default cross-section: 2 lanes of 3 m, 2 m sidewalks at d +-4 m, 0.5 m verge step, 0.2 m clearance
    assert moved.d_m == pytest.approx(5.7, abs=0.01)


def test_side_entries_at_the_nodes_shared_with_other_highways(street):
    got = sorted((round(e.s_m), e.side, e.kind) for e in street.entries)
    assert got == [(50, "left", "path"), (50, "right", "junction"), (140, "right", "driveway")]
    junction = next(e for e in street.entries if e.kind == "junction")
    assert junction.name == "Querstraße" and dict(junction.share)["vehicle"] == pytest.approx(0.1)


def test_tags_set_the_speed_and_the_defaults_the_cross_section(street):
    assert street.cross.maxspeed_kmh == 30.0
    assert [lane[2] for lane in street.cross.lanes] == [-1, 1]  # right-hand traffic: d < 0 toward +s
    assert len(street.cross.sidewalks) == 2


def test_import_street_gives_the_scenario_data_of_the_contract():
    data = import_street(FIXTURE, "10")
    assert data["street"]["centreline_m"][0] == [0.0, 0.0]
    assert data["street"]["length_m"] == pytest.approx(180.0, abs=TOL_M)
    assert data["street"]["origin"]["latitude_deg"] == pytest.approx(51.0, abs=1e-7)
    assert {"s_m", "d_m", "ref"} <= set(data["lamps"]["poles"][0])
    assert data["traffic"]["classes"]["vehicle"]["speed_kmh"]["max"] == pytest.approx(33.0)
    assert "y_m" not in data["lamps"]


def test_lamps_within_a_smaller_range_leave_the_far_ones_out():
    near = street_from_data(read_osm(FIXTURE), "Teststraße", lamps_within_m=6.8)
    assert [round(p.s_m) for p in near.poles] == [70, 85]


def test_select_streets_lists_the_streets_with_enough_lamps():
    found = select_streets(FIXTURE, highway_classes=("residential",), min_lamps=2)
    assert [c.name for c in found] == ["Teststraße"]
    assert found[0].lamp_count == 4 and found[0].way_ids == (10, 11)
    assert found[0].length_m == pytest.approx(180.0, abs=TOL_M)


@pytest.mark.parametrize(("way", "within_m", "message"), [
    ("Testweg", 15.0, "nearest names: 'Teststraße'"),
    ("999", 15.0, "no highway way with that id"),
    ("Kurzweg", 15.0, "15.0 m long; a scenario street needs >= 30 m"),
    ("Schleife", 15.0, "crosses itself"),
    ("Teststraße", 1.0, "the nearest beside it stands 2.0 m from the centreline (--lamps-within 2.1"),
])
def test_bad_input_is_one_clear_error(way, within_m, message):
    with pytest.raises(GisInputError) as err:
        import_osm(FIXTURE, way, lamps_within_m=within_m)
    assert message in str(err.value)


def test_a_pbf_file_imports_as_its_xml(tmp_path):
    import osmium

    pbf = tmp_path / "teststrasse.osm.pbf"
    with osmium.SimpleWriter(str(pbf)) as writer:
        for obj in osmium.FileProcessor(str(FIXTURE)):
            writer.add(obj)
    from_pbf, from_xml = import_osm(pbf, "Teststraße"), import_osm(FIXTURE, "Teststraße")
    assert from_pbf.centreline_m == from_xml.centreline_m
    assert [(p.s_m, p.d_m) for p in from_pbf.poles] == [(p.s_m, p.d_m) for p in from_xml.poles]


def test_a_branch_that_turns_back_is_not_joined_into_the_street(tmp_path):
    # a same-name spur leaving Teststraße's end at (100, 80) back south-west, 170 deg from its heading
    text = FIXTURE.read_text().replace("</osm>", (
        '  <node id="40" lat="51.0002" lon="7.0012"/>\n'
        '  <way id="17"><nd ref="3"/><nd ref="40"/><tag k="highway" v="residential"/>'
        '<tag k="name" v="Teststraße"/></way>\n</osm>'))
    spur = tmp_path / "spur.osm"
    spur.write_text(text)
    assert import_osm(spur, "Teststraße").length_m == pytest.approx(180.0, abs=TOL_M)


def test_the_notes_give_the_approaches_before_and_after_the_lamp_zones(street):
    # lamps at s 30, 70, 85, 140 on 180 m: zones from 30 - 40/2 = 10 m to 140 + 55/2 = 167.5 m
    assert "approaches: 10.0 m before the first lamp zone, 12.5 m after the last" in street.notes


def test_a_scenario_name_spells_german_letters_out():
    from citysim.gis.imported import slug

    assert slug("Geißlerweg") == "geisslerweg"
    assert slug("Düsseldorfer Straße") == "duesseldorfer_strasse"  # ü as ue, not u
    assert slug("Rue de l'Église") == "rue_de_l_eglise"
