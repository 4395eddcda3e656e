"""The city file: its errors name the file and the field before any street runs (exit code 2)."""

from __future__ import annotations

import pytest
import yaml

from citysim.city.spec import CityError, load_city
from citysim.city.streets import prepare_streets
from citysim.cli import main
from tests.citysim.city.conftest import write_city


def test_a_good_city_file_loads_and_the_city_overrides_site_and_costs(tmp_path):
    city_file = write_city(tmp_path)
    city = load_city(city_file)
    jobs = prepare_streets([tmp_path / s for s in city.streets], city, sample_s=45.0)
    assert [j.name for j in jobs] == ["elm", "oak", "ash"]
    for job in jobs:
        assert (job.year.latitude_deg, job.year.timezone, job.year.sample_s) == (51.2, "Europe/Berlin", 45.0)
        assert job.scenario.costs.energy_price_per_kwh == 0.3  # the street said 9.0
        assert job.scenario.costs.discount_rate == 0.05


def test_a_street_listed_twice_gets_a_second_name(tmp_path):
    city_file = write_city(tmp_path, streets=["elm.yaml", "elm.yaml"])
    city = load_city(city_file)
    jobs = prepare_streets([tmp_path / s for s in city.streets], city)
    assert [j.name for j in jobs] == ["elm", "elm-2"]
    assert jobs[0].fingerprint() == jobs[1].fingerprint()


@pytest.mark.parametrize(("change", "message"), [
    ({"stretes": ["elm.yaml"]}, r"stretes: unknown field; did you mean streets"),
    ({"streets": ["elm.yaml", "nope.yaml"]}, r"streets\.1: no scenario file .*nope\.yaml"),
    ({"streets": []}, r"give `streets:`"),
    ({"site": {"latitude_deg": 51, "longitude_deg": 7, "timezone": "Europe/Berln"}}, r"site\.timezone.*Europe/Berlin"),
    ({"costs": {"lifetime_year": 5}}, r"costs\.lifetime_year.*lifetime_years"),
    ({"osm": {"file": "missing.osm"}}, r"osm\.file: no file"),
])  # fmt: skip
def test_bad_city_files_name_the_field(tmp_path, change, message):
    city_file = write_city(tmp_path)
    data = {**yaml.safe_load(city_file.read_text()), **change}
    city_file.write_text(yaml.safe_dump(data))
    with pytest.raises(CityError, match=message):
        load_city(city_file)


def test_the_command_exits_2_before_any_work_and_writes_nothing(tmp_path, capsys):
    city_file = write_city(tmp_path / "in", costs={"discount_rte": 0.1})
    out = tmp_path / "out"
    assert main(["city", str(city_file), "--out", str(out), "--no-progress"]) == 2
    assert "costs.discount_rte" in capsys.readouterr().err
    assert not out.exists()
    good = write_city(tmp_path / "in2")
    assert main(["city", str(good), "--out", str(out), "--controllers", "pri", "--no-progress"]) == 2
    assert "pir" in capsys.readouterr().err  # the nearest valid name
    assert not out.exists()


def test_help_names_every_cost_field_with_its_default(capsys):
    from citysim.config.costs import CostsSpec

    with pytest.raises(SystemExit):
        main(["city", "--help"])
    text = capsys.readouterr().out
    for name in CostsSpec.model_fields:
        assert name in text
    assert "--scheduler" in text and "--min-lit-on-entry" in text and "(default 0.03)" in text
