"""Zone crossings: objects.csv and the lag and darkness figures of a run.

``CrossingsCollector`` feeds a ``ZoneTracker`` every physics step, streams each finished
object-and-zone visit to objects.csv, and gives the run's lag quantiles, dark exposure,
unlit crossings and per-class figures at the end.
"""

from __future__ import annotations

import csv
from collections.abc import Sequence
from typing import Any

import numpy as np

from citysim.metrics.collector import Collector
from citysim.metrics.intervals import lit_share_interval
from citysim.metrics.zones import ZoneTracker
from citysim.world.agents import AgentState
from citysim.world.street import Street

OBJECTS_CSV_HEADER = [
    "controller", "object_id", "cls", "lamp", "t_enter_s", "t_exit_s", "lag_s", "dark_s", "lit_on_entry",
]  # fmt: skip


class CrossingsCollector(Collector):
    """Per object and lamp zone: entry, exit, lag to the required light, dark seconds."""

    def __init__(self, street: Street, label: str, writer: csv.writer | None, kinds: Sequence[str] | None = None):
        """``kinds``: the road-user kinds that need light in a zone (default: the detector's targets)."""
        self.zones = ZoneTracker(street, None if kinds is None else dict.fromkeys(kinds, 1.0))
        self.label, self.writer = label, writer
        #: per road user, [zone entries, entries lit on entry]: what the rate's interval resamples
        self.tallies: dict[int, list[int]] = {}

    def _write_rows(self) -> None:
        if not self.zones.has_rows:
            return
        for row in self.zones.rows(drain=True):
            tally = self.tallies.setdefault(row["object_id"], [0, 0])
            tally[0] += 1
            tally[1] += bool(row["lit_on_entry"])
            if self.writer is None:
                continue
            self.writer.writerow([
                self.label, row["object_id"], row["cls"], row["lamp"], f"{row['t_enter_s']:.3f}",
                f"{row['t_exit_s']:.3f}", f"{row['lag_s']:.3f}", f"{row['dark_s']:.3f}",
                int(bool(row["lit_on_entry"])),
            ])  # fmt: skip

    def on_step(self, t_s: float, agents: Sequence[AgentState], levels: np.ndarray) -> None:
        self.zones.update(t_s, agents, levels)
        self._write_rows()

    def finish(self, t_end_s: float) -> dict[str, Any]:
        self.zones.finish(t_end_s)
        self._write_rows()
        summary = self.zones.summary()
        overall = summary["overall"]
        per_class_keys = ("objects", "lag_p50_s", "lag_p95_s", "lag_max_s")
        entries = overall["visits"]
        return {
            # the planner's darkness axis: share of zone entries whose lamp was already at the
            # level the object needs (None without entries)
            "lit_on_entry_rate": overall["lit_on_entry_fraction"],
            # how far that rate could be off from this night's road users alone (``metrics.intervals``)
            "lit_on_entry_interval_95": lit_share_interval([(1.0, list(self.tallies.values()))]),
            "zone_entries": entries,
            "dark_s_per_100_entries": 100.0 * overall["dark_exposure_total_s"] / entries if entries else None,
            "lag_p50_s": overall["lag_p50_s"],
            "lag_p95_s": overall["lag_p95_s"],
            "lag_max_s": overall["lag_max_s"],
            "dark_exposure_s": overall["dark_exposure_total_s"],
            "unlit_crossings": overall["unlit_crossings"],
            "objects": overall["objects"],
            "per_class": {
                cls: {
                    **{k: s[k] for k in per_class_keys},
                    "dark_exposure_s": s["dark_exposure_total_s"],
                    "unlit_crossings": s["unlit_crossings"],
                }
                for cls, s in summary["by_class"].items()
            },
        }
