"""oracle_seen: the oracle on what a perfect detector in the cameras sees; the gap split in the summary and table."""

from __future__ import annotations

import math

import numpy as np
import pytest

from citysim.config.scenario import ControllerSpec, scenario_from_mapping
from citysim.report.table import comparison_table
from citysim.sim.compare import with_savings_vs_oracle
from citysim.sim.loop import build_controller, run_controller
from citysim.sim.night import build_night
from citysim.world.agents import AgentState
from tests.citysim.fast.synthetic import tiny_scenario


def walker(x_m: float, heading_rad: float = 0.0, speed_mps: float = 1.4, object_id: int = 1) -> AgentState:
    return AgentState(object_id, "pedestrian", x_m, -4.3, heading_rad, speed_mps, 0.5, 0.5, 1.7)


@pytest.fixture
def controller():
    scenario = scenario_from_mapping(tiny_scenario())
    return build_controller(build_night(scenario), ControllerSpec(name="oracle_seen"))


def test_a_road_user_in_view_is_known_as_it_is_and_one_never_seen_is_unknown(controller):
    in_view = walker(31.0)  # lamp 0's camera (pole at 15 m, looking +x) sees this sidewalk at 27-40 m
    never = walker(46.0, object_id=2)  # under lamp 1's pole: no camera sees it
    known = controller.known(0.0, [in_view, never])
    assert known == [in_view]


def test_a_road_user_leaving_every_view_is_carried_at_its_last_speed_and_forgotten_when_gone(controller):
    controller.known(0.0, [walker(37.0)])
    # 5 s later it stands under lamp 1's pole (blind), having turned back: oracle_seen still believes the last sighting
    assert not controller.views.seen_xy(np.array([[44.0, -4.3]])).any()
    [carried] = controller.known(5.0, [walker(44.0, heading_rad=math.pi)])
    assert carried.x_m == pytest.approx(37.0 + 1.4 * 5.0)
    assert carried.heading_rad == 0.0
    assert controller.known(6.0, []) == [] and controller.last_seen == {}


#: the tiny street's traffic at a tenth (90 road users an hour, not 900): the oracle saves 20 % in its
#: minute; at 900 an hour its lamps are at full the whole minute and it saves -3.9 %, nothing to split
QUIET = {"classes": {"pedestrian": {"rate_per_hour": 60}, "vehicle": {"rate_per_hour": 20},
                     "cyclist": {"rate_per_hour": 10}}}  # fmt: skip


def _tiny_results(**changes) -> dict:
    scenario = scenario_from_mapping(tiny_scenario(duration_s=60, **changes))
    names = ("always_on", "oracle", "oracle_seen", "pir")
    return {n: {"controller": n, **run_controller(scenario, ControllerSpec(name=n))} for n in names}


def test_oracle_seen_never_lights_more_entries_than_the_oracle_and_the_summary_splits_the_gap():
    results = _tiny_results(traffic=QUIET)
    assert results["oracle"]["savings_vs_always_on"] > 0.1  # a bound to take shares of
    oracle, seen = results["oracle"], results["oracle_seen"]
    assert seen["lit_on_entry_rate"] <= oracle["lit_on_entry_rate"]
    assert seen["energy_kwh"] <= oracle["energy_kwh"] + 1e-12  # it knows less, so it lights no more
    out = with_savings_vs_oracle(results)
    pir = out["pir"]
    # the two parts add up to the whole gap, on both axes
    assert pir["gap_unseen"] + pir["gap_unused"] == pytest.approx(1.0 - pir["savings_vs_oracle"])
    assert pir["dark_unseen"] + pir["dark_unused"] == pytest.approx(1.0 - pir["lit_on_entry_rate"])
    summary = {"scenario": "tiny", "duration_s": 60.0, "seed": 11, "controllers": out}
    table = comparison_table(summary)
    assert "no camera can see" in table and "pir" in table.split("no camera can see")[1]


def test_no_gap_split_when_the_oracle_saves_nothing():
    results = _tiny_results()  # 900 road users an hour: the oracle's lamps at full all minute
    assert results["oracle"]["savings_vs_always_on"] < 0.0
    out = with_savings_vs_oracle(results)
    assert all(out[n]["savings_vs_oracle"] is None and out[n]["gap_unseen"] is None and out[n]["gap_unused"] is None
               for n in out)  # fmt: skip
    assert out["pir"]["dark_unused"] is not None  # the lit-on-entry split needs no saving
    table = comparison_table({"scenario": "tiny", "duration_s": 60.0, "seed": 11, "controllers": out})
    assert "no camera can see" not in table and "vs oracle not given" in table


def test_the_frontier_draws_oracle_seen_as_a_black_cross_beside_the_oracles_star():
    from citysim.report.frontier import frontier_figure

    controllers = {
        "oracle": {"controller": "oracle", "lit_on_entry_rate": 1.0, "savings_vs_always_on": 0.3},
        "oracle_seen": {"controller": "oracle_seen", "lit_on_entry_rate": 0.97, "savings_vs_always_on": 0.31},
        "detector_fused": {"controller": "detector_fused", "lit_on_entry_rate": 0.96, "savings_vs_always_on": 0.26},
    }
    fig = frontier_figure(controllers)
    ax = fig.axes[0]
    by_label = {c.get_label(): c for c in ax.collections}
    seen = by_label["oracle_seen"]
    assert tuple(seen.get_facecolor()[0][:3]) == (0.0, 0.0, 0.0)
    assert seen.get_paths()[0].vertices.shape != by_label["oracle"].get_paths()[0].vertices.shape  # not a star
