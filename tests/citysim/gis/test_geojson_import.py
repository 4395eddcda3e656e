"""Importing a GeoJSON street and lamp inventory in a projected CRS (fixtures/inventarweg_*.geojson).

Inventarweg runs 120 m east from (345000, 5650000) in ETRS89 / UTM 32N (EPSG:25832, named in the
files' `crs` member), then 90 m north. Lamps at (+20, -7), (+60, +8), (+113, +50) m from the start
and one far away (the third stands west of the northward leg: left, d > 0). s and d do not depend on the frame's rotation, and UTM's scale there (0.9996 x
~1.0002) changes lengths by < 0.02 %: hand-computed from the UTM metres within 0.5 m.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from citysim.gis import GisInputError, import_geojson

FIXTURES = Path(__file__).parent / "fixtures"
STREET, LAMPS = FIXTURES / "inventarweg_street.geojson", FIXTURES / "inventarweg_lamps.geojson"
TOL_M = 0.5


def test_a_projected_inventory_gives_lamps_at_their_hand_computed_s_and_d():
    street = import_geojson(STREET, LAMPS)
    assert street.name == "Inventarweg" and street.crs == "EPSG:25832"
    assert street.length_m == pytest.approx(210.0, abs=TOL_M)
    got = [(p.s_m, p.d_m) for p in street.poles]
    for (s, d), (s_hand, d_hand) in zip(got, [(20, -7), (60, 8), (170, 7)], strict=True):
        assert s == pytest.approx(s_hand, abs=TOL_M) and d == pytest.approx(d_hand, abs=TOL_M)
    assert len(got) == 3  # the lamp 300 m away is not this street's


def test_pole_height_and_power_come_from_the_properties():
    poles = import_geojson(STREET, LAMPS).poles
    assert [p.height_m for p in poles] == [4.0, 6.0, None]
    assert [p.rated_power_w for p in poles] == [35.0, None, 50.0]
    assert poles[0].ref == "ref L0"


def test_a_crs_flag_reads_files_without_a_crs_member(tmp_path):
    import json

    for src in (STREET, LAMPS):
        data = json.loads(src.read_text())
        data.pop("crs")
        (tmp_path / src.name).write_text(json.dumps(data))
    street = import_geojson(tmp_path / STREET.name, tmp_path / LAMPS.name, crs="EPSG:25832")
    assert [round(p.s_m) for p in street.poles] == [20, 60, 170]
    # read as longitude/latitude instead, the numbers are far outside the Earth: an error
    with pytest.raises(GisInputError):
        import_geojson(tmp_path / STREET.name, tmp_path / LAMPS.name)


def test_a_file_without_a_linestring_is_refused():
    with pytest.raises(GisInputError, match="no LineString feature \\(found: Point\\)"):
        import_geojson(FIXTURES / "only_points.geojson", LAMPS)


def test_an_unknown_crs_is_refused():
    with pytest.raises(GisInputError, match="--crs: unknown CRS 'EPSG:999999'"):
        import_geojson(STREET, LAMPS, crs="EPSG:999999")
