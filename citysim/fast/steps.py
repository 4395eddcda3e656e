"""What fast mode reads of one step's agents: their candidates, nearest lamps and p_hit cells.

``StepGeometries.of(agents, rows)`` gives ``FastSensors`` a ``StepGeometry`` per sensed step: the
``Candidates`` of ``citysim.fast.geometry``, the lamp nearest each agent along the street (whose
level is the light at the agent) and, on first ask, every agent's p_hit cell for every camera.

A live world's step is computed from its agents. Replayed traffic (``citysim.sim.replay``) hands
out a chunk of recorded steps as columns (``AgentColumns``; ``rows`` says where the step's agents
stand in them): then the whole chunk is computed in one numpy pass, once, and each step's rows
are cut from it. Every value is elementwise (or a per-row search), the same operation on the same
numbers, so a step's values are its own bit for bit; numpy's per-call cost on a step's few
agents was most of fast mode's sensing.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from citysim.fast.geometry import CameraGeometry, Candidates
from citysim.fast.model import KINDS, cell_of
from citysim.fast.pairs import ChunkPairs, StepPairs
from citysim.world.agents import AgentColumns, AgentState

#: ``KINDS`` index of each kind's name
_KIND_INDEX = {name: i for i, name in enumerate(KINDS)}


def p_hit_cells(kinds: np.ndarray, cand: Candidates, speed_mps: np.ndarray) -> tuple[np.ndarray, ...]:
    """The p_hit cells of agents of ``KINDS`` indices ``kinds`` (A,) for every camera, less the
    frame's light and background age: (kind (A,), distance bin (A, C), bearing bin (A, C), speed bin (A,))."""
    cells = cell_of(kinds[:, None], cand.forward_m, cand.bearing_rad, np.zeros(1), np.zeros(1), speed_mps[:, None])
    return cells[0][:, 0], cells[1], cells[2], cells[5][:, 0]


class StepGeometry:
    """One step's agents seen from every camera: ``cand``, ``awake``, ``nearest_lamp`` (A,), ``cells``
    and ``pairs``, each made on first ask (``*_of``; a replayed step's ``cand`` is cut from its
    chunk's only when read: most frames read only ``awake`` and ``pairs``)."""

    def __init__(self, cand_of: Callable[[], Candidates], nearest_lamp: np.ndarray,
                 cells_of: Callable[[], tuple[np.ndarray, ...]], pairs_of: Callable[[], StepPairs] | None = None,
                 awake_of: Callable[[], list[bool]] | None = None):  # fmt: skip
        self._cand_of = cand_of
        self._cand: Candidates | None = None
        self._awake_of = awake_of
        self.nearest_lamp = nearest_lamp
        self._cells_of = cells_of
        self._cells: tuple[np.ndarray, ...] | None = None
        self._pairs_of = pairs_of
        self._pairs: StepPairs | None = None

    @property
    def cand(self) -> Candidates:
        if self._cand is None:
            self._cand = self._cand_of()
        return self._cand

    def awake(self) -> list[bool]:
        """``cand.awake`` as a list."""
        return self._awake_of() if self._awake_of is not None else self.cand.awake.tolist()

    @property
    def cells(self) -> tuple[np.ndarray, ...]:
        """``p_hit_cells`` of the step's agents, made on first ask (the threshold baselines never ask)."""
        if self._cells is None:
            self._cells = self._cells_of()
        return self._cells

    def pairs(self, table_shape: tuple[int, ...]) -> StepPairs:
        """The step's candidate pairs as lists (``citysim.fast.pairs``), made on first ask: cut from
        its chunk's, or found from the step's own arrays (``table_shape``: the p_hit table's)."""
        if self._pairs is None:
            if self._pairs_of is not None:
                self._pairs = self._pairs_of()
            else:
                chunk = ChunkPairs(self.cand, self.cells, self.nearest_lamp, table_shape)
                self._pairs = chunk.step(0, len(self.nearest_lamp), self.cand.seen.shape[1])
        return self._pairs


def step_of_agents(geometry: CameraGeometry, agents: Sequence[AgentState]) -> StepGeometry:
    """The ``StepGeometry`` of one step's ``agents``, computed from them."""

    def cells() -> tuple[np.ndarray, ...]:
        kinds = np.array([KINDS.index(a.cls) for a in agents], dtype=np.int64)
        return p_hit_cells(kinds, cand, np.array([a.speed_mps for a in agents], dtype=np.float64))

    cand = geometry.candidates(agents)
    x_m = np.fromiter((a.x_m for a in agents), np.float64, len(agents))
    return StepGeometry(lambda: cand, geometry.nearest_lamp(x_m), cells)


class ChunkGeometry:
    """``StepGeometry`` of every row of a chunk of replayed steps, computed for all rows at once
    (``table_shape``: the p_hit table's, for the pairs' cells)."""

    def __init__(self, geometry: CameraGeometry, columns: AgentColumns, table_shape: tuple[int, ...]):
        self.columns = columns
        xy = np.column_stack([columns.x_m, columns.y_m])
        self.cand = geometry.candidates_at(xy, columns.light_on, columns.heading_rad)
        self.nearest_lamp = geometry.nearest_lamp(columns.x_m)
        self.table_shape = table_shape
        self._cells: tuple[np.ndarray, ...] | None = None
        self._pairs: ChunkPairs | None = None
        self._wake: tuple[list[int], list[int]] | None = None

    def cells(self) -> tuple[np.ndarray, ...]:
        """``p_hit_cells`` of every row, made on first ask."""
        if self._cells is None:
            kinds = np.array([_KIND_INDEX[cls] for cls in self.columns.cls], dtype=np.int64)
            self._cells = p_hit_cells(kinds, self.cand, self.columns.speed_mps)
        return self._cells

    def pairs(self) -> ChunkPairs:
        """The candidate pairs of every row, made on first ask."""
        if self._pairs is None:
            self._pairs = ChunkPairs(self.cand, self.cells(), self.nearest_lamp, self.table_shape)
        return self._pairs

    def awake(self, first: int, n: int) -> list[bool]:
        """``cand.awake`` of the step of rows ``first`` to ``first + n``: whether any of them is in
        each camera's wake view, from the chunk's wake pairs (found once, as lists)."""
        if self._wake is None:
            rows, cameras = np.nonzero(self.cand.wake)
            self._wake = np.searchsorted(rows, np.arange(len(self.cand.wake) + 1)).tolist(), cameras.tolist()
        row_starts, cameras = self._wake
        awake = [False] * self.cand.wake.shape[1]
        for camera in cameras[row_starts[first] : row_starts[first + n]]:
            awake[camera] = True
        return awake

    def step(self, first: int, n: int) -> StepGeometry:
        """The step whose ``n`` agents are the rows from ``first``."""
        rows = slice(first, first + n)
        return StepGeometry(lambda: self.cand.rows(first, n), self.nearest_lamp[rows],
                            lambda: tuple(cells[rows] for cells in self.cells()),
                            lambda: self.pairs().step(first, n, self.cand.seen.shape[1]),
                            lambda: self.awake(first, n))  # fmt: skip


class StepGeometries:
    """The ``StepGeometry`` of each step asked for, from its chunk's one pass when it is replayed."""

    def __init__(self, geometry: CameraGeometry, table_shape: tuple[int, ...]):
        self.geometry = geometry
        self.table_shape = table_shape
        self._chunk: ChunkGeometry | None = None

    def of(self, agents: Sequence[AgentState], rows: tuple[AgentColumns, int] | None) -> StepGeometry:
        """The geometry of ``agents``; ``rows``: the replayed chunk's columns and the first row of
        ``agents`` in them (``TrafficReplay.rows_of``), None for agents of a live world."""
        if rows is None:
            return step_of_agents(self.geometry, agents)
        columns, first = rows
        if self._chunk is None or self._chunk.columns is not columns:
            self._chunk = ChunkGeometry(self.geometry, columns, self.table_shape)
        return self._chunk.step(first, len(agents))
