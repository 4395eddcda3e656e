"""`citysim year` as a planner meets it: year.json, the monthly plot, report.html; bad input exits 2."""

from __future__ import annotations

import json

import pytest
import yaml

from citysim.cli import main

KEYS = ("energy_kwh_per_year", "cost_per_year", "co2_kg_per_year", "aeci_wh_per_m2", "lit_on_entry_rate",
        "dark_s_per_year", "monthly_energy_kwh", "savings_vs_always_on")


def test_year_writes_annual_figures_plot_and_report(toy_file, tmp_path, capsys):
    out = tmp_path / "year"
    assert main(["year", str(toy_file), "--out", str(out), "--workers", "1", "--no-progress",
                 "--controllers", "always_on,pir"]) == 0  # fmt: skip
    printed = capsys.readouterr().out
    result = json.loads((out / "year.json").read_text())
    assert list(result["controllers"]) == ["always_on", "oracle", "pir"]
    for figures in result["controllers"].values():
        assert all(k in figures for k in KEYS)
        assert sum(figures["monthly_energy_kwh"]) == pytest.approx(figures["energy_kwh_per_year"])
    always_on = result["controllers"]["always_on"]
    # two 60 W lamps over every dark hour of Berlin's 2025
    assert always_on["energy_kwh_per_year"] == pytest.approx(0.120 * result["dark_hours_per_year"], rel=1e-9)
    assert result["nights_with_darkness"] == 365 and result["fidelity"] == "fast"  # the default
    assert result["hour_runs"] == len(result["table"]["runs"]) == 1 + len(result["table"]["idle"])
    assert (out / "plots" / "monthly_energy.png").stat().st_size > 5000
    report = (out / "report.html").read_text()
    assert "<h2>A year</h2>" in report and "AECI" in report and "Energy per month." in report
    assert "results written to" in printed and str(out / "year.json") in printed and "Wh/m2" in printed
    # the darkness figures say how many measured entries they rest on: the level runs' per-hour
    # entries times the measured share of an hour
    (level,) = result["table"]["levels"].values()
    entries = round(level["always_on"]["zone_entries"] * result["sample_s"] / 3600)
    assert f"read from {entries:,} zone entries measured" in printed
    # ... and a 95 % interval of the rate from resampling their road users, beside the rate
    lo, hi = result["controllers"]["pir"]["lit_on_entry_interval_95"]
    assert lo <= result["controllers"]["pir"]["lit_on_entry_rate"] <= hi
    assert f"({100 * lo:.1f}-{100 * hi:.1f})" in printed and "95 % interval" in printed


def _no_year(tmp_path, toy_file):
    data = yaml.safe_load(toy_file.read_text())
    del data["year"]
    path = tmp_path / "no_year.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.parametrize(("extra", "needles"), [
    (["--timezone", "Europe/Berlni"], ["--timezone", "did you mean Europe/Berlin"]),
    (["--controllers", "always_on,pri"], ["controllers", "pir"]),
    (["--lat", "95"], ["--lat", "<= 90"]),
])
def test_bad_arguments_are_one_error_and_exit_2_before_any_work(toy_file, tmp_path, capsys, extra, needles):
    out = tmp_path / "year"
    assert _exit_code(["year", str(toy_file), "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert all(n in err for n in needles), err
    assert not out.exists()


def _exit_code(argv: list[str]) -> int:
    """main's return code, or argparse's exit code for an argument it refuses itself."""
    try:
        return main(argv)
    except SystemExit as exc:
        return exc.code


def test_a_bad_counts_file_names_file_line_and_field_and_leaves_no_output(toy_file, tmp_path, capsys):
    counts = tmp_path / "counts.csv"
    counts.write_text("date_or_weekday,hour,class,count\nmon,22,vehicle,3\nmon,25,vehicle,3\n")
    out = tmp_path / "year"
    assert main(["year", str(toy_file), "--out", str(out), "--counts", str(counts)]) == 2
    err = capsys.readouterr().err
    assert f"{counts}:3: hour" in err and "0..23" in err
    assert not out.exists()


def test_a_scenario_without_a_year_section_needs_the_site(toy_file, tmp_path, capsys):
    path = _no_year(tmp_path, toy_file)
    assert main(["year", str(path), "--out", str(tmp_path / "y")]) == 2
    assert "no `year:` section" in capsys.readouterr().err


def test_counts_from_another_year_are_refused_not_silently_unused(toy_file, tmp_path, capsys):
    counts = tmp_path / "counts.csv"
    counts.write_text("date_or_weekday,hour,class,count\n2024-01-05,22,vehicle,30\n")
    assert main(["year", str(toy_file), "--out", str(tmp_path / "y"), "--counts", str(counts)]) == 2
    err = capsys.readouterr().err
    assert "2024-01-05" in err and "2025" in err and "--year" in err
