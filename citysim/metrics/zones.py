"""Illumination lag and dark exposure per object and lamp zone, streamed step by step.

``ZoneTracker`` holds O(agents + lamps) state between physics steps and emits
one row per completed zone visit, which the caller writes out and drops
(``rows()`` drains). Distributions come from ``QuantileSketch``.

Zone convention: lamp j (``street.lamps[j]``) is responsible for x in
``[zone_start_m, zone_end_m)``; an object is in a zone while the x of its
centre is. An object needs light from ``lookahead_s`` ahead: it occupies every
zone that the segment from its centre to ``x + v_x * lookahead_s`` touches, so
a vehicle "enters" a zone lookahead_s before its centre does and leaves when
its centre leaves.

Between two ``update`` calls positions and lamp levels are taken to move
linearly (lamp ramps are linear, and a physics step is short), so entry,
exit, first-lit times and dark seconds are solved inside the step rather than
rounded to it; the error is below one physics step (largest where a ramp ends
inside a step).
"""

from __future__ import annotations

import bisect
import math
from collections import deque
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from citysim.config.kinds import AGENT_KINDS, TARGET_KINDS
from citysim.control.lamps import check_number
from citysim.metrics.quantiles import QuantileSketch
from citysim.metrics.spans import intersect, nonneg_span, pos_span
from citysim.metrics.zone_rows import RecordedZones
from citysim.world.agents import AgentState
from citysim.world.street import Street

#: Seconds of look-ahead per class (``AgentKind.lookahead_s``). A zone must be lit when an
#: object enters it ("the lamps ahead lit before it arrives"), so every kind's is 0 s. A
#: stricter stopping-sight look-ahead (a driver needing the road lit about two seconds
#: ahead, ~33 m at 60 km/h; a cyclist about one) can be set per kind, but no camera with the
#: paper's 25 m range can meet it at the first lamp of a chain.
DEFAULT_LOOKAHEAD_S = {name: AGENT_KINDS[name].lookahead_s for name in TARGET_KINDS}

_LEVEL_TOL = 1e-9  # a ramp that ends exactly at the required level counts as reaching it


@dataclass
class _Visit:
    t_enter_s: float
    lit_on_entry: bool
    t_lit_s: float | None
    dark_s: float = 0.0


@dataclass
class _Track:
    cls: str
    lo_m: float  # x extent of the stretch the object needs lit, at the last update
    hi_m: float
    visits: dict[int, _Visit]
    dark_s: float = 0.0
    n_visits: int = 0


class ZoneTracker:
    """Per object and lamp zone: entry, lag to the required light, dark seconds.

    ``required_level``: class -> lamp level (0..1) the class needs; only these
    classes are tracked (default: 1.0 for every target kind). ``lookahead_s``:
    class -> seconds of look-ahead (default ``DEFAULT_LOOKAHEAD_S``).
    Call ``update`` every physics step, ``finish`` at the end, drain ``rows``.
    """

    def __init__(
        self,
        street: Street,
        required_level: dict[str, float] | None = None,
        lookahead_s: dict[str, float] | None = None,
    ) -> None:
        self.required_level = (
            dict.fromkeys(TARGET_KINDS, 1.0) if required_level is None else dict(required_level)
        )
        for cls, level in self.required_level.items():
            check_number("ZoneTracker.required_level", cls, level, 0.0, 1.0)
        self.lookahead_s = dict(DEFAULT_LOOKAHEAD_S if lookahead_s is None else lookahead_s)
        for cls, seconds in self.lookahead_s.items():
            check_number("ZoneTracker.lookahead_s", cls, seconds, 0.0)
        if not street.lamps:
            raise ValueError("ZoneTracker.street.lamps: a street needs at least one lamp zone")
        for j, site in enumerate(street.lamps):
            if not site.zone_end_m > site.zone_start_m:
                raise ValueError(
                    f"ZoneTracker.street.lamps[{j}]: zone_end_m ({site.zone_end_m}) must exceed "
                    f"zone_start_m ({site.zone_start_m})"
                )
        self._starts = np.array([s.zone_start_m for s in street.lamps], dtype=float)
        self._ends = np.array([s.zone_end_m for s in street.lamps], dtype=float)
        self._lamp_ids = [s.index for s in street.lamps]
        order = np.argsort(self._starts, kind="stable")
        # zones sorted by start whose ends are sorted too: those touching a segment form one run
        self._order = order.tolist() if np.all(np.diff(self._ends[order]) >= 0) else None
        # plain floats: per-agent work is scalar, where numpy scalars only add overhead
        self._sorted_starts, self._sorted_ends = (
            self._starts[order].tolist(),
            self._ends[order].tolist(),
        )
        self._start_m, self._end_m = self._starts.tolist(), self._ends.tolist()
        # zones that do not overlap: a span inside one zone touches no other (``_stays_in_zone``)
        self._disjoint = self._order is not None and all(
            end <= start for end, start in zip(self._sorted_ends[:-1], self._sorted_starts[1:], strict=True)
        )
        self._recorded = self._short_path()
        self._t_s: float | None = None
        self._levels: list[float] | None = None
        self._levels_array: np.ndarray | None = None  # the read-only array ``_levels`` was listed from
        self._tracks: dict[int, _Track] = {}
        self._done: deque[dict[str, Any]] = deque()
        self._lag = {c: QuantileSketch() for c in self.required_level}
        self._dark = {c: QuantileSketch() for c in self.required_level}
        self._counts = {
            c: {"visits": 0, "unlit_crossings": 0, "lit_on_entry": 0} for c in self.required_level
        }

    def _short_path(self) -> RecordedZones | None:
        """The short path of replayed steps (``citysim.metrics.zone_rows``) where it holds: disjoint
        zones, one required level, no look-ahead."""
        reqs = set(self.required_level.values())
        if not self._disjoint or len(reqs) != 1 or any(self.lookahead_s.get(c, 0.0) for c in self.required_level):
            return None
        req = reqs.pop()
        return RecordedZones(self.required_level, self._starts[self._order], self._ends[self._order], self._order,
                             lambda level: level - req + _LEVEL_TOL >= 0.0)  # ``_stays_in_zone``'s test  # fmt: skip

    # ------------------------------------------------------------------ stepping
    def _need_span(self, agent: AgentState) -> tuple[float, float]:
        x_m = float(agent.x_m)
        lookahead_s = self.lookahead_s.get(agent.cls, 0.0)
        if not lookahead_s:  # no look-ahead (every kind's default): min and max below both give x_m
            return x_m, x_m
        ahead_m = float(agent.speed_mps * math.cos(agent.heading_rad)) * lookahead_s
        return min(x_m, x_m + ahead_m), max(x_m, x_m + ahead_m)

    def _zones_touching(self, lo_m: float, hi_m: float) -> Sequence[int]:
        if self._order is None:
            return np.flatnonzero((self._starts <= hi_m) & (self._ends > lo_m)).tolist()
        first = bisect.bisect_right(self._sorted_ends, lo_m)
        last = bisect.bisect_right(self._sorted_starts, hi_m)
        return self._order[first:last]

    def update(self, t_s: float, agents: Sequence[AgentState], levels: np.ndarray) -> None:
        """Account for the step from the previous call to ``t_s`` (s, strictly increasing).

        ``levels``: one visible-light level (0..1) per ``street.lamps`` entry at ``t_s``.
        """
        same_levels = levels is self._levels_array
        if not same_levels:  # (the same read-only levels as before were checked then)
            levels = np.asarray(levels, dtype=float)
            if levels.shape != self._starts.shape:
                raise ValueError(
                    f"ZoneTracker.update levels: need one level per street lamp, shape "
                    f"{self._starts.shape}, got {levels.shape}"
                )
        if self._t_s is not None and not t_s > self._t_s:
            raise ValueError(f"ZoneTracker.update t_s: must increase, got {t_s} after {self._t_s}")
        t_s = float(t_s)
        if same_levels:  # the same read-only levels (``LampStates``): listed already
            level_list = self._levels
        else:
            level_list = levels.tolist()
            self._levels_array = None if levels.flags.writeable else levels
        recorded = None if self._recorded is None else self._recorded.step_of(agents)
        if recorded is not None and self._recorded.skip(self._tracks, recorded, self._t_s, t_s, levels, same_levels):
            self._t_s = t_s
            return
        if self._recorded is not None:  # the long path reads the tracks' spans of the steps skipped
            self._recorded.give_spans(self._tracks)
        if agents or self._tracks:  # else nobody in the street, nobody to retire
            if recorded is None:
                spans = ((a.object_id, a.cls, *self._need_span(a)) for a in agents)
            else:  # a replayed step's rows: no agent's snapshot is made
                spans = self._recorded.spans(recorded)
            self._step_all(t_s, spans, level_list)
        if recorded is not None:
            self._recorded.after_long_path(self._tracks, recorded, level_list)
        self._t_s = t_s
        self._levels = level_list

    def _step_all(self, t_s: float, spans, level_list: list[float]) -> None:
        """Every object's step; ``spans``: (object id, class, span low, span high) of each agent."""
        seen: set[int] = set()
        for object_id, cls, lo1, hi1 in spans:
            req = self.required_level.get(cls)
            if req is None:
                continue
            seen.add(object_id)
            track = self._tracks.get(object_id)
            if track is None or self._t_s is None:
                self._tracks[object_id] = track = _Track(cls, lo1, hi1, {})
                self._step_object(track, object_id, req, self._t_s, t_s, level_list)
            elif not self._stays_in_zone(track, req, t_s - self._t_s, level_list, lo1, hi1):
                self._step_object(track, object_id, req, self._t_s, t_s, level_list, lo1, hi1)
            track.lo_m, track.hi_m = lo1, hi1
        for object_id in [i for i in self._tracks if i not in seen]:
            self._retire(object_id, self._t_s)

    def _stays_in_zone(
        self, track: _Track, req: float, dt_s: float, levels1: list[float], lo1_m: float, hi1_m: float
    ) -> bool:
        """``_step_object``'s step, bit for bit, for the usual case, and whether it applied: the
        object's span stays inside the one zone it is visiting, whose lamp's level did not change.
        Then no visit opens or closes and the step is lit or dark throughout (the general path's
        spans are all [0, 1]); the object's steps inside a zone are most steps of a night."""
        if len(track.visits) != 1 or not self._disjoint:
            return False
        ((j, visit),) = track.visits.items()
        level = levels1[j]
        if not (
            self._levels[j] == level
            and self._start_m[j] <= min(track.lo_m, lo1_m)
            and max(track.hi_m, hi1_m) < self._end_m[j]
        ):
            return False
        if level - req + _LEVEL_TOL >= 0.0:  # lit throughout: lit from the step's start
            if visit.t_lit_s is None:
                visit.t_lit_s = self._t_s + 0.0 * dt_s
            visit.dark_s += 0.0 * dt_s
            track.dark_s += 0.0 * dt_s
        else:  # dark throughout
            visit.dark_s += 1.0 * dt_s
            track.dark_s += 1.0 * dt_s
        return True

    def _step_object(
        self,
        track: _Track,
        object_id: int,
        req: float,
        t0_s: float | None,
        t1_s: float,
        levels1: list[float],
        lo1_m: float | None = None,
        hi1_m: float | None = None,
    ) -> None:
        if lo1_m is None:  # first sighting: present at t1 only
            for j in self._zones_touching(track.lo_m, track.hi_m):
                lit = levels1[j] >= req - _LEVEL_TOL
                track.visits[j] = _Visit(t1_s, lit, t1_s if lit else None)
                track.n_visits += 1
            return
        assert t0_s is not None and self._levels is not None
        dt_s = t1_s - t0_s
        lo0, hi0 = track.lo_m, track.hi_m
        candidates = set(self._zones_touching(min(lo0, lo1_m), max(hi0, hi1_m)))
        dark_spans: list[tuple[float, float]] = []
        for j in sorted(candidates | set(track.visits)):
            inside = intersect(
                nonneg_span(hi0 - self._start_m[j], hi1_m - self._start_m[j]),
                pos_span(self._end_m[j] - lo0, self._end_m[j] - lo1_m),
            )
            visit = track.visits.get(j)
            if visit is not None and (inside is None or inside[0] > 0.0):
                self._close(object_id, track, j, t0_s)
                visit = None
            if inside is None:
                continue
            l0, l1 = self._levels[j], levels1[j]
            lit = nonneg_span(l0 - req + _LEVEL_TOL, l1 - req + _LEVEL_TOL)
            if visit is None:
                t_enter = t0_s + inside[0] * dt_s
                level_in = l0 + (l1 - l0) * inside[0]
                on_entry = level_in >= req - _LEVEL_TOL
                visit = track.visits[j] = _Visit(t_enter, on_entry, t_enter if on_entry else None)
                track.n_visits += 1
            lit_inside = intersect(inside, lit)
            if visit.t_lit_s is None and lit_inside is not None:
                visit.t_lit_s = t0_s + lit_inside[0] * dt_s
            lit_len = 0.0 if lit_inside is None else lit_inside[1] - lit_inside[0]
            visit.dark_s += (inside[1] - inside[0] - lit_len) * dt_s
            # lit spans touch an end of [0, 1], so what is left dark is one span
            if inside[1] - inside[0] > lit_len:
                if lit_inside is None:
                    dark_spans.append(inside)
                elif lit_inside[0] > inside[0]:
                    dark_spans.append((inside[0], lit_inside[0]))
                else:
                    dark_spans.append((lit_inside[1], inside[1]))
            if inside[1] < 1.0:
                self._close(object_id, track, j, t0_s + inside[1] * dt_s)
        # an object in two dim zones at once is in the dark once, not twice
        covered, reach = 0.0, -1.0
        for a, b in sorted(dark_spans):
            covered += max(0.0, b - max(a, reach))
            reach = max(reach, b)
        track.dark_s += covered * dt_s

    def _close(
        self, object_id: int, track: _Track, j: int, t_exit_s: float, completed: bool = True
    ) -> None:
        visit = track.visits.pop(j)
        lit = visit.t_lit_s is not None
        lag_s = (visit.t_lit_s if lit else t_exit_s) - visit.t_enter_s
        counts = self._counts[track.cls]
        counts["visits"] += 1
        counts["unlit_crossings"] += int(not lit)
        counts["lit_on_entry"] += int(visit.lit_on_entry)
        self._lag[track.cls].add(max(0.0, lag_s))
        self._done.append(
            {
                "object_id": object_id,
                "cls": track.cls,
                "lamp": self._lamp_ids[j],
                "t_enter_s": visit.t_enter_s,
                "t_exit_s": t_exit_s,
                "lag_s": max(0.0, lag_s),
                "dark_s": visit.dark_s,
                "lit_on_entry": bool(visit.lit_on_entry),
                "lit": lit,
                "completed": completed,
            }
        )

    def _retire(self, object_id: int, t_last_s: float | None, completed: bool = True) -> None:
        track = self._tracks.pop(object_id)
        for j in list(track.visits):
            self._close(object_id, track, j, t_last_s, completed)
        if track.n_visits:
            self._dark[track.cls].add(track.dark_s)

    def finish(self, t_end_s: float) -> None:
        """Close every open visit at the last update time (rows get ``completed=False``).

        ``t_end_s`` must not precede the last update; nothing past the last
        update is known, so nothing past it is counted.
        """
        if self._t_s is not None and t_end_s < self._t_s:
            raise ValueError(
                f"ZoneTracker.finish t_end_s: {t_end_s} precedes the last update {self._t_s}"
            )
        for object_id in list(self._tracks):
            self._retire(object_id, self._t_s, completed=False)

    # ------------------------------------------------------------------ output
    @property
    def has_rows(self) -> bool:
        """Whether ``rows`` has a completed visit to give (asked every step)."""
        return bool(self._done)

    def rows(self, drain: bool = True) -> Iterator[dict[str, Any]]:
        """Completed visits, oldest first (objects.csv rows). ``drain`` drops them as they are read."""
        if not drain:
            yield from list(self._done)
            return
        while self._done:
            yield self._done.popleft()

    def summary(self) -> dict[str, Any]:
        """Per class and overall: objects, visits, unlit crossings, lag and dark-exposure quantiles.

        Covers closed visits and retired objects (call ``finish`` first). Lag is
        per visit; dark exposure is per object (its seconds in under-lit zones
        over the whole run, counting overlapping zones once); only objects that
        entered at least one zone count.
        """
        overall_lag, overall_dark = QuantileSketch(), QuantileSketch()
        by_class: dict[str, dict[str, Any]] = {}
        for cls in self.required_level:
            by_class[cls] = self._describe(self._counts[cls], self._lag[cls], self._dark[cls])
            overall_lag.merge(self._lag[cls])
            overall_dark.merge(self._dark[cls])
        totals = {
            k: sum(self._counts[c][k] for c in self._counts)
            for k in ("visits", "unlit_crossings", "lit_on_entry")
        }
        return {"overall": self._describe(totals, overall_lag, overall_dark), "by_class": by_class}

    @staticmethod
    def _describe(
        counts: dict[str, int], lag: QuantileSketch, dark: QuantileSketch
    ) -> dict[str, Any]:
        return {
            "objects": dark.count,
            "visits": counts["visits"],
            "unlit_crossings": counts["unlit_crossings"],
            "lit_on_entry_fraction": counts["lit_on_entry"] / counts["visits"]
            if counts["visits"]
            else None,
            **lag.describe("lag"),
            **dark.describe("dark_exposure"),
            "dark_exposure_total_s": dark.total,
        }
