"""One replayed chunk of recorded steps, and a step's agents made only when someone reads them.

``TrafficReplay.next_step`` (``citysim.sim.replay``) hands out a ``RecordedAgents`` per physics
step: a read-only sequence of the step's ``AgentState`` snapshots that builds them on first read
(the same objects, bit for bit, as the recorded world's ``states()``). Most readers of a fast run
never read them: the metrics (``citysim.metrics``) and the oracle compute over the chunk's
columns once per chunk instead, and find them through the step's ``chunk`` and ``step``
attributes. Building every agent's snapshot each step was a third of a fast run's base cost.

A ``RecordedChunk``'s per-row arrays hold one row per agent and step, step after step; step ``s``
is rows ``step_first[s]`` to ``step_first[s + 1]``.
"""

from __future__ import annotations

from collections.abc import Collection, Iterator, Sequence
from functools import cached_property
from typing import overload

import numpy as np

from citysim.world.agents import AgentColumns, AgentState, MemberState, frozen_from_fields

#: the columns of a chunk's per-agent rows
DYNAMIC_COLUMNS = ("x_m", "y_m", "heading_rad", "speed_mps", "gait_phase_rad")


class RecordedChunk:
    """A chunk file's steps as columns (``looks``: object id -> its looks, every row's object in it)."""

    def __init__(self, data: dict, looks: dict):
        counts = data["counts"].astype(np.int64)
        self.n_steps = len(counts)
        self.step_first = np.concatenate(([0], np.cumsum(counts)))
        self.first_list: list[int] = self.step_first.tolist()
        self.spawned: list[int] = data["spawned"].tolist()
        self.object_id: np.ndarray = data["objects"]  # int64 per row
        self.rows: np.ndarray = data["rows"]  # float64, one row of DYNAMIC_COLUMNS per agent and step
        self.member_phases: np.ndarray = data["member_phases"]
        ids, self.object_index = np.unique(self.object_id, return_inverse=True)
        #: the looks of the chunk's objects, in ``object_index`` order
        self.object_looks = [looks[i] for i in ids.tolist()]
        members = np.array([len(lk.members) for lk in self.object_looks], np.int64)[self.object_index]
        self.member_first = np.concatenate(([0], np.cumsum(members))).tolist()  # per row

    def column(self, name: str) -> np.ndarray:
        """One of ``DYNAMIC_COLUMNS`` of every row (a view)."""
        return self.rows[:, DYNAMIC_COLUMNS.index(name)]

    @cached_property
    def step_of_row(self) -> np.ndarray:
        return np.repeat(np.arange(self.n_steps), np.diff(self.step_first))

    @cached_property
    def object_list(self) -> list[int]:
        return self.object_id.tolist()

    @cached_property
    def x_list(self) -> list[float]:
        return self.column("x_m").tolist()

    @cached_property
    def cls_list(self) -> list[str]:
        return [self.object_looks[i].cls for i in self.object_index.tolist()]

    def of_kinds(self, kinds: Collection[str]) -> np.ndarray:
        """Per row: whether its object's class is one of ``kinds`` (bool)."""
        return np.array([lk.cls in kinds for lk in self.object_looks], dtype=bool)[self.object_index]

    @cached_property
    def columns(self) -> AgentColumns:
        """Every row as ``AgentColumns`` (fast mode's candidates read them)."""
        x_m, y_m, heading_rad, speed_mps = (np.ascontiguousarray(self.column(name))
                                            for name in ("x_m", "y_m", "heading_rad", "speed_mps"))  # fmt: skip
        light_on = np.array([lk.light_on for lk in self.object_looks], dtype=bool)[self.object_index]
        return AgentColumns(x_m, y_m, heading_rad, speed_mps, tuple(self.cls_list), light_on)

    def agents(self, step: int) -> list[AgentState]:
        """The snapshots of step ``step``'s agents, in recorded order."""
        first, end = self.first_list[step], self.first_list[step + 1]
        out = []
        phases = self.member_phases[self.member_first[first] : self.member_first[end]].tolist()
        member = 0  # this step's members' phases used so far
        for oid, index, (x, y, heading, speed, phase) in zip(
            self.object_id[first:end].tolist(), self.object_index[first:end].tolist(),
            self.rows[first:end].tolist(), strict=True,
        ):  # fmt: skip
            looks = self.object_looks[index]
            members = ()
            if looks.members:
                own = phases[member : member + len(looks.members)]
                member += len(looks.members)
                members = tuple(MemberState(*m, p) for m, p in zip(looks.members, own, strict=True))
            out.append(frozen_from_fields(AgentState, {"object_id": oid, "cls": looks.cls, "x_m": x, "y_m": y, "heading_rad": heading,
                                     "speed_mps": speed, "length_m": looks.length_m, "width_m": looks.width_m,
                                     "height_m": looks.height_m, "gait_phase_rad": phase, "members": members,
                                     "light_on": looks.light_on}))  # fmt: skip
        return out


class RecordedAgents(Sequence[AgentState]):
    """Step ``step`` of ``chunk``'s agents: a read-only sequence whose snapshots are made on first read."""

    __slots__ = ("chunk", "step", "first", "_n", "_agents")

    def __init__(self, chunk: RecordedChunk, step: int):
        self.chunk, self.step = chunk, step
        self.first = chunk.first_list[step]
        self._n = chunk.first_list[step + 1] - self.first
        self._agents: list[AgentState] | None = None

    def __len__(self) -> int:
        return self._n

    def _list(self) -> list[AgentState]:
        if self._agents is None:
            self._agents = self.chunk.agents(self.step) if self._n else []
        return self._agents

    @overload
    def __getitem__(self, index: int) -> AgentState: ...
    @overload
    def __getitem__(self, index: slice) -> list[AgentState]: ...
    def __getitem__(self, index):
        return self._list()[index]

    def __iter__(self) -> Iterator[AgentState]:
        return iter(self._list())

    def __repr__(self) -> str:
        return f"RecordedAgents(step={self.step}, n={self._n})"
