"""Energy of a run: the lamps' draw against always-on lighting of the same night, per hour.

``energy_summary`` compares a run's lamps (all advanced to one time) with the always-on
baseline; ``EnergyCollector`` closes an hourly bin at each whole hour of the run and gives the
run's energy figures at its end.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from citysim.config.street import LuminaireSpec
from citysim.control.lamps import Lamp, always_on_energy_j, check_number
from citysim.metrics.collector import Collector

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


class EnergyCollector(Collector):
    """Hourly energy bins (kWh per hour of the run) and the run's energy figures.

    An hour's bin closes at each whole hour of simulated time; the last, possibly partial,
    bin at the end of the run. Savings are against ``len(lamps)`` always-on luminaires.
    """

    def __init__(self, lamps: Sequence[Lamp], luminaire: LuminaireSpec):
        self.lamps = list(lamps)
        self.luminaire = luminaire
        self.hourly_kwh: list[float] = []
        self._last_energy_j = 0.0

    def _close_bin(self, t_s: float) -> None:
        for lamp in self.lamps:
            lamp.advance(t_s)
        energy_j = sum(lamp.energy_j for lamp in self.lamps)
        self.hourly_kwh.append((energy_j - self._last_energy_j) / J_PER_KWH)
        self._last_energy_j = energy_j

    def on_second(self, t_s: float) -> None:
        if t_s > 0 and math.isclose(t_s % 3600.0, 0.0, abs_tol=1e-6):
            self._close_bin(t_s)

    def finish(self, t_end_s: float) -> dict[str, Any]:
        self._close_bin(t_end_s)
        if all(lamp.spec.rated_power_w == self.luminaire.rated_power_w for lamp in self.lamps):
            always_on_j = always_on_energy_j(len(self.lamps), self.luminaire, t_end_s)
        else:  # surveyed lamps of their own power: each lamp's always-on
            always_on_j = sum(always_on_energy_j(1, lamp.spec, t_end_s) for lamp in self.lamps)
        energy = energy_summary(self.lamps, always_on_j)
        split = ("luminaire_energy_kwh", "standby_energy_kwh", "sensing_energy_kwh")
        return {
            "energy_kwh": energy["energy_kwh"],
            "savings_vs_always_on": energy["savings_vs_always_on"],
            "switches": energy["switches"],
            "on_time_s": energy["on_time_s"],
            "energy_per_hour_kwh": self.hourly_kwh,
            "energy_split_kwh": {k.removesuffix("_energy_kwh"): energy[k] for k in split},
            # where it was drawn: the report sets each lamp against the oracle's (``report.oracle_gap``)
            "energy_per_lamp_kwh": [lamp.energy_j / J_PER_KWH for lamp in self.lamps],
        }
