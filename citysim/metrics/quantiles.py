"""Streaming quantiles whose memory depends on the value range, never on the count.

The run metrics report p50/p95/max of lags and dark exposures over a whole
night without keeping the values: a log-binned histogram (the DDSketch idea)
answers any quantile within a fixed relative error.
"""

from __future__ import annotations

import math


class QuantileSketch:
    """Streaming quantiles of non-negative values with bounded relative error.

    Values fall into geometric bins of ratio ``(1 + a) / (1 - a)`` (a = 0.005);
    zeros (common: a lamp already lit on entry) are counted exactly. Quantiles
    use the lower-rank convention of ``numpy.quantile(method="lower")``.
    """

    def __init__(self, relative_accuracy: float = 0.005) -> None:
        self._gamma_log = math.log((1 + relative_accuracy) / (1 - relative_accuracy))
        self._bins: dict[int, int] = {}
        self.zeros = 0
        self.count = 0
        self.total = 0.0
        self.max = 0.0

    def add(self, value: float) -> None:
        if not value >= 0.0:
            raise ValueError(f"QuantileSketch.add: value must be >= 0, got {value!r}")
        self.count += 1
        self.total += value
        self.max = max(self.max, value)
        if value <= 1e-12:
            self.zeros += 1
        else:
            key = math.ceil(math.log(value) / self._gamma_log)
            self._bins[key] = self._bins.get(key, 0) + 1

    def quantile(self, q: float) -> float | None:
        if self.count == 0:
            return None
        rank = int(q * (self.count - 1))
        if rank < self.zeros:
            return 0.0
        seen = self.zeros
        for key in sorted(self._bins):
            seen += self._bins[key]
            if seen > rank:
                g = math.exp(self._gamma_log)
                return min(self.max, 2.0 * g**key / (g + 1.0))
        return self.max

    def describe(self, prefix: str) -> dict[str, float | None]:
        return {
            f"{prefix}_p50_s": self.quantile(0.5),
            f"{prefix}_p95_s": self.quantile(0.95),
            f"{prefix}_max_s": self.max if self.count else None,
            f"{prefix}_mean_s": self.total / self.count if self.count else None,
        }

    def merge(self, other: QuantileSketch) -> None:
        """Fold ``other``'s values into this sketch (same relative accuracy)."""
        if other._gamma_log != self._gamma_log:
            raise ValueError("QuantileSketch.merge: sketches need the same relative_accuracy")
        self.count += other.count
        self.zeros += other.zeros
        self.total += other.total
        self.max = max(self.max, other.max)
        for key, n in other._bins.items():
            self._bins[key] = self._bins.get(key, 0) + n
