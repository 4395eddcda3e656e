"""Annual sums: AECI by hand on a one-hour year, and how the table is read between and beyond levels."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import pytest

from citysim.year.annual import annual_figures, lit_area_m2
from citysim.year.table import ResponseTable, build_table
from citysim.year.twilight import HourPiece


def test_aeci_of_always_on_on_a_one_hour_year_is_the_hand_computed_one(toy):
    """Two 60 W lamps burning one hour: 120 Wh over a 60 m chain x 10.8 m = 648 m2."""
    one_hour = [(HourPiece(dt.date(2025, 1, 6), 22, 1.0), 1, 1.0)]
    table = build_table(toy, toy.year, [22], ["always_on"], workers=1, progress=False)
    assert table.labels == ["always_on", "oracle"]  # the bound is in every comparison
    figures = annual_figures(table, one_hour, toy, toy.year)
    assert lit_area_m2(toy, toy.year) == pytest.approx((648.0, 60.0, 10.8))
    always_on = figures["controllers"]["always_on"]
    assert always_on["energy_kwh_per_year"] == pytest.approx(0.120, rel=1e-9)
    assert always_on["aeci_wh_per_m2"] == pytest.approx(120.0 / 648.0, rel=1e-9)
    assert always_on["cost_per_year"] == pytest.approx(0.120 * 0.3, rel=1e-9)
    assert always_on["co2_kg_per_year"] == pytest.approx(0.120 * 0.4, rel=1e-9)
    assert always_on["monthly_energy_kwh"][0] == pytest.approx(0.120) and sum(always_on["monthly_energy_kwh"][1:]) == 0
    assert always_on["lit_on_entry_rate"] == 1.0 and always_on["dark_s_per_year"] == 0.0
    # the oracle lights only for the traffic: less than always-on, more than two idle dimmed lamps
    oracle = figures["controllers"]["oracle"]
    assert 0.0 < oracle["savings_vs_always_on"] < 1.0
    assert oracle["zone_entries_per_year"] == always_on["zone_entries_per_year"] > 0  # same traffic


def _figs(energy_kwh: float, entries: float = 0.0, lit: float = 0.0, dark_s: float = 0.0) -> dict:
    return {"energy_kwh": energy_kwh, "zone_entries": entries, "lit_entries": lit, "dark_s": dark_s}


def test_hours_add_idle_energy_and_what_their_traffic_costs_and_extend_past_the_top_level(toy):
    table = ResponseTable(
        reference_hour=22,
        levels={1.0: {"always_on": _figs(2.0, 10, 10), "clock": _figs(1.0, 10, 10)},
                2.0: {"always_on": _figs(3.0, 20, 20), "clock": _figs(1.0, 20, 20)}},
        idle={22: {"always_on": _figs(1.0), "clock": _figs(1.0)},
              3: {"always_on": _figs(1.0), "clock": _figs(0.5)}},  # "clock" dims at 03:00
        labels=["always_on", "clock"], cells=[])  # fmt: skip
    pieces = [(HourPiece(dt.date(2025, 1, 6), 22, 0.5), 1, 1.5),   # half an hour at level 1.5
              (HourPiece(dt.date(2025, 2, 7), 3, 1.0), 2, 3.0)]    # a whole hour above the table
    f = annual_figures(table, pieces, toy, toy.year)
    a = f["controllers"]["always_on"]
    # 0.5 h x (1 + 1.5) + 1 h x (1 + 3: the last segment, +1 kWh per level, goes on)
    assert a["monthly_energy_kwh"][:2] == pytest.approx([1.25, 4.0])
    assert a["zone_entries_per_year"] == pytest.approx(0.5 * 15 + 1.0 * 30)
    assert f["dark_hours_above_table"] == pytest.approx(1.0)
    c = f["controllers"]["clock"]
    assert c["energy_kwh_per_year"] == pytest.approx(0.5 * 1.0 + 1.0 * 0.5)  # traffic adds nothing
    assert c["reads_clock"] and c["lit_on_entry_rate"] is None and c["dark_s_per_year"] is None
    assert not a["reads_clock"] and a["lit_on_entry_rate"] == pytest.approx(1.0)


def test_the_table_is_the_same_bit_for_bit_in_one_process_or_two(toy):
    one = build_table(toy, toy.year, [22, 23], ["pir"], workers=1, progress=False)
    two = build_table(toy, toy.year, [22, 23], ["pir"], workers=2, progress=False)
    assert one.levels == two.levels and one.idle == two.idle
    assert one.levels[1.0]["pir"]["zone_entries"] > 0  # the level run saw traffic in its window


def test_a_fast_year_runs_every_cell_on_the_scenarios_own_sensor_model(toy, monkeypatch):
    from citysim.sim import compare
    from citysim.year import table as year_table
    from tests.citysim.fast.synthetic import constant_model

    looked_up = []
    model = constant_model(0.3)
    monkeypatch.setattr(year_table, "sensor_model_for", lambda scenario, **kw: looked_up.append(scenario) or model)
    monkeypatch.setattr(compare, "sensor_model_for", lambda *a, **k: pytest.fail("a cell looked up a model of its own"))
    table = build_table(toy, toy.year, [22, 23], ["detector_located"], workers=1, fidelity="fast", progress=False)
    assert looked_up == [toy]  # once, for the scenario itself
    assert set(table.idle) == {22, 23} and table.levels  # idle cells and traffic levels ran on it


def test_an_idle_cell_alone_would_key_a_model_of_its_own():
    # why the year hands its cells the scenario's model: with no traffic, suburban_night's e-scooters
    # drop out of the kinds its key hashes, and a cell's own lookup calibrated a model on empty nights
    from citysim.config.scenario import load_scenario
    from citysim.sim.calibration import calibration_key
    from citysim.year.table import Cell, cell_variant

    suburban = load_scenario(Path(__file__).resolve().parents[3] / "scenarios" / "suburban_night.yaml")
    idle = cell_variant(suburban, Cell("idle", 0.0, 2.0, 10.0, 60.0))
    assert calibration_key(idle, 120.0, 2) != calibration_key(suburban, 120.0, 2)


def _tallied_table(objects: list[tuple[int, int]]) -> ResponseTable:
    """One traffic level whose figures are its road users' (entries, lit entries) summed."""
    entries, lit = sum(e for e, _ in objects), sum(v for _, v in objects)
    return ResponseTable(reference_hour=22, levels={1.0: {"pir": _figs(2.0, entries, lit)}},
                         idle={22: {"pir": _figs(1.0)}}, labels=["pir"], cells=[],
                         tallies={1.0: {"pir": objects}})  # fmt: skip


def test_the_lit_on_entry_interval_resamples_road_users_and_narrows_with_more_of_them(toy):
    from citysim.metrics.intervals import wilson_interval

    pieces = [(HourPiece(dt.date(2025, 1, 6), 22, 1.0), 1, 0.8), (HourPiece(dt.date(2025, 1, 7), 22, 1.0), 1, 1.6)]

    def figures(objects):
        return annual_figures(_tallied_table(objects), pieces, toy, toy.year)["controllers"]["pir"]

    # two road users, one lit in both its zones, one dark in both: two trials, not four entries
    two = figures([(2, 2), (2, 0)])
    assert two["lit_on_entry_rate"] == pytest.approx(0.5)
    assert two["lit_on_entry_interval_95"] == pytest.approx(wilson_interval(0.5, 2.0), abs=0.03)
    # 98 of 100 lit: a few points wide around the rate, and drawn the same each time
    many = [(1, 1)] * 98 + [(1, 0)] * 2
    lo, hi = figures(many)["lit_on_entry_interval_95"]
    assert 0.90 < lo < 0.98 < hi < 1.0
    assert figures(many)["lit_on_entry_interval_95"] == (lo, hi)
    # everyone lit: resampling shows no spread, so the road users count as the trials (n = 50, not 150)
    lo, hi = figures([(3, 3)] * 50)["lit_on_entry_interval_95"]
    assert hi == 1.0 and lo == pytest.approx(wilson_interval(1.0, 50.0)[0]) and 0.9 < lo < 0.95


def test_the_level_weights_give_the_years_sums(toy):
    from citysim.year.annual import level_weights

    table = ResponseTable(
        reference_hour=22,
        levels={1.0: {"pir": _figs(2.0, 10, 9)}, 2.0: {"pir": _figs(3.0, 24, 20)}},
        idle={h: {"pir": _figs(1.0)} for h in (22, 23, 3)}, labels=["pir"], cells=[])  # fmt: skip
    pieces = [(HourPiece(dt.date(2025, 1, 6), 22, 0.5), 1, 1.5), (HourPiece(dt.date(2025, 2, 7), 3, 1.0), 2, 3.0),
              (HourPiece(dt.date(2025, 3, 7), 23, 1.0), 3, 0.4)]  # between, above and below the levels
    weights = level_weights(table, pieces)
    f = annual_figures(table, pieces, toy, toy.year)["controllers"]["pir"]
    assert weights @ [10, 24] == pytest.approx(f["zone_entries_per_year"], rel=1e-12)
    assert (weights @ [9, 20]) / (weights @ [10, 24]) == pytest.approx(f["lit_on_entry_rate"], rel=1e-12)
    assert f["lit_on_entry_interval_95"] is None  # a table without road users' tallies has none
