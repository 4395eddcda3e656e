"""lamps.csv: the level and power of every lamp at every whole simulated second."""

from __future__ import annotations

import csv

from citysim.control.lamps import Lamp
from citysim.metrics.collector import Collector

LAMPS_CSV_HEADER = ["controller", "t_s", "lamp", "level", "power_w"]


class LampLog(Collector):
    """Writes one row per lamp each second (before that second's events); no writer: nothing."""

    def __init__(self, label: str, lamps: list[Lamp], writer: csv.writer | None):
        self.label, self.lamps, self.writer = label, lamps, writer

    def on_second(self, t_s: float) -> None:
        if self.writer is None:
            return
        for lamp in self.lamps:
            self.writer.writerow(
                [self.label, f"{t_s:.3f}", lamp.index, f"{lamp.level_at(t_s):.4f}", f"{lamp.power_w(t_s):.3f}"]
            )
