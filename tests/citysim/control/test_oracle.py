"""The oracle bound and the planner's darkness figures, against hand computations."""

import csv
import io
import math

import pytest

from citysim.config.scenario import ControllerSpec, scenario_from_mapping
from citysim.sim.compare import (
    ORACLE_SAVES_NOTHING_BELOW,
    oracle_bound,
    resolve_controllers,
    with_savings_vs_oracle,
)
from citysim.sim.loop import build_controller, run_controller
from citysim.sim.night import build_night
from tests.citysim.sim.test_loop import FPS, tiny_scenario


def test_oracle_lights_from_one_ramp_before_entry_until_exit_plus_hold():
    scenario = scenario_from_mapping(tiny_scenario())
    objects = io.StringIO()
    result = run_controller(scenario, ControllerSpec(name="oracle"), objects_writer=csv.writer(objects))
    lum = scenario.lamps.luminaire
    (row,) = list(csv.reader(io.StringIO(objects.getvalue())))
    t_enter, t_exit, lag = float(row[4]), float(row[5]), float(row[6])
    assert lag == 0.0 and row[8] == "1"  # lit on entry: nobody meets a dim lamp
    assert result["lit_on_entry_rate"] == 1.0 and result["dark_s_per_100_entries"] == 0.0

    # by hand: full from one ramp before entry (plus the oracle's two physics steps of margin)
    # until exit plus the hold, a linear rise and fade, dim otherwise; sensing paid all night
    rise_s = (1.0 - lum.dim_level) * lum.ramp_up_s
    fall_s = (1.0 - lum.dim_level) * lum.fade_s
    t_on = t_enter - rise_s - 2.0 / 30.0
    t_off = t_exit + lum.hold_s
    full_equiv_s = (t_off - t_on) - rise_s / 2 + fall_s / 2
    T = scenario.duration_s
    energy_hand_j = lum.rated_power_w * (lum.dim_level * T + (1 - lum.dim_level) * full_equiv_s) \
        + (lum.standby_power_w + lum.sensing_power_w) * T
    one_frame_j = lum.rated_power_w * (1 - lum.dim_level) / FPS
    assert result["energy_kwh"] * 3.6e6 == pytest.approx(energy_hand_j, abs=one_frame_j)
    trig = result["lamp_triggers"][0]
    assert trig["first_s"] == pytest.approx(t_on, abs=1.0 / FPS)


@pytest.mark.parametrize("physics_hz", [30.0, 60.0])
def test_the_oracles_margin_is_two_of_the_worlds_steps(physics_hz):
    scenario = scenario_from_mapping({**tiny_scenario(), "physics_hz": physics_hz})
    oracle = build_controller(build_night(scenario), ControllerSpec(name="oracle"))
    lum = scenario.lamps.luminaire
    assert oracle.lead_s == pytest.approx((1.0 - lum.dim_level) * lum.ramp_up_s + 2.0 / physics_hz, abs=1e-12)


def test_the_oracle_reaches_as_far_as_a_road_user_setting_off_could_go():
    # a car at 2.6 m/s a little short of a zone, setting off at its kind's greatest acceleration
    # (1.5 m/s^2: the world's driver model never exceeds it), arrives sooner than its speed says
    from citysim.config.kinds import AGENT_KINDS
    from citysim.world.agents import AgentState

    scenario = scenario_from_mapping(tiny_scenario())
    oracle = build_controller(build_night(scenario), ControllerSpec(name="oracle"))
    last = len(oracle.zone_start_m) - 1  # the tiny street's one zone; the car is short of it
    zone_start_m, lead_s = float(oracle.zone_start_m[last]), oracle.lead_s
    accel_mps2 = AGENT_KINDS["vehicle"].motion.accel_mps2
    by_speed_m, by_accel_m = 2.6 * lead_s, 0.5 * accel_mps2 * lead_s**2
    x_m = zone_start_m - by_speed_m - by_accel_m / 2  # beyond its speed's reach, within its acceleration's

    def car(heading_rad):
        return AgentState(object_id=1, cls="vehicle", x_m=x_m, y_m=-1.6, heading_rad=heading_rad, speed_mps=2.6,
                          length_m=4.0, width_m=1.8, height_m=1.5)  # fmt: skip

    assert last in oracle.zones_needed([car(0.0)]).tolist()
    assert last not in oracle.zones_needed([car(math.pi)]).tolist()  # going away from that zone
    assert last not in oracle.zones_needed([car(math.pi / 2)]).tolist()  # crossing: no way along x
    assert zone_start_m - by_speed_m > x_m + 1e-6  # the speed alone would not have lit it


def test_every_comparison_holds_always_on_and_the_oracle_first():
    scenario = scenario_from_mapping(tiny_scenario())
    names = [s.name for s in resolve_controllers(scenario, ["pir", "detector"])]
    assert names == ["always_on", "oracle", "pir", "detector"]


def test_savings_vs_oracle_is_the_share_of_the_bound():
    results = {
        "always_on": {"controller": "always_on", "savings_vs_always_on": 0.0, "x": 1},
        "oracle": {"controller": "oracle", "savings_vs_always_on": 0.5},
        "pir": {"controller": "pir", "savings_vs_always_on": 0.45},
    }
    out = with_savings_vs_oracle(results)
    assert out["pir"]["savings_vs_oracle"] == pytest.approx(0.9)
    assert out["oracle"]["savings_vs_oracle"] == pytest.approx(1.0)
    assert list(out["always_on"]) == ["controller", "savings_vs_always_on", "savings_vs_oracle", "x"]
    assert with_savings_vs_oracle({"pir": results["pir"]})["pir"]["savings_vs_oracle"] is None


@pytest.mark.parametrize("oracle_saving", [-0.061, 0.0, 0.009])
def test_no_share_of_an_oracle_that_saves_nothing(oracle_saving):
    # a 60 s run of a busy street: the oracle's lamps at full all along; 0.171 / -0.061 read -280 %
    results = {
        "always_on": {"controller": "always_on", "savings_vs_always_on": 0.0},
        "oracle": {"controller": "oracle", "savings_vs_always_on": oracle_saving},
        "pir": {"controller": "pir", "savings_vs_always_on": 0.171},
    }
    assert oracle_bound(results) is None
    out = with_savings_vs_oracle(results)
    assert all(figures["savings_vs_oracle"] is None for figures in out.values())
    # just at the threshold the bound counts
    results["oracle"]["savings_vs_always_on"] = ORACLE_SAVES_NOTHING_BELOW
    assert with_savings_vs_oracle(results)["pir"]["savings_vs_oracle"] == pytest.approx(0.171 / ORACLE_SAVES_NOTHING_BELOW)
