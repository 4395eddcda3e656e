"""``ZoneTracker``'s short path for replayed steps (``citysim.metrics.recorded_rows``).

Most physics steps of a night change nothing a zone tracker holds: every tracked object stays in
the one zone it is visiting, whose lamp's level did not change, so no visit opens or closes and
its step is lit or dark throughout (``ZoneTracker._stays_in_zone``). For replayed steps that is
known of a whole chunk at once: ``ZoneChunk`` marks the *static* steps, whose tracked objects are
the previous step's, each in the same zone (or the same gap between zones) as then. A static step with the previous step's levels
(the same shared read-only array, ``LampStates``) after a *settled* step (each tracked object's
only open visit is the zone holding it, and it was lit already unless its zone is dark; objects in
a gap have none) is the long path's step, bit for bit, in a few operations: nothing for objects
in lit zones or gaps, and one step's dark seconds for those in dark zones. Other steps take the long path, reading the rows'
object ids, classes and positions instead of building the agents' snapshots.

Valid for disjoint zones in start order, one required level for every class and no look-ahead
(every kind's default): an object's span is then its centre, ``[x, x]``.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np

from citysim.metrics.recorded_rows import lit_mask, place_of, step_masks


class ZoneChunk:
    """What the short path reads of one replayed chunk: per row the place of a tracked object
    (``place_of``: the lamp index of the zone holding it, negative in a gap between zones or
    before or after them; -1 too for rows not tracked), per step whether it is static and the
    zones its tracked objects occupy (bitmask)."""

    def __init__(self, chunk: Any, tracked_kinds, starts_m: np.ndarray, ends_m: np.ndarray, order: list[int]):
        self.chunk = chunk
        tracked = chunk.of_kinds(tracked_kinds)
        in_sorted = place_of(starts_m, ends_m, chunk.column("x_m"))
        zone = np.where(in_sorted >= 0, np.asarray(order)[np.maximum(in_sorted, 0)], in_sorted)
        zone[~tracked] = -1
        self.zone: list[int] = zone.tolist()
        self.tracked: list[bool] = tracked.tolist()
        self.static: list[bool] = _static_steps(chunk, tracked, zone)
        self.occupied: list[int] = step_masks(chunk, zone)


def _static_steps(chunk: Any, tracked: np.ndarray, zone: np.ndarray) -> list[bool]:
    """Per step: its tracked objects are the previous step's, each in the same zone or the same
    gap as then. The first step of a chunk is never static (its previous step is another chunk's)."""
    rows = np.flatnonzero(tracked)
    step, oid, where = chunk.step_of_row[rows], chunk.object_id[rows], zone[rows]
    by_object = np.lexsort((step, oid))  # each object's rows in step order
    s, o, z = step[by_object], oid[by_object], where[by_object]
    stayed = np.zeros(len(rows), dtype=bool)
    stayed[1:] = (o[1:] == o[:-1]) & (s[1:] == s[:-1] + 1) & (z[1:] == z[:-1])
    moved = np.bincount(s[~stayed], minlength=chunk.n_steps) > 0
    count = np.bincount(step, minlength=chunk.n_steps)
    static = ~moved
    static[1:] &= count[1:] == count[:-1]  # none of the previous step's objects left
    static[0] = False
    return static.tolist()


class RecordedZones:
    """The short path's state beside one ``ZoneTracker``: the current chunk's ``ZoneChunk``, the
    latest step seen, whether it left the tracker settled, and the latest step skipped (its spans
    are given to the tracks before the long path runs again)."""

    def __init__(self, tracked_kinds, starts_m: np.ndarray, ends_m: np.ndarray, order: list[int], is_lit):
        self.tracked_kinds = tuple(tracked_kinds)
        self.starts_m, self.ends_m, self.order = starts_m, ends_m, order
        self.is_lit = is_lit  # level -> whether an object needing the required level is lit
        self._zones: ZoneChunk | None = None
        self._latest: tuple[Any, int] | None = None  # (chunk, step) of the latest update
        self._settled = False
        self._skipped: tuple[ZoneChunk, int] | None = None
        self._lit: tuple[np.ndarray | None, int] = (None, 0)  # a levels array and its lit bitmask

    def step_of(self, agents) -> tuple[ZoneChunk, int] | None:
        chunk = getattr(agents, "chunk", None)  # ``recorded_step``, asked every step
        if chunk is None:
            return None
        step = agents.step
        if self._zones is None or self._zones.chunk is not chunk:
            self._zones = ZoneChunk(chunk, self.tracked_kinds, self.starts_m, self.ends_m, self.order)
        return self._zones, step

    def skip(
        self, tracks: dict, at: tuple[ZoneChunk, int], t0_s: float | None, t1_s: float, levels: np.ndarray, same_levels: bool
    ) -> bool:
        """Do step ``at``'s work if it is a static step after a settled one with the previous
        step's levels (``same_levels``) and say so; else False, nothing done."""
        zones, step = at
        previous, self._latest = self._latest, (zones.chunk, step)
        if not (same_levels and self._settled and zones.static[step] and previous == (zones.chunk, step - 1)):
            return False
        if self._lit[0] is not levels:
            self._lit = (levels, lit_mask(levels.tolist(), self.is_lit))
        dark = zones.occupied[step] & ~self._lit[1]
        if dark:  # the long path's dark step of each object in a dark zone (``_stays_in_zone``)
            dt_s = t1_s - t0_s
            first, end = zones.chunk.first_list[step], zones.chunk.first_list[step + 1]
            objects = zones.chunk.object_list
            for row in range(first, end):
                j = zones.zone[row]
                if j >= 0 and dark >> j & 1:
                    track = tracks[objects[row]]
                    track.visits[j].dark_s += 1.0 * dt_s
                    track.dark_s += 1.0 * dt_s
        self._skipped = (zones, step)
        return True

    def give_spans(self, tracks: dict) -> None:
        """Before the long path: the tracks' spans of the latest skipped step (skipping leaves them)."""
        if self._skipped is None:
            return
        zones, step = self._skipped
        chunk = zones.chunk
        for row in range(chunk.first_list[step], chunk.first_list[step + 1]):
            if zones.tracked[row]:
                track = tracks[chunk.object_list[row]]
                track.lo_m = track.hi_m = chunk.x_list[row]
        self._skipped = None

    def spans(self, at: tuple[ZoneChunk, int]) -> Iterator[tuple[int, str, float, float]]:
        """(object id, class, span low, span high) of step ``at``'s rows, as the agents give them."""
        chunk, step = at[0].chunk, at[1]
        first, end = chunk.first_list[step], chunk.first_list[step + 1]
        x_m = chunk.x_list[first:end]
        return zip(chunk.object_list[first:end], chunk.cls_list[first:end], x_m, x_m, strict=True)

    def after_long_path(self, tracks: dict, at: tuple[ZoneChunk, int], levels: list[float]) -> None:
        """Whether the long path left step ``at`` settled: every tracked object in a zone has that
        zone's visit open and no other, lit already unless the zone is dark; every one in a gap
        has no visit open (a static step moves it along its gap, touching no zone: nothing to do)."""
        zones, step = at
        chunk = zones.chunk
        self._settled = False
        for row in range(chunk.first_list[step], chunk.first_list[step + 1]):
            if not zones.tracked[row]:
                continue
            j = zones.zone[row]
            visits = tracks[chunk.object_list[row]].visits
            if j < 0:
                if visits:
                    return
            elif len(visits) != 1 or j not in visits or (visits[j].t_lit_s is None and self.is_lit(levels[j])):
                return
        self._settled = True
