"""Lamp levels follow linear ramps and their energy is the exact integral of the power model."""

from __future__ import annotations

import numpy as np
import pytest

from citysim.config.street import LuminaireSpec
from citysim.control.lamps import Lamp, always_on_energy_j


def test_always_on_energy_is_lamps_times_rated_power_times_duration_exactly():
    spec = LuminaireSpec(rated_power_w=65.0)
    lamps = [Lamp(i, spec, senses=False, initial_level=1.0) for i in range(7)]
    duration_s = 8 * 3600.0
    rng = np.random.default_rng(3)
    # irregular stepping must not matter: energy is integrated in closed form
    for t_s in np.sort(rng.uniform(0.0, duration_s, 500)):
        for lamp in lamps:
            lamp.advance(float(t_s))
    for lamp in lamps:
        lamp.advance(duration_s)
    total_j = sum(lamp.energy_j for lamp in lamps)
    assert total_j == 7 * 65.0 * duration_s
    assert total_j == always_on_energy_j(7, spec, duration_s)
    assert all(lamp.switches == 0 and lamp.on_time_s == duration_s for lamp in lamps)


def test_switch_up_with_ramp_integrates_to_hand_computed_joules():
    spec = LuminaireSpec(
        rated_power_w=60.0, dim_level=0.2, standby_power_w=0.5, sensing_power_w=5.0, ramp_up_s=0.3
    )
    lamp = Lamp(0, spec, senses=True, initial_level=0.2)
    lamp.set_target(10.0, 1.0)
    # ramp 0.2 -> 1.0 at 1/0.3 per s takes 0.8 * 0.3 = 0.24 s
    assert lamp.reached_at_s() == pytest.approx(10.24)
    assert lamp.level_at(10.12) == pytest.approx(0.6)
    assert lamp.level_at(10.24) == 1.0
    lamp.advance(20.0)
    level_s = 0.2 * 10.0 + 0.5 * (0.2 + 1.0) * 0.24 + 1.0 * (20.0 - 10.24)  # 11.904
    expected_j = 60.0 * level_s + 0.5 * 20.0 + 5.0 * 20.0  # 714.24 + 10 + 100
    assert lamp.energy_j == pytest.approx(824.24, rel=1e-12)
    assert lamp.energy_j == pytest.approx(expected_j, rel=1e-12)
    assert lamp.luminaire_energy_j == pytest.approx(714.24, rel=1e-12)
    # on above dim from the instant the ramp starts
    assert lamp.on_time_s == pytest.approx(10.0, rel=1e-12)


def test_energy_does_not_depend_on_how_often_the_lamp_is_advanced():
    spec = LuminaireSpec(ramp_up_s=0.3, fade_s=2.5)
    coarse, fine = (Lamp(0, spec, True, 0.2) for _ in range(2))
    events = [(1.0, 1.0), (4.13, 0.2), (4.9, 1.0), (12.0, 0.0)]
    for t_s, level in events:
        coarse.set_target(t_s, level)
        for t in np.arange(fine.t_s, t_s, 1 / 30):
            fine.advance(float(t))
        fine.set_target(t_s, level)
    for t in np.arange(fine.t_s, 20.0, 1 / 30):
        fine.advance(float(t))
    coarse.advance(20.0)
    fine.advance(20.0)
    assert fine.energy_j == pytest.approx(coarse.energy_j, rel=1e-12)
    assert fine.on_time_s == pytest.approx(coarse.on_time_s, rel=1e-12)


def test_fade_to_off_crosses_dim_level_at_the_computed_instant():
    spec = LuminaireSpec(rated_power_w=60.0, dim_level=0.2, fade_s=2.0)
    lamp = Lamp(3, spec, senses=False, initial_level=1.0)
    lamp.set_target(5.0, 0.0)  # falls at 0.5 per s: 0.2 at 6.6 s, 0 at 7.0 s
    assert lamp.level_at(6.0) == pytest.approx(0.5)
    assert lamp.level_at(9.0) == 0.0
    lamp.advance(10.0)
    assert lamp.on_time_s == pytest.approx(6.6)
    assert lamp.energy_j == pytest.approx(60.0 * (5.0 + 0.5 * 1.0 * 2.0))
    assert lamp.switches == 1


def test_a_ramp_interrupted_midway_turns_from_where_it_is():
    spec = LuminaireSpec(rated_power_w=100.0, dim_level=0.2, ramp_up_s=1.0, fade_s=1.0)
    lamp = Lamp(0, spec, senses=False, initial_level=0.0)
    lamp.set_target(0.0, 1.0)
    lamp.set_target(0.5, 0.0)  # at 0.5 the level is 0.5; it is back at 0 at 1.0 s
    assert lamp.level_at(0.75) == pytest.approx(0.25)
    lamp.advance(3.0)
    assert lamp.light_integral_s == pytest.approx(0.25)
    assert lamp.energy_j == pytest.approx(25.0)
    assert lamp.on_time_s == pytest.approx(0.6)  # above 0.2 from 0.2 s to 0.8 s


def test_zero_ramp_is_an_instant_step():
    lamp = Lamp(0, LuminaireSpec(ramp_up_s=0.0, fade_s=0.0, rated_power_w=50.0), False, 0.2)
    lamp.set_target(2.0, 1.0)
    assert lamp.level_at(2.0) == 1.0
    lamp.advance(4.0)
    assert lamp.energy_j == pytest.approx(50.0 * (0.2 * 2.0 + 1.0 * 2.0))


def test_hold_is_the_callers_job_a_lamp_never_dims_by_itself():
    spec = LuminaireSpec(hold_s=30.0)
    lamp = Lamp(0, spec, senses=True, initial_level=0.2)
    lamp.set_target(1.0, 1.0)
    assert lamp.level_at(1.0 + 100 * spec.hold_s) == 1.0
    lamp.set_target(
        1.0 + spec.hold_s, spec.dim_level
    )  # what a controller does when the hold expires
    assert lamp.level_at(1.0 + spec.hold_s + spec.fade_s) == pytest.approx(spec.dim_level)


def test_switch_count_counts_crossings_between_dim_and_on():
    lamp = Lamp(0, LuminaireSpec(dim_level=0.2), senses=True, initial_level=0.2)
    for t_s, level in [(1, 1.0), (2, 1.0), (3, 0.5), (4, 0.2), (5, 0.0), (6, 1.0), (7, 0.1)]:
        lamp.set_target(float(t_s), level)
    # on at 1, (still on at 2 and 3), off at 4, (still off at 5), on at 6, off at 7
    assert lamp.switches == 4


def test_standby_is_paid_by_controlled_lamps_and_sensing_by_sensing_lamps():
    spec = LuminaireSpec(rated_power_w=60.0, standby_power_w=0.5, sensing_power_w=5.0)
    plain = Lamp(0, spec, senses=False, initial_level=0.0)
    smart = Lamp(1, spec, senses=True, initial_level=0.0)
    scheduled = Lamp(2, spec, senses=False, initial_level=0.0, standby=True)
    for lamp in (plain, smart, scheduled):
        lamp.advance(100.0)
    assert plain.energy_j == 0.0
    assert smart.energy_j == pytest.approx(550.0)
    assert scheduled.energy_j == pytest.approx(50.0)
    assert smart.power_w(100.0) == pytest.approx(5.5)


def test_time_only_moves_forward():
    lamp = Lamp(4, LuminaireSpec(), senses=True, initial_level=0.2)
    lamp.advance(10.0)
    with pytest.raises(ValueError, match=r"Lamp 4: t_s=5.0 precedes"):
        lamp.set_target(5.0, 1.0)
    lamp.set_target(12.0, 1.0)
    with pytest.raises(ValueError, match="past levels are not stored"):
        lamp.level_at(11.0)


@pytest.mark.parametrize(
    "field, value",
    [
        ("rated_power_w", -1.0),
        ("standby_power_w", float("nan")),
        ("sensing_power_w", -0.1),
        ("dim_level", 1.5),
        ("ramp_up_s", -0.3),
        ("fade_s", float("inf")),
        ("hold_s", 4000.0),
    ],
)
def test_spec_errors_name_the_field(field, value):
    with pytest.raises(ValueError, match=rf"LuminaireSpec[\s\S]*{field}"):
        LuminaireSpec(**{field: value})


def test_bad_levels_name_the_argument():
    with pytest.raises(ValueError, match="Lamp.initial_level"):
        Lamp(0, LuminaireSpec(), True, 1.2)
    lamp = Lamp(0, LuminaireSpec(), True, 0.2)
    with pytest.raises(ValueError, match=r"Lamp\.set_target\.level"):
        lamp.set_target(1.0, -0.5)


def test_target_level_and_ramping_state_for_controllers():
    lamp = Lamp(0, LuminaireSpec(ramp_up_s=0.3), senses=True, initial_level=0.2)
    assert lamp.target_level == 0.2 and not lamp.is_ramping(0.0)
    lamp.set_target(1.0, 1.0)
    assert lamp.target_level == 1.0
    assert lamp.is_ramping(1.1) and not lamp.is_ramping(1.25)


def test_bank_releases_each_lamp_when_its_own_hold_runs_out_not_before():
    # release_expired skips its scan until the earliest hold ends: a later trigger with a shorter
    # hold must move that time earlier, and a lamp must never drop while its hold runs
    from types import SimpleNamespace

    from citysim.control.base import LampBank

    spec = LuminaireSpec(dim_level=0.2, ramp_up_s=0.0, fade_s=0.0)
    lamps = [Lamp(i, spec, senses=True, initial_level=0.2) for i in range(3)]
    bank = LampBank(SimpleNamespace(lamps=lamps, hold_s=30.0, dim_level=0.2))
    bank.trigger(0, 0.0)  # held until 30 s
    bank.trigger(1, 5.0, hold_s=10.0)  # held until 15 s: earlier than lamp 0's
    targets = []
    for t_s in (1.0, 14.9, 15.0, 29.9, 30.0):
        bank.release_expired(t_s)
        targets.append([lamp.target_level for lamp in lamps])
    assert targets == [[1.0, 1.0, 0.2], [1.0, 1.0, 0.2], [1.0, 0.2, 0.2], [1.0, 0.2, 0.2], [0.2, 0.2, 0.2]]
    bank.trigger(2, 31.0, hold_s=0.0)  # no hold: released at the next step
    bank.release_expired(31.0)
    assert lamps[2].target_level == 0.2


def test_level_after_the_ramp_is_the_target_exactly_and_ramping_ends_there():
    spec = LuminaireSpec(dim_level=0.2, ramp_up_s=0.3, fade_s=2.0)
    lamp = Lamp(0, spec, senses=True, initial_level=0.2)
    lamp.set_target(1.0, 1.0)
    assert lamp.is_ramping(1.1) and not lamp.is_ramping(lamp.reached_at_s())
    assert lamp.level_at(1.0 + 0.8 * 0.3) == 1.0 and lamp.level_at(50.0) == 1.0
    lamp.set_target(2.0, 0.2)
    assert lamp.level_at(2.0 + 0.8 * 2.0) == 0.2 and lamp.level_at(3.0) == pytest.approx(0.5)


def test_lamp_states_give_every_lamps_own_levels_and_ramping_bit_for_bit():
    # LampStates reuses the levels read once every lamp settled, until a target changes: at random
    # times and targets (ramps cut short, targets set again to the same level) it must say what the
    # lamps themselves say
    from citysim.control.lamps import LampStates, levels_at

    spec = LuminaireSpec(rated_power_w=60.0, dim_level=0.2, ramp_up_s=0.3, fade_s=2.0)
    lamps = [Lamp(i, spec, senses=True, initial_level=0.2) for i in range(5)]
    states = LampStates(lamps)
    rng = np.random.default_rng(11)
    reused = 0
    for t_s in np.cumsum(rng.choice([1 / 30, 1 / 60, 0.5, 3.0], size=3000, p=[0.6, 0.3, 0.08, 0.02])).tolist():
        if rng.random() < 0.03:
            lamps[int(rng.integers(5))].set_target(t_s, float(rng.choice([0.2, 0.6, 1.0])))
        before = states._levels
        levels = states.levels_at(t_s)
        reused += levels is before
        assert levels.tolist() == levels_at(lamps, t_s).tolist() and not levels.flags.writeable
        assert list(states.ramping(t_s)) == [lamp.is_ramping(t_s) for lamp in lamps]
        assert states.any_ramping(t_s) == any(lamp.is_ramping(t_s) for lamp in lamps)
    assert reused > 1000  # most reads reuse the settled levels
