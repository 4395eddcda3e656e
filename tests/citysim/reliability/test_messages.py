"""Careless input gets one line naming what is wrong and what would be valid, exit 2, nothing written."""

from __future__ import annotations

import pytest

from citysim.cli import main
from tests.citysim.test_cli import tiny


def one_line(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err, err
    return err


def test_an_empty_scenario_file_says_it_is_empty(tmp_path, capsys):
    empty = tmp_path / "empty.yaml"
    empty.write_text("# nothing yet\n")
    assert main(["run", str(empty), "--out", str(tmp_path / "o")]) == 2
    line = one_line(capsys)
    assert "the file is empty" in line and "NoneType" not in line
    assert not (tmp_path / "o").exists()


def test_a_yaml_syntax_error_keeps_its_line_and_column(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\nseed: 3\nstreet:\n  length_m 100\n  lanes: [1\n")
    assert main(["run", str(bad), "--out", str(tmp_path / "o")]) == 2
    line = one_line(capsys)
    # "lanes:" (line 5, its colon at column 8) continues the plain scalar "length_m 100": a mapping value there
    assert line.startswith(f"error: {bad}: not valid YAML at line 5, column 8: mapping values"), line


def test_a_bad_timezone_blames_the_argument_and_suggests(tmp_path, capsys):
    scenario = str(tiny(tmp_path))
    assert main(["year", scenario, "--timezone", "Mars/Phobos", "--out", str(tmp_path / "y")]) == 2
    assert one_line(capsys).startswith("error: --timezone: unknown IANA time zone 'Mars/Phobos'; valid: ")
    assert main(["year", scenario, "--timezone", "Europe/Berln", "--out", str(tmp_path / "y")]) == 2
    assert "did you mean Europe/Berlin" in one_line(capsys)
    assert not (tmp_path / "y").exists()


@pytest.mark.parametrize("argv, expected", [
    (["run", "{s}", "--controllers", "pirr", "--out", "{o}"], "did you mean pir?"),
    (["rnu", "{s}"], "did you mean 'run'?"),
    (["run", "{s}", "--fidelity", "fsat", "--out", "{o}"], "did you mean 'fast'?"),
])  # fmt: skip
def test_near_misses_get_did_you_mean(tmp_path, capsys, argv, expected):
    scenario = str(tiny(tmp_path))
    argv = [a.format(s=scenario, o=tmp_path / "o") for a in argv]
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's own errors
        code = exc.code
    assert code == 2
    assert expected in one_line(capsys)
    assert not (tmp_path / "o").exists()


def test_a_misspelt_scenario_field_gets_the_nearest_one(tmp_path, capsys):
    scenario = tiny(tmp_path, **{"lamps.pole_heigth_m": 4.0})
    assert main(["run", str(scenario), "--out", str(tmp_path / "o")]) == 2
    assert "lamps.pole_heigth_m: unknown field; did you mean pole_height_m?" in one_line(capsys)
