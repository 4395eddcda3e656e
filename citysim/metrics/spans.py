"""Where a quantity that moves linearly over a step (tau from 0 to 1) is >= 0 or > 0: the zone
tracker's entry, exit and lit times inside a physics step (``citysim.metrics.zones``)."""

from __future__ import annotations


def nonneg_span(a0: float, a1: float) -> tuple[float, float] | None:
    """Where the line from a0 (tau=0) to a1 (tau=1) is >= 0, as a tau interval in [0, 1]."""
    if a0 >= 0.0 and a1 >= 0.0:
        return 0.0, 1.0
    if a0 < 0.0 and a1 < 0.0:
        return None
    root = a0 / (a0 - a1)
    return (0.0, root) if a0 >= 0.0 else (root, 1.0)


def pos_span(a0: float, a1: float) -> tuple[float, float] | None:
    """Where the line from a0 to a1 is > 0 (zones are half-open at their end)."""
    if a0 > 0.0 and a1 > 0.0:
        return 0.0, 1.0
    if a0 <= 0.0 and a1 <= 0.0:
        return None
    root = a0 / (a0 - a1)
    return (0.0, root) if a0 > 0.0 else (root, 1.0)


def intersect(
    a: tuple[float, float] | None, b: tuple[float, float] | None
) -> tuple[float, float] | None:
    if a is None or b is None:
        return None
    lo, hi = max(a[0], b[0]), min(a[1], b[1])
    return (lo, hi) if lo <= hi else None
