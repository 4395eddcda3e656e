"""What the metrics read of a replayed step: its chunk's rows, placed in the lamp zones once a chunk.

A replayed step's agents (``citysim.sim.recorded.RecordedAgents``) carry their ``chunk`` (one row
per agent and step, numpy columns over a minute of steps) and their ``step`` in it. A collector
that knows where every row of a chunk stands (which zone holds it, which zones each step's
targets occupy) computes that in one numpy pass per chunk, where asking each agent of each step
was most of a fast run's metrics. Agents of a live world carry no chunk: collectors take their
per-agent path then.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def recorded_step(agents: Any) -> tuple[Any, int] | None:
    """(chunk, step) of a replayed step's agents; None for any other sequence of agents."""
    chunk = getattr(agents, "chunk", None)
    return None if chunk is None else (chunk, agents.step)


def zone_of(starts_m: np.ndarray, ends_m: np.ndarray, x_m: np.ndarray) -> np.ndarray:
    """Per point, the index of the zone [start, end) holding it, -1 for none; the zones are in
    start order, each ending at or before the next starts (so only the last one starting at or
    before a point can hold it: ``bisect_right(starts, x) - 1``, the per-agent paths' look-up)."""
    place = place_of(starts_m, ends_m, x_m)
    return np.where(place >= 0, place, -1)


def place_of(starts_m: np.ndarray, ends_m: np.ndarray, x_m: np.ndarray) -> np.ndarray:
    """Per point, like ``zone_of``, the index of the zone holding it, or for a point in no zone
    -2 - i for the gap after zone i (-1 before the first): two points of the same gap see no zone
    between them."""
    j = np.searchsorted(starts_m, x_m, side="right") - 1
    inside = (j >= 0) & (x_m < ends_m[np.maximum(j, 0)])
    return np.where(inside, j, -2 - j)


def step_masks(chunk: Any, zone: np.ndarray) -> list[int]:
    """Per step of ``chunk``: the bitmask of the zones (bit j: zone j) holding any of its rows
    (``zone``: per row, -1 for rows that count nowhere)."""
    held = zone >= 0
    masks = np.zeros(chunk.n_steps, dtype=np.int64)
    np.bitwise_or.at(masks, chunk.step_of_row[held], np.left_shift(np.int64(1), zone[held].astype(np.int64)))
    return masks.tolist()


def lit_mask(levels: list[float], is_lit) -> int:
    """The bitmask of the zones whose lamp's level ``is_lit(level)``."""
    return sum(1 << j for j, level in enumerate(levels) if is_lit(level))
