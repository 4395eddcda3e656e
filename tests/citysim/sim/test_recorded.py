"""Replayed steps' short paths give their long paths' results bit for bit: the zone tracker and the
false on-time read a chunk's rows once a chunk (and the tracker skips static steps), the oracle
finds each step's needed zones in one pass a chunk, and the physics clock runs steps without
simpy's queue when nothing else is due. Each is compared with the same work done on the step's
agents as a plain list (the per-agent path every live world takes)."""

from __future__ import annotations

import numpy as np
import pytest

from citysim.config.scenario import ControllerSpec, scenario_from_mapping
from citysim.control.oracle import Oracle
from citysim.metrics.false_on import FalseOnTime
from citysim.metrics.zones import ZoneTracker
from citysim.sim import replay
from citysim.sim.loop import build_controller
from citysim.sim.night import build_night
from citysim.sim.replay import TrafficReplay, record_traffic
from tests.citysim.sim.test_replay import busy_street

LAMPS_X_M = (4.0, 30.0, 56.0)
DIM_LEVEL = 0.2
#: lit, dim, half way and a hair under full (lit only within the zone tracker's tolerance)
LEVELS = (1.0, DIM_LEVEL, 0.6, 1.0 - 1e-9)


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """A busy street's recording: 60 s in chunks of 97 steps (none a whole number of seconds)."""
    folder = tmp_path_factory.mktemp("traffic")
    patch = pytest.MonkeyPatch()
    patch.setattr(replay, "CHUNK_STEPS", 97)
    scenario = scenario_from_mapping(busy_street(60.0, lamps_x_m=LAMPS_X_M))
    record_traffic(scenario, folder)
    patch.undo()
    return scenario, folder


def replayed_steps(scenario, folder):
    """(t_s, agents) of every replayed step, the agents as ``next_step`` gives them."""
    night = build_night(scenario, replay=TrafficReplay(folder))
    steps = []
    night.start_physics(lambda t_s, agents: steps.append((t_s, agents)))
    night.run_until(scenario.duration_s)
    return night, steps


def held_levels(n_steps: int, n_lamps: int, seed: int) -> list[np.ndarray]:
    """Per step, read-only level arrays held for runs of steps (the same array while held, as
    ``LampStates`` passes them), drawn from ``LEVELS``."""
    rng = np.random.default_rng(seed)
    out, levels = [], None
    for _ in range(n_steps):
        if levels is None or rng.random() < 0.02:
            levels = rng.choice(LEVELS, size=n_lamps)
            levels.flags.writeable = False
        out.append(levels)
    return out


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_zone_tracker_and_false_on_time_of_replayed_steps_are_their_lists_bit_for_bit(recorded, seed):
    scenario, folder = recorded
    night, steps = replayed_steps(scenario, folder)
    levels = held_levels(len(steps), len(LAMPS_X_M), seed)
    short, long = ZoneTracker(night.street), ZoneTracker(night.street)
    short_on, long_on = (FalseOnTime(night.street, DIM_LEVEL, night.physics_dt_s) for _ in range(2))
    skipped, skip = [], short._recorded.skip
    short._recorded.skip = lambda *args: skipped.append(skip(*args)) or skipped[-1]
    for (t_s, agents), level in zip(steps, levels, strict=True):
        short.update(t_s, agents, level)
        long.update(t_s, list(agents), level)
        short_on.on_step(t_s, agents, level)
        long_on.on_step(t_s, list(agents), level)
    assert len(skipped) == len(steps) and 0.3 * len(steps) < sum(skipped) < len(steps)  # both paths taken
    for tracker in (short, long):
        tracker.finish(steps[-1][0])
    rows = list(long.rows())
    assert list(short.rows()) == rows and short.summary() == long.summary()
    assert len(rows) > 20 and any(r["dark_s"] > 0.0 for r in rows) and any(r["lit_on_entry"] for r in rows)
    assert short_on.seconds == long_on.seconds > 0.0


def test_oracle_triggers_of_replayed_steps_are_their_lists(recorded):
    scenario, folder = recorded
    night, steps = replayed_steps(scenario, folder)
    oracle = build_controller(night, ControllerSpec(name="oracle"))
    assert isinstance(oracle, Oracle)
    needed = 0
    for _, agents in steps:
        by_chunk = oracle.needed_by_step(agents.chunk)[agents.step]
        assert by_chunk == oracle.zones_needed(list(agents)).tolist()
        needed += len(by_chunk)
    assert needed > 100


@pytest.mark.parametrize("name", ["oracle", "pir"])
def test_controllers_given_replayed_steps_trigger_as_given_their_lists(recorded, name):
    scenario, folder = recorded
    night, steps = replayed_steps(scenario, folder)
    # two controllers of the same night: the same lamps' settings and the same random streams
    short, long = (build_controller(build_night(scenario), ControllerSpec(name=name)) for _ in range(2))
    for t_s, agents in steps:
        short.on_physics_step(t_s, agents)
        long.on_physics_step(t_s, list(agents))
    banks = [(c.bank.triggers, c.bank.first_trigger_s, c.bank.last_trigger_s, c.bank.lit_until_s) for c in (short, long)]
    assert repr(banks[0]) == repr(banks[1]) and sum(short.bank.triggers) > 20
    assert [lamp.energy_j for lamp in short.ctx.lamps] == [lamp.energy_j for lamp in long.ctx.lamps]


def test_physics_steps_run_at_the_times_and_in_the_order_of_the_clock_queue(recorded):
    """Steps run without the queue when nothing else is due: the same times, in the same order
    among other events (some due exactly on a step) and ``run_until``'s ends."""
    scenario, folder = recorded

    def log(skip: bool) -> list[tuple[float, str]]:
        night = build_night(scenario, replay=TrafficReplay(folder))
        night.skip_idle_clock = skip
        out: list[tuple[float, str]] = []
        night.start_physics(lambda t_s, agents: out.append((night.env.now, f"step {t_s!r} {len(agents)}")))

        def other():
            for k, delay_s in enumerate([0.0, 0.05, 1 / 30, 0.2, 2 / 30, 0.0, 0.7, 0.1] * 20):
                yield night.env.timeout(delay_s)
                out.append((night.env.now, f"other {k}"))

        night.env.process(other())
        for t_s in (0.5, 1.0, 2.0, 2.05, 3.0, 7.3, 12.0):
            night.run_until(t_s)
            out.append((night.env.now, "until"))
        return out

    skipped, queued = log(True), log(False)
    assert skipped == queued and len(skipped) > 12 * 30
