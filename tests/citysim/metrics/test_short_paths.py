"""The metrics' short paths give the sums of their long ones bit for bit: FalseOnTime per step
(plain lists, lit lamps kept while ``LampStates`` passes the same levels) against the same sum in
numpy arrays (``false_on_by_arrays``, how it was computed before), and ZoneTracker fed shared
read-only levels against fresh copies of them."""

from __future__ import annotations

import numpy as np
import pytest

from citysim.metrics.false_on import FalseOnTime
from citysim.metrics.zones import ZoneTracker
from tests.citysim.metrics.test_metrics import DT_S, _agent, _street

ZONES_M = [(0.0, 10.0), (10.0, 20.0), (20.0, 30.0), (30.0, 40.0)]
#: zones out of street order, one inside another, one empty: the per-step path's general case
OVERLAPPING_ZONES_M = [(10.0, 20.0), (0.0, 15.0), (20.0, 20.0), (18.0, 40.0)]
DIM_LEVEL = 0.2


def false_on_by_arrays(street, dim_level: float, dt_s: float, target_x_m: np.ndarray, levels: np.ndarray) -> float:
    """One step's false on-time in numpy arrays: lamp-seconds lit above ``dim_level`` with no target
    in the zone."""
    starts = np.array([s.zone_start_m for s in street.lamps])
    ends = np.array([s.zone_end_m for s in street.lamps])
    lit = levels > dim_level + 1e-6
    if not lit.any():
        return 0.0
    if len(target_x_m):
        occupied = ((target_x_m[None, :] >= starts[:, None]) & (target_x_m[None, :] < ends[:, None])).any(axis=1)
    else:
        occupied = np.zeros(len(levels), dtype=bool)
    return dt_s * float(np.count_nonzero(lit & ~occupied))


def _steps(seed: int, n_steps: int = 600):
    """(agents, levels) per step: levels held for runs of steps (as a settled street's are), agents
    of target and other kinds at random places, sometimes none, sometimes on a zone's edge."""
    rng = np.random.default_rng(seed)
    levels = np.full(len(ZONES_M), DIM_LEVEL)
    steps = []
    for _ in range(n_steps):
        if rng.random() < 0.05:
            levels = rng.choice([DIM_LEVEL, DIM_LEVEL + 1e-7, 0.6, 1.0], size=len(ZONES_M))
        xs = rng.choice([0.0, 10.0, 19.999, 20.0, 35.0, 41.0], size=rng.integers(0, 4)).tolist()
        xs += rng.uniform(-5.0, 45.0, size=rng.integers(0, 3)).tolist()
        kinds = rng.choice(["pedestrian", "vehicle", "animal", "e_scooter"], size=len(xs))
        steps.append(([_agent(j, str(c), x, 1.0) for j, (c, x) in enumerate(zip(kinds, xs, strict=True))], levels))
    return steps


@pytest.mark.parametrize("zones_m", [ZONES_M, OVERLAPPING_ZONES_M])
def test_false_on_time_per_step_is_the_array_sum_bit_for_bit(zones_m):
    street = _street(zones_m)
    for seed in range(5):
        fast, long_s = FalseOnTime(street, DIM_LEVEL, DT_S), 0.0
        shared = None
        for k, (agents, levels) in enumerate(_steps(seed)):
            if shared is None or not np.array_equal(shared, levels):
                shared = levels.copy()
                shared.flags.writeable = False  # as LampStates passes them
            fast.on_step(k * DT_S, agents, shared)
            target_x_m = np.array([a.x_m for a in agents if a.is_target])
            long_s += false_on_by_arrays(street, DIM_LEVEL, DT_S, target_x_m, levels)
        assert fast.seconds == long_s and long_s > 0.0


def test_zone_tracker_with_shared_levels_is_the_same_as_with_copies():
    street = _street(ZONES_M)
    shared_tracker, copied_tracker = ZoneTracker(street), ZoneTracker(street)
    shared = None
    for k, (agents, levels) in enumerate(_steps(7)):
        if shared is None or not np.array_equal(shared, levels):
            shared = levels.copy()
            shared.flags.writeable = False
        shared_tracker.update((k + 1) * DT_S, agents, shared)
        copied_tracker.update((k + 1) * DT_S, agents, levels.copy())
    shared_tracker.finish((k + 2) * DT_S)
    copied_tracker.finish((k + 2) * DT_S)
    rows = list(shared_tracker.rows())
    assert rows == list(copied_tracker.rows()) and len(rows) > 10
    assert shared_tracker.summary() == copied_tracker.summary()
