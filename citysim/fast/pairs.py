"""A step's (agent, camera) candidate pairs as plain lists, camera by camera.

A judged camera draws a hit per candidate from the p_hit cell of that candidate in that camera
(``FastSensors``). Asking numpy for each camera's few candidates (slice the indices, index the
cells, the table and the persistence, then convert) cost more than the draws themselves, ~100k
times an hour at 22:00, and so did a numpy pass per step for every camera at once. Replayed
traffic comes in chunks of many steps (``citysim.fast.steps.ChunkGeometry``): ``ChunkPairs``
finds the pairs of every row of a chunk in one numpy pass and reads, per pair, its forward
distance, its agent's kind and nearest lamp and its p_hit cell (as a flat index into the table,
less the light and background-age bins); ``StepPairs`` cuts a step's rows from those lists and
orders them as ``np.nonzero(seen.T)`` did per step (cameras ascending, each camera's agents
ascending). Every value is an element read from the same arrays, so it is bit for bit the one the
per-camera numpy reads gave.

``CandidatePairs`` is the numpy form (index arrays) the threshold baselines' segmenters read.
"""

from __future__ import annotations

from itertools import accumulate

import numpy as np

from citysim.fast.geometry import Candidates


class CandidatePairs:
    """The pairs ``matrix`` (A, C; bool) marks, grouped by camera: the agents' indices (``of``)."""

    def __init__(self, matrix: np.ndarray, n_cameras: int):
        cameras, agents = np.nonzero(matrix.T)
        self.agents = agents
        self.starts: list[int] = np.searchsorted(cameras, np.arange(n_cameras + 1)).tolist()

    def of(self, camera: int) -> np.ndarray:
        """The indices of camera ``camera``'s agents (ascending)."""
        return self.agents[self.starts[camera] : self.starts[camera + 1]]


class ChunkPairs:
    """The candidate pairs of every row of a chunk of steps (``cand``'s, R rows), row by row, and
    where its beam pairs are (only whether a step has any is read here).

    ``cells``: the rows' p_hit cells less light and age (kind (R,), distance (R, C), bearing (R, C),
    speed (R,)), indices into a table of ``table_shape``; ``nearest_lamp`` (R,): each row's lamp."""

    def __init__(self, cand: Candidates, cells: tuple[np.ndarray, ...], nearest_lamp: np.ndarray,
                 table_shape: tuple[int, ...]):  # fmt: skip
        rows, cameras = np.nonzero(cand.seen)  # row-major: each row's cameras ascending
        kind, distance, bearing, speed = cells
        zeros = np.zeros(len(rows), np.int64)
        base = np.ravel_multi_index((kind[rows], distance[rows, cameras], bearing[rows, cameras], zeros, zeros,
                                     speed[rows]), table_shape)  # fmt: skip
        row_bounds = np.arange(len(cand.seen) + 1)
        self.row_starts: list[int] = np.searchsorted(rows, row_bounds).tolist()
        self.beam_row_starts: list[int] = np.searchsorted(np.nonzero(cand.beam_seen)[0], row_bounds).tolist()
        self.rows: list[int] = rows.tolist()
        self.cameras: list[int] = cameras.tolist()
        self.forward_m: list[float] = cand.forward_m[rows, cameras].tolist()
        self.kind: list[int] = kind[rows].tolist()
        self.lamp: list[int] = nearest_lamp[rows].tolist()
        self.cell: list[int] = base.tolist()
        # the table's light and background-age axes (the fourth and fifth): their strides, entries
        self.lit_stride = int(np.prod(table_shape[4:]))
        self.young_stride = int(np.prod(table_shape[5:]))

    def step(self, first: int, n: int, n_cameras: int) -> StepPairs:
        """The pairs of the step whose agents are rows ``first`` to ``first + n``."""
        return StepPairs(self, first, n, n_cameras)


class StepPairs:
    """One step's pairs, camera by camera: per pair its agent's index in the step (``agents``),
    forward distance (m), kind (``KINDS`` index), nearest lamp and p_hit cell (flat, light and age
    0); ``bounds(camera)``: where the camera's pairs are in those lists; ``p_hit`` their P(hit);
    ``beams``: how many beam pairs the step has (any camera's)."""

    def __init__(self, chunk: ChunkPairs, first: int, n: int, n_cameras: int):
        lo, hi = chunk.row_starts[first], chunk.row_starts[first + n]
        self.beams = chunk.beam_row_starts[first + n] - chunk.beam_row_starts[first]
        self.lit_stride, self.young_stride = chunk.lit_stride, chunk.young_stride
        if lo == hi:  # road users about, none a candidate
            self.agents, self.forward_m, self.kind, self.lamp, self.cell = [], [], [], [], []
            self.counts, self.starts = [0] * n_cameras, [0] * (n_cameras + 1)
            return
        cameras = chunk.cameras
        step_cameras = cameras[lo:hi]
        if step_cameras == sorted(step_cameras):  # most steps: already camera by camera, the lists' slices
            self.agents = [row - first for row in chunk.rows[lo:hi]]
            self.forward_m, self.kind = chunk.forward_m[lo:hi], chunk.kind[lo:hi]
            self.lamp, self.cell = chunk.lamp[lo:hi], chunk.cell[lo:hi]
        else:
            # stable: within a camera the rows (agents) stay ascending, as np.nonzero(seen.T) gave them
            order = sorted(range(lo, hi), key=cameras.__getitem__)
            self.agents = [chunk.rows[q] - first for q in order]
            self.forward_m = [chunk.forward_m[q] for q in order]
            self.kind = [chunk.kind[q] for q in order]
            self.lamp = [chunk.lamp[q] for q in order]
            self.cell = [chunk.cell[q] for q in order]
        self.counts = [0] * n_cameras  # pairs per camera
        for camera in step_cameras:
            self.counts[camera] += 1
        self.starts = [0, *accumulate(self.counts)]

    def count(self, camera: int) -> int:
        return self.starts[camera + 1] - self.starts[camera]

    def bounds(self, camera: int) -> tuple[int, int]:
        return self.starts[camera], self.starts[camera + 1]

    def p_hit(self, camera: int, p_hit_flat: list[float], lamps_lit: list[int], young: bool) -> list[float]:
        """P(hit) of camera ``camera``'s pairs: each pair's cell at its lamp's light bin
        (``lamps_lit``: per lamp, 1 when lit) and the background's age bin (``young``), read from
        the raveled p_hit table ``p_hit_flat``."""
        first, end = self.bounds(camera)
        young_at, lit_stride, cell, lamp = self.young_stride if young else 0, self.lit_stride, self.cell, self.lamp
        return [p_hit_flat[cell[q] + lit_stride * lamps_lit[lamp[q]] + young_at] for q in range(first, end)]
