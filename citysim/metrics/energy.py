"""Run metrics: energy against always-on, illumination lag and dark exposure, detection confusion.

The one import point for the simulator's summary. Everything streams: nothing
keeps per-step history, memory stays flat however long the night.

* ``energy_summary`` (here): energy of the lamps of one run vs the always-on
  baseline of the same run.
* ``ZoneTracker`` (``metrics_zones``): per object and lamp zone, entry time,
  lag to the required light and dark seconds; p50/p95/max per class.
* ``DetectionConfusion`` (``metrics_confusion``): binary and 5-class
  confusion, false positives per frame and region, per-object miss rate.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from citysim.control.lamps import Lamp, check_number
from citysim.metrics.confusion import (
    CONFUSION_CLASSES,
    DetectionConfusion,
    greedy_match,
    iou_matrix,
)
from citysim.metrics.quantiles import QuantileSketch
from citysim.metrics.zones import DEFAULT_LOOKAHEAD_S, ZoneTracker

__all__ = [
    "CONFUSION_CLASSES",
    "DEFAULT_LOOKAHEAD_S",
    "DetectionConfusion",
    "QuantileSketch",
    "ZoneTracker",
    "energy_summary",
    "greedy_match",
    "iou_matrix",
]

J_PER_KWH = 3.6e6


def energy_summary(lamps: Sequence[Lamp], always_on_energy_j: float) -> dict[str, Any]:
    """Energy of a run (all lamps advanced to the same time) against the always-on baseline.

    ``savings_vs_always_on`` is a fraction (0.6: 60 % less energy than always-on
    lamps on the same night); ``switches`` and ``on_time_s`` are summed over lamps.
    """
    if not lamps:
        raise ValueError("energy_summary lamps: need at least one lamp")
    clocks = {lamp.t_s for lamp in lamps}
    if len(clocks) != 1:
        raise ValueError(
            f"energy_summary lamps: advance every lamp to the same t_s first, got {sorted(clocks)}"
        )
    check_number("energy_summary", "always_on_energy_j", always_on_energy_j, 0.0)
    if always_on_energy_j == 0.0:
        raise ValueError("energy_summary always_on_energy_j: must be > 0 to compare against")
    energy_j = sum(lamp.energy_j for lamp in lamps)
    return {
        "energy_j": energy_j,
        "energy_kwh": energy_j / J_PER_KWH,
        "always_on_energy_kwh": always_on_energy_j / J_PER_KWH,
        "savings_vs_always_on": 1.0 - energy_j / always_on_energy_j,
        "luminaire_energy_kwh": sum(lamp.luminaire_energy_j for lamp in lamps) / J_PER_KWH,
        "standby_energy_kwh": sum(lamp.standby_energy_j for lamp in lamps) / J_PER_KWH,
        "sensing_energy_kwh": sum(lamp.sensing_energy_j for lamp in lamps) / J_PER_KWH,
        "switches": sum(lamp.switches for lamp in lamps),
        "on_time_s": sum(lamp.on_time_s for lamp in lamps),
    }
