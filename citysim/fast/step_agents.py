"""A step's agents as fast sensing reads them, without having the step's snapshots made.

A replayed step's agents (``citysim.sim.recorded.RecordedAgents``) make every agent's
``AgentState`` of the step on the first read of any one of them. Nothing but fast sensing reads
them in a fast run (the metrics and the oracle read the chunk's columns), and sensing reads a
few agents of most steps (a candidate's id, class, position and size): building every snapshot
of those steps was about a tenth of a fast detector_located run. ``StepAgents`` reads just the
agents asked for from the chunk's rows, as ``RecordedChunk.agents`` does (the same arrays, the
same conversions: ints and floats by ``tolist``, the looks' own values), into a ``RowAgent``
with the fields sensing reads. A live world's agents are its ``AgentState`` list, read as it is.
"""

from __future__ import annotations

from collections.abc import Sequence


class RowAgent:
    """The fields of an ``AgentState`` fast sensing reads (its class, id, pose, speed and size)."""

    __slots__ = ("object_id", "cls", "x_m", "y_m", "heading_rad", "speed_mps", "length_m", "width_m", "height_m",
                 "light_on")  # fmt: skip

    def __init__(self, chunk, row: int):
        """Row ``row`` of ``chunk`` (a ``citysim.sim.recorded.RecordedChunk``)."""
        looks = chunk.object_looks[chunk.object_index[row]]
        self.object_id: int = int(chunk.object_id[row])  # the int64's value, as tolist gives it
        self.cls: str = looks.cls
        self.x_m, self.y_m, self.heading_rad, self.speed_mps, _ = chunk.rows[row].tolist()
        self.length_m, self.width_m, self.height_m = looks.length_m, looks.width_m, looks.height_m
        self.light_on = looks.light_on


class StepAgents:
    """``agents[j]`` of one step's ``agents``: a replayed step's from its chunk's rows (each made once
    on first read, a ``RowAgent``), a live step's its own."""

    __slots__ = ("agents", "_chunk", "_first", "_made")

    def __init__(self, agents: Sequence):
        self.agents = agents
        chunk = getattr(agents, "chunk", None)  # a replayed step: its chunk and first row
        self._chunk = chunk if chunk is not None and hasattr(chunk, "object_looks") else None
        self._first = agents.first if self._chunk is not None else 0
        self._made: dict[int, RowAgent] = {}

    def __getitem__(self, index: int):
        if self._chunk is None:
            return self.agents[index]
        agent = self._made.get(index)
        if agent is None:
            if not 0 <= index < len(self.agents):
                raise IndexError(f"StepAgents: agent {index} of {len(self.agents)}")
            agent = self._made[index] = RowAgent(self._chunk, self._first + index)
        return agent
