"""Checks of the tracks' limits dataclasses (``PlausibilityLimits``, ``MotionLimits``): one error
naming the class, the field and what would be valid."""

from __future__ import annotations


def require_positive(limits: object, names: tuple[str, ...]) -> None:
    """Every field of ``names`` is > 0."""
    for name in names:
        value = getattr(limits, name)
        if not value > 0:
            raise ValueError(f"{type(limits).__name__}.{name}: must be > 0, got {value!r}")


def require_int_at_least(limits: object, names: tuple[str, ...], low: int) -> None:
    """Every field of ``names`` is an integer (not a bool) >= ``low``."""
    for name in names:
        value = getattr(limits, name)
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise ValueError(f"{type(limits).__name__}.{name}: must be an integer >= {low}, got {value!r}")
