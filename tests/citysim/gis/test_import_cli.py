"""`citysim import osm|geojson` as a planner meets it: the files written, the committed real-street
scenarios current, and one clear error (exit 2, nothing written) for each kind of bad input."""

from __future__ import annotations

import shlex
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from citysim.cli import build_parser, main
from citysim.cli.import_ import import_text
from tests.citysim.gis.structure import contract_problems

REPO = Path(__file__).resolve().parents[3]
FIXTURES = Path(__file__).parent / "fixtures"
OSM = FIXTURES / "teststrasse.osm"
COMMITTED = sorted((REPO / "scenarios" / "osm").glob("*.yaml"))


def test_osm_import_writes_a_commented_scenario_and_its_picture(tmp_path, capsys):
    out = tmp_path / "sub" / "test.yaml"
    assert main(["import", "osm", str(OSM), "--way", "teststrasse", "--rate", "vehicle=12", "--out", str(out)]) == 0
    text = out.read_text()
    assert text.startswith("# Teststraße: imported by\n#   citysim import osm ")
    assert "--rate vehicle=12" in text.splitlines()[1]
    data = yaml.safe_load(text)
    assert contract_problems(data) == []
    assert data["traffic"]["classes"]["vehicle"]["rate_per_hour"] == 12.0
    assert len(data["lamps"]["poles"]) == 4 and len(data["street"]["side_entries"]) == 3
    png = out.with_suffix(".png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
    assert f"scenario written to {out}" in capsys.readouterr().out


def test_geojson_import_writes_a_scenario(tmp_path):
    out = tmp_path / "inv.yaml"
    argv = ["import", "geojson", "--street", str(FIXTURES / "inventarweg_street.geojson"),
            "--lamps", str(FIXTURES / "inventarweg_lamps.geojson"), "--no-picture", "--out", str(out)]
    assert main(argv) == 0
    data = yaml.safe_load(out.read_text())
    assert contract_problems(data) == []
    assert data["street"]["origin"]["crs"] == "EPSG:25832"
    assert [p.get("rated_power_w") for p in data["lamps"]["poles"]] == [35.0, None, 50.0]
    assert not out.with_suffix(".png").exists()


@pytest.mark.parametrize(("argv", "message"), [
    (["osm", str(OSM), "--way", "Testweg"], "nearest names: 'Teststraße'"),
    (["osm", str(OSM), "--way", "Teststraße", "--lamps-within", "1"], "the nearest beside it stands 2.0 m"),
    (["osm", str(OSM), "--way", "Kurzweg"], "a scenario street needs >= 30 m"),
    (["osm", str(OSM), "--way", "Schleife"], "crosses itself"),
    (["osm", str(FIXTURES / "missing.osm"), "--way", "x"], "not found"),
    (["osm", str(OSM), "--way", "Teststraße", "--rate", "car=3"], "unknown class 'car'"),
    (["osm", str(OSM), "--way", "Teststraße", "--timezone", "Europe/Berln"], "nearest: 'Europe/Berlin'"),
    (["geojson", "--street", str(FIXTURES / "only_points.geojson"), "--lamps", str(FIXTURES / "only_points.geojson")],
     "no LineString feature"),
    (["geojson", "--street", str(FIXTURES / "inventarweg_street.geojson"), "--lamps",
      str(FIXTURES / "inventarweg_lamps.geojson"), "--crs", "EPSG:999999"], "unknown CRS"),
])
def test_bad_input_is_one_error_line_exit_2_and_nothing_written(tmp_path, capsys, argv, message):
    out = tmp_path / "out" / "s.yaml"
    assert main(["import", *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and message in err and "\n" not in err
    assert not (tmp_path / "out").exists()


def test_an_out_file_that_is_not_yaml_is_refused(tmp_path, capsys):
    assert main(["import", "osm", str(OSM), "--way", "Teststraße", "--out", str(tmp_path / "s.txt")]) == 2
    assert "ending in .yaml" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_the_command_exits_2_as_a_process(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "citysim", "import", "osm", str(OSM), "--way", "Nowhere",
                           "--out", str(tmp_path / "s.yaml")], capture_output=True, text=True, cwd=REPO)
    assert proc.returncode == 2 and proc.stderr.startswith("error: --way 'Nowhere'")
    assert list(tmp_path.iterdir()) == []


def test_the_real_extract_gives_several_streets_with_many_lamps_and_a_curve():
    assert {p.stem for p in COMMITTED} >= {"geisslerweg", "kirchhoffweg", "dopplerweg"}
    data = {p.stem: yaml.safe_load(p.read_text()) for p in COMMITTED}
    assert len(data["geisslerweg"]["lamps"]["poles"]) == 11
    assert max(len(d["lamps"]["poles"]) for d in data.values()) >= 9
    from citysim.gis.geometry import sharpest_turn_deg

    turns = {k: sharpest_turn_deg([tuple(p) for p in d["street"]["centreline_m"]])[0] for k, d in data.items()}
    assert 60 < turns["kirchhoffweg"] <= 150


@pytest.mark.parametrize("path", COMMITTED, ids=[p.stem for p in COMMITTED])
def test_committed_imports_are_current_and_keep_the_contract(path, monkeypatch):
    text = path.read_text(encoding="utf-8")
    command = text.splitlines()[1].removeprefix("#").strip()
    assert command.startswith("citysim import ")
    monkeypatch.chdir(REPO)  # the command's paths are relative to the repository
    args = build_parser().parse_args(shlex.split(command)[1:])
    fresh, data, _ = import_text(args)
    assert fresh == text, f"{path.name} is stale: run `{command}` from the repository root"
    assert contract_problems(data) == []
