"""The city map's geometry and the ranking of streets, on numbers worked out by hand."""

from __future__ import annotations

import math

import pytest

from citysim.city.layout import grid_shifts, offset_m, place
from citysim.city.results import best_controller, city_total, ranking


def test_a_point_is_placed_along_and_left_of_a_bent_centreline():
    line = [(0.0, 0.0), (10.0, 0.0), (10.0, 20.0)]  # east 10 m, then north 20 m
    assert place(line, 4.0, 2.0) == pytest.approx((4.0, 2.0))  # left of east is north
    assert place(line, 15.0, 3.0) == pytest.approx((7.0, 5.0))  # left of north is west
    assert place(line, 40.0, 0.0) == pytest.approx((10.0, 20.0))  # past the end: the end


def test_an_origin_one_thousandth_degree_north_and_east_of_the_reference():
    east, north = offset_m((51.001, 7.001), (51.0, 7.0))
    assert north == pytest.approx(111.19, abs=0.01)  # 6371008.8 m x 0.001 deg in radians
    assert east == pytest.approx(111.19 * math.cos(math.radians(51.0)), abs=0.01)


def test_the_grid_keeps_streets_apart():
    shifts = grid_shifts([[(0, 0), (100, 0)], [(0, 0), (50, 0)], [(0, 0), (80, 10)], [(0, 0), (30, 0)]])
    assert shifts[0] == (0, 0) and shifts[1] == (140.0, 0)  # 100 m + 40 m gap
    assert shifts[2][1] == -50.0 and shifts[2][0] == 0  # second row: 10 m + 40 m below


def _street(name, **controllers):
    figures = {label: {"payback_years": p, "npv": n, "lit_on_entry_rate": lit} for label, (p, n, lit) in controllers.items()}
    figures["always_on"] = {"payback_years": 0.0, "npv": 0.0, "lit_on_entry_rate": None}
    best = best_controller(figures, 0.99)
    return {"name": name, "controllers": figures, "best": best,
            "best_payback_years": figures[best]["payback_years"] if best else None,
            "best_npv": figures[best]["npv"] if best else None}  # fmt: skip


def test_the_best_controller_lights_enough_and_pays_back_first():
    a = _street("a", pir=(3.0, 500.0, 0.95), detector=(5.0, 200.0, 0.995), oracle=(1.0, 900.0, 1.0))
    assert a["best"] == "detector"  # the pir lights too few entries, the oracle is a bound
    b = _street("b", pir=(2.0, 100.0, 0.992), detector=(2.0, 300.0, 0.999))
    assert b["best"] == "detector"  # equal payback: the larger NPV
    c = _street("c", pir=(None, -50.0, 0.999))
    assert c["best"] is None  # never pays back
    ranked = ranking([c, a, b])
    assert [(r["rank"], r["street"], r["controller"]) for r in ranked] == [(1, "b", "detector"), (2, "a", "detector"),
                                                                          (3, "c", None)]


def test_a_city_total_of_a_figure_no_street_has_is_null_not_zero():
    # the oracle's capex per street is null (a bound: nothing to buy), so the city's total is too
    assert city_total([None, None]) is None
    assert city_total([1200.0, None, 800.0]) == pytest.approx(2000.0)
    assert city_total([0.0]) == 0.0  # always-on's capex: a real zero
