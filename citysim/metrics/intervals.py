"""How far a lit-on-entry rate could be off from the road users it was measured on: a 95 % interval.

Zone entries are not independent trials: a car the cameras miss is often dark in two or three
zones running. So the rate's spread is found by resampling *road users* (each with all its
entries) with replacement, and the interval is Wilson's score interval with n the number of
independent entries that spread amounts to. Where every resample gives the same rate (nobody
dark, or nobody lit) the spread says nothing, and n is the number of road users: the cautious
reading, each road user one trial. Used for a run's figure (``CrossingsCollector``) and a year's
(``citysim.year.annual``, whose rate is a weighted sum over its traffic-level runs).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

#: Resamples behind the interval, and the seed they are drawn with (same tallies, same interval).
RESAMPLES, SEED = 2000, 20240611
#: The normal quantile of a two-sided 95 % interval.
Z_95 = 1.959964


def wilson_interval(rate: float, n: float, z: float = Z_95) -> tuple[float, float]:
    """Wilson's score interval of a share ``rate`` out of ``n`` trials (95 % by default)."""
    z2n = z * z / n
    centre = (rate + z2n / 2.0) / (1.0 + z2n)
    half = z * math.sqrt(rate * (1.0 - rate) / n + z2n / (4.0 * n)) / (1.0 + z2n)
    # at a share of 0 or 1 the bound on that side is exactly it (the float sum can miss it by an ulp)
    return (0.0 if rate <= 0.0 else max(0.0, centre - half)), (1.0 if rate >= 1.0 else min(1.0, centre + half))


def lit_share_interval(samples: Sequence[tuple[float, Sequence[Sequence[int]]]]) -> tuple[float, float] | None:
    """A 95 % interval of the share sum(w * lit) / sum(w * entries) over ``samples``, each a weight
    ``w`` and its road users' (zone entries, entries lit on entry); None without entries."""
    rng = np.random.default_rng(SEED)
    entries, lit = np.zeros(RESAMPLES), np.zeros(RESAMPLES)
    total_entries = total_lit = 0.0
    road_users = 0
    for weight, objects in samples:
        if not len(objects):
            continue
        counts = np.asarray(objects, dtype=float)  # (road users, 2): entries, lit entries
        total_entries += weight * counts[:, 0].sum()
        total_lit += weight * counts[:, 1].sum()
        road_users += len(counts)
        picks = rng.integers(len(counts), size=(RESAMPLES, len(counts)))
        entries += weight * counts[picks, 0].sum(axis=1)
        lit += weight * counts[picks, 1].sum(axis=1)
    if total_entries <= 0:
        return None
    rate = float(total_lit / total_entries)
    spread = float(np.var(lit[entries > 0] / entries[entries > 0]))
    n = rate * (1.0 - rate) / spread if spread > 0 and 0 < rate < 1 else float(road_users)
    return wilson_interval(rate, n)
