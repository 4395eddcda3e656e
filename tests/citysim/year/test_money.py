"""Money figures against always-on, checked against numbers worked out by hand."""

from __future__ import annotations

import pytest

from citysim.config.costs import CostsSpec
from citysim.config.scenario import ScenarioError, scenario_from_mapping
from citysim.year.money import Prices, hardware_of, money_figures, npv, payback_years, prices_of
from tests.citysim.year.conftest import toy_mapping

COSTS = CostsSpec(camera_node_per_pole=200, controller_node_per_pole=100, pir_sensor_per_pole=50,
                  installation_per_pole=100, camera_maintenance_per_pole_year=10,
                  controller_maintenance_per_pole_year=5, pir_maintenance_per_pole_year=2,
                  lifetime_years=3, discount_rate=0.1, energy_price_per_kwh=0.5,
                  energy_price_change_per_year=0.0, grid_kg_co2_per_kwh=0.4)  # fmt: skip


def test_hand_computed_payback_and_npv_of_a_camera_street():
    # 4 poles; camera node 200 + controller 100 + installation 100 = 400 per pole -> capex 1600;
    # upkeep (10 + 5) x 4 = 60 a year; 2000 kWh saved x 0.5 = 1000 a year -> net 940 a year.
    # payback 1600 / 940 = 1.7021 y; NPV = -1600 + 940/1.1 + 940/1.21 + 940/1.331 = 854.545 + 776.860 + 706.236 - 1600 = 737.64
    prices = prices_of(COSTS)
    money = money_figures({"always_on": 5000.0, "detector_located": 3000.0}, {}, 4, COSTS, prices)
    cam = money["detector_located"]
    assert cam["capex"] == pytest.approx(1600.0)
    assert cam["opex_per_year"] == pytest.approx(60.0)
    assert cam["money_saved_per_year"] == pytest.approx(940.0)
    assert cam["payback_years"] == pytest.approx(1600 / 940)
    assert cam["npv"] == pytest.approx(-1600 + 940 / 1.1 + 940 / 1.21 + 940 / 1.331)
    assert cam["npv"] == pytest.approx(737.64, abs=0.01)
    assert cam["co2_avoided_kg_over_lifetime"] == pytest.approx(2000 * 0.4 * 3)
    # the reference: nothing invested, nothing saved, and no payback at all (null, not 0 years)
    assert money["always_on"] == {"capex": 0.0, "opex_per_year": 0.0, "money_saved_per_year": 0.0,
                                  "payback_years": None, "npv": 0.0, "co2_avoided_kg_over_lifetime": 0.0}


def test_the_oracle_is_a_bound_with_no_capex_payback_or_npv():
    # 4 poles; the oracle saves 2500 kWh: 2500 x 0.5 = 1250 a year, with no upkeep (nothing to keep)
    prices = prices_of(COSTS)
    money = money_figures({"always_on": 5000.0, "oracle": 2500.0, "oracle_seen": 2600.0}, {}, 4, COSTS, prices)
    for bound in ("oracle", "oracle_seen"):
        figures = money[bound]
        assert figures["capex"] is None and figures["opex_per_year"] is None
        assert figures["payback_years"] is None and figures["npv"] is None
    assert money["oracle"]["money_saved_per_year"] == pytest.approx(1250.0)
    assert money["oracle"]["co2_avoided_kg_over_lifetime"] == pytest.approx(2500 * 0.4 * 3)


def test_price_escalation_shortens_payback_and_raises_npv():
    # saving 100 kWh x 1.0 = 100 in year 1, 200 in year 2 (price doubles), 400 in year 3; no upkeep:
    # capex 250 is reached in year 2 after 100 of year 1: 1 + 150/200 = 1.75 y
    prices = Prices(price_per_kwh=1.0, kg_co2_per_kwh=0.0, price_change_per_year=1.0, discount_rate=0.0,
                    lifetime_years=3)
    assert payback_years(250.0, 100.0, 0.0, prices) == pytest.approx(1.75)
    assert npv(250.0, 100.0, 0.0, prices) == pytest.approx(-250 + 100 + 200 + 400)


def test_a_saving_smaller_than_the_upkeep_never_pays_back():
    prices = Prices(1.0, 0.0, 0.0, 0.03, 10)
    assert payback_years(100.0, 5.0, 10.0, prices) is None
    assert npv(100.0, 5.0, 10.0, prices) < -100


def test_hardware_per_controller_kind():
    assert hardware_of("always_on") == ()
    assert hardware_of("oracle") == () and hardware_of("oracle_seen") == ()  # bounds: nothing to buy
    assert hardware_of("pir") == ("pir_sensor", "controller_node")
    assert hardware_of("schedule") == ("controller_node",)
    assert hardware_of("detector_located") == ("camera_node", "controller_node")
    assert hardware_of("threshold_5") == ("camera_node", "controller_node")


def test_prices_fall_back_to_the_year_section_then_to_the_defaults():
    assert CostsSpec().price_per_kwh(0.31) == 0.31
    assert CostsSpec().price_per_kwh(0.0) == 0.25
    assert CostsSpec(energy_price_per_kwh=0.4).price_per_kwh(0.31) == 0.4
    assert CostsSpec().kg_co2_per_kwh(0.0) == 0.38


def test_a_bad_cost_field_is_named_in_the_error():
    data = {**toy_mapping(), "costs": {"discount_rte": 0.05}}
    with pytest.raises(ScenarioError, match=r"costs\.discount_rte.*discount_rate"):
        scenario_from_mapping(data, source="toy")
    data = {**toy_mapping(), "costs": {"lifetime_years": 0}}
    with pytest.raises(ScenarioError, match=r"costs\.lifetime_years"):
        scenario_from_mapping(data, source="toy")


def test_the_year_table_shows_the_money_and_what_it_assumes():
    from citysim.report.year_section import MONEY_HEAD, money_facts, money_rows

    prices = prices_of(COSTS)
    controllers = {label: {"energy_kwh_per_year": kwh} for label, kwh in (("always_on", 5000.0), ("pir", 3000.0))}
    for label, money in money_figures({k: v["energy_kwh_per_year"] for k, v in controllers.items()}, {}, 4, COSTS,
                                      prices).items():  # fmt: skip
        controllers[label].update(money)
    result = {"currency": "EUR", "controllers": controllers,
              "money": {"poles": 4, **vars(prices)}}  # fmt: skip
    rows = money_rows(result)
    assert [r[0] for r in rows] == ["always_on", "pir"] and len(rows[1]) == len(MONEY_HEAD)
    # pir: 4 x (50 + 100 + 100) = 1000 capex; 4 x 7 = 28 a year; 2000 x 0.5 - 28 = 972 a year
    assert rows[1][1:5] == ["1,000 EUR", "28 EUR", "972 EUR", f"{1000 / 972:.1f} y"]
    assert "4 poles at 0.5 EUR/kWh" in money_facts(result) and "10 % a year" in money_facts(result)
    assert money_rows({"currency": "EUR", "controllers": {"always_on": {"energy_kwh_per_year": 1.0}}}) == []


def test_the_year_table_gives_no_payback_for_the_reference_or_the_bound_and_says_why():
    from citysim.report.year_section import MONEY_HEAD, money_rows, year_table

    prices = prices_of(COSTS)
    kwh = {"always_on": 5000.0, "oracle": 2500.0, "pir": 3000.0}
    controllers = {label: {"energy_kwh_per_year": v} for label, v in kwh.items()}
    for label, money in money_figures(kwh, {}, 4, COSTS, prices).items():
        controllers[label].update(money)
    result = {"currency": "EUR", "controllers": controllers, "money": {"poles": 4, **vars(prices)}}
    rows = {r[0]: dict(zip(MONEY_HEAD, r, strict=True)) for r in money_rows(result)}
    assert rows["always_on"]["payback"] == "-" and rows["always_on"]["capex"] == "0 EUR"
    assert [rows["oracle"][c] for c in ("capex", "opex / year", "payback", "NPV")] == ["-"] * 4
    assert rows["oracle"]["saved / year"] == "1,250 EUR"
    assert rows["pir"]["payback"] == f"{1000 / 972:.1f} y"
    # an older year.json held always-on's payback as 0 and costed the oracle as cameras: still dashes
    controllers["always_on"]["payback_years"] = 0.0
    controllers["oracle"].update(capex=1600.0, opex_per_year=60.0, payback_years=1.2, npv=737.6)
    again = {r[0]: dict(zip(MONEY_HEAD, r, strict=True)) for r in money_rows(result)}
    assert again["always_on"]["payback"] == "-" and again["oracle"]["capex"] == again["oracle"]["NPV"] == "-"
    notes = "\n".join(year_table_money_notes(result, year_table))
    assert "always_on is the reference" in notes and "no payback" in notes
    assert "The oracle is a bound" in notes and "no capex, upkeep, payback or NPV" in notes


def year_table_money_notes(result: dict, year_table) -> list[str]:
    """The lines after the money table's rows in the terminal's year table (a minimal year.json)."""
    full = {**result, "scenario": "toy", "year": 2025, "sample_s": 900.0,
            "table": {"labels": list(result["controllers"]), "levels": {}}}  # fmt: skip
    for f in full["controllers"].values():
        f.update(savings_vs_always_on=0.0, cost_per_year=0.0, co2_kg_per_year=0.0, aeci_wh_per_m2=0.0,
                 lit_on_entry_rate=None, dark_s_per_year=None)  # fmt: skip
    return year_table(full).split("CO2 avoided")[1].splitlines()
