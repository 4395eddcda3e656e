"""The one protocol through which the run loop feeds every figure of a run.

A collector is told about each physics step (the agents and the lamps' levels), each judged
camera frame (the renderer's truth and the detector's answer), each whole simulated second,
and the end of the run; ``finish`` returns its part of the controller's summary. The loop
(``citysim.sim.loop``) calls every collector alike, so a new figure is one new collector,
not a new wire through the loop. Collectors stream: none keeps per-step history.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from citysim.world.agents import AgentState


class Collector:
    """Base collector: every hook does nothing; override the ones a figure needs.

    Times are simulated seconds from the start of the run; ``levels`` holds one visible-light
    level (0..1) per street lamp at ``t_s``.
    """

    def on_step(self, t_s: float, agents: Sequence[AgentState], levels: np.ndarray) -> None:
        """After each physics step."""

    def on_frame(self, lamp_index: int, t_s: float, truth: Sequence, detections: Sequence | None) -> None:
        """After lamp ``lamp_index``'s camera frame was judged (``detections`` None: not judged)."""

    def on_second(self, t_s: float) -> None:
        """At each whole second before the end (t = 0, 1, 2, ...), before that instant's events."""

    def finish(self, t_end_s: float) -> dict[str, Any]:
        """At the end of the run: this collector's figures for the summary."""
        return {}


def overriding(collectors: Sequence[Collector], hook: str) -> list[Collector]:
    """The collectors whose class overrides ``hook`` (e.g. "on_step"), in order: the base's hooks do
    nothing, and the loop calls them up to 30 times a simulated second."""
    base = getattr(Collector, hook)
    return [c for c in collectors if getattr(type(c), hook, None) is not base or hook in getattr(c, "__dict__", {})]
