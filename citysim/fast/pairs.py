"""One step's (agent, camera) candidate pairs as plain lists, camera by camera.

A judged camera draws a hit per candidate from the p_hit cell of that candidate in that camera
(``FastSensors``). Asking numpy for each camera's few candidates (slice the indices, index the
cells, the table and the persistence, then convert) cost more than the draws themselves, ~100k
times an hour at 22:00. ``CandidatePairs`` does it once per step for every camera's candidates at
once, in the order the per-camera slices had (cameras ascending, each camera's agents ascending),
and hands out list slices. Every value is an element read from the same arrays (no arithmetic),
so a camera's values are the ones its own slices gave, bit for bit.
"""

from __future__ import annotations

import numpy as np


class CandidatePairs:
    """The pairs ``matrix`` (A, C; bool) marks, grouped by camera: the agents' indices as an array
    (``of``) and a list (``agents_of``), and where each camera's pairs start and end (``bounds``)."""

    def __init__(self, matrix: np.ndarray, n_cameras: int):
        cameras, agents = np.nonzero(matrix.T)
        self.cameras = cameras
        self.agents = agents
        self.starts: list[int] = np.searchsorted(cameras, np.arange(n_cameras + 1)).tolist()
        self._agent_list: list[int] | None = None

    def of(self, camera: int) -> np.ndarray:
        """The indices of camera ``camera``'s agents (ascending)."""
        return self.agents[self.starts[camera] : self.starts[camera + 1]]

    def count(self, camera: int) -> int:
        return self.starts[camera + 1] - self.starts[camera]

    def bounds(self, camera: int) -> tuple[int, int]:
        """Where camera ``camera``'s pairs start and end in the lists below."""
        return self.starts[camera], self.starts[camera + 1]

    @property
    def agent_list(self) -> list[int]:
        """Every pair's agent index, as a list."""
        if self._agent_list is None:
            self._agent_list = self.agents.tolist()
        return self._agent_list


class PairDrawInputs:
    """What a hit draw reads of every candidate pair of one step: the forward distance (m, per
    pair; the frame's truth reads it too), the kind's persistence (``persistence_of``) and, per
    frame's light, the p_hit of each pair with an old and with a young background (``p_of``)."""

    def __init__(self, pairs: CandidatePairs, forward_m: np.ndarray):
        self.pairs = pairs
        self.forward_m: list[float] = forward_m[pairs.agents, pairs.cameras].tolist()
        self._persistence: list[float] | None = None

    def persistence_of(self, kind: np.ndarray, persistence: np.ndarray) -> list[float]:
        """Per pair, the persistence of its agent's kind: ``persistence`` (per ``KINDS`` index) at
        ``kind`` (per agent); made on first ask (the threshold baselines never draw hits)."""
        if self._persistence is None:
            self._persistence = persistence[kind[self.pairs.agents]].tolist()
        return self._persistence

    def p_of(self, p_hit: np.ndarray, cells: tuple[np.ndarray, ...], lit_cells: np.ndarray) -> list[list[float]]:
        """Per pair, ``[p_hit old, p_hit young]`` of its cell with the frame's light bin ``lit_cells`` (A,)."""
        a, c = self.pairs.agents, self.pairs.cameras
        kind, distance, bearing, speed = cells
        # the young axis left whole: the two entries a camera picks from by its background's age
        return p_hit[kind[a], distance[a, c], bearing[a, c], lit_cells[a], :, speed[a]].tolist()
