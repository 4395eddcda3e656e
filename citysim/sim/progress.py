"""The progress bar of simulated time: what its unit is, and no time-left guess before warm-up.

A run's first seconds of wall time go to starting worker processes, importing and compiling; the
simulated seconds done by then say nothing about the speed to come (a first estimate of 68 hours
was seen). So the bar shows "time left after warm-up" until ``WARMUP_S`` of wall time have passed
and some simulated time is done, then its estimate; the description says what is counted.
"""

from __future__ import annotations

from tqdm import tqdm

#: Wall seconds before the bar estimates the time left, s.
WARMUP_S = 10.0
#: The counted unit, as the bar's description explains it.
UNIT = "simulated s"
_WARMING = "{l_bar}{bar}| {n:.0f}/{total:.0f} [{elapsed}, time left after warm-up]"
_RUNNING = "{l_bar}{bar}| {n:.0f}/{total:.0f} [{elapsed}<{remaining}, {rate_noinv_fmt}]"


class SimulatedTimeBar(tqdm):
    """A tqdm bar counting simulated seconds; no estimate of the time left before ``warmup_s``.

    Parameters
    ----------
    total_s : float
        Simulated seconds to do in all (summed over the runs counted), s.
    desc : str
        What runs; the bar adds what its numbers count.
    warmup_s : float
        Wall seconds before the time left is estimated, s.
    **kwargs
        Passed to ``tqdm`` (e.g. ``disable``).
    """

    def __init__(self, total_s: float, desc: str, warmup_s: float = WARMUP_S, **kwargs) -> None:
        self.warmup_s = warmup_s
        super().__init__(total=total_s, desc=f"{desc} ({UNIT} done/total)", unit=f" {UNIT}", bar_format=_RUNNING,
                         **kwargs)  # fmt: skip

    @property
    def format_dict(self) -> dict:
        fmt = super().format_dict
        warming = fmt["elapsed"] < getattr(self, "warmup_s", 0.0) or fmt["n"] <= 0
        return {**fmt, "bar_format": _WARMING if warming else _RUNNING}
