"""Luminaire power model: light level ramps and exact energy integration.

A lamp's light is a level in 0..1 (0 off, ``dim_level`` idle, 1 full) that ramps linearly to
the controller's target; power (W) is ``rated_power_w * level`` plus standby and sensing power;
energy (J) is integrated in closed form. The spec is the scenario's ``lamps.luminaire``
(``citysim.config.street.LuminaireSpec``); the controller calls ``set_target(t, dim_level)``
once its hold has expired: a lamp never drops its level by itself.

Time: every method takes simulation seconds ``t_s``; a lamp's clock only moves
forward (``advance``/``set_target`` with an earlier time raise ``ValueError``).

Design: docs/design/modules.md (Luminaire power)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from numbers import Real
from typing import ClassVar

import numpy as np

from citysim.config.street import LuminaireSpec


def check_number(owner: str, name: str, value: object, low: float, high: float = math.inf) -> None:
    """Raise ValueError naming ``owner.name`` unless ``low <= value <= high`` and finite.

    Shared by the energy, network and metrics modules so their errors read alike.
    """
    if isinstance(value, bool) or not isinstance(value, Real) or not math.isfinite(value):
        raise ValueError(f"{owner}.{name} must be a finite number, got {value!r}")
    if not low <= value <= high:
        valid = f">= {low}" if high == math.inf else f"in [{low}, {high}]"
        raise ValueError(f"{owner}.{name} must be {valid}, got {value!r}")


def always_on_energy_j(n_lamps: int, spec: LuminaireSpec, duration_s: float) -> float:
    """Energy (J) of ``n_lamps`` plain lamps at full light for ``duration_s``: the savings baseline."""
    if isinstance(n_lamps, bool) or not isinstance(n_lamps, int) or n_lamps < 0:
        raise ValueError(f"n_lamps must be an int >= 0, got {n_lamps!r}")
    check_number("always_on_energy_j", "duration_s", duration_s, 0.0)
    return n_lamps * spec.rated_power_w * duration_s


def _ramp(
    level: float, target: float, spec: LuminaireSpec, dt_s: float
) -> tuple[float, float, float]:
    """Follow one ramp toward ``target`` for ``dt_s`` seconds.

    Returns (level at the end, integral of level over the span in level*s,
    time spent above ``spec.dim_level`` in s). The level moves linearly until
    it reaches the target, then stays there.
    """
    going_up = target >= level
    full_swing_s = spec.ramp_up_s if going_up else spec.fade_s
    reach_s = abs(target - level) * full_swing_s  # 0 for an instant step
    ramp_s = min(dt_s, reach_s)
    if dt_s >= reach_s:
        end_of_ramp = target  # exact, no rounding drift at the end of a ramp
    else:
        slope_per_s = (1.0 if going_up else -1.0) / full_swing_s
        end_of_ramp = level + slope_per_s * ramp_s
    flat_s = dt_s - ramp_s
    integral = 0.5 * (level + end_of_ramp) * ramp_s + target * flat_s

    dim = spec.dim_level
    if level > dim and end_of_ramp > dim:
        above_s = ramp_s
    elif level <= dim and end_of_ramp <= dim:
        above_s = 0.0
    else:  # the ramp crosses the dim level once, at a known fraction of its length
        cross_s = ramp_s * (dim - level) / (end_of_ramp - level)
        above_s = ramp_s - cross_s if going_up else cross_s
    if target > dim:
        above_s += flat_s
    return end_of_ramp, integral, above_s


class Lamp:
    """One luminaire: its level over time, its switching, and the energy it draws.

    ``senses``: the lamp carries a camera/board/emitter and pays
    ``sensing_power_w``. ``standby``: the lamp has a controllable (DALI) driver
    and radio that draw ``standby_power_w`` at every level; ``None`` means "same
    as ``senses``". A plain always-on or photocell lamp has no separate standby
    draw (its driver losses are inside ``rated_power_w``), so the always-on
    baseline is exactly lamps x rated power x duration.

    The lamp keeps only an anchor (time, level, target) and accumulators, so
    memory and per-call work are O(1) however long the run.
    """

    #: Target changes of every lamp of the process so far: a ``LampStates`` whose count is unchanged
    #: knows no lamp has started a ramp since it last looked.
    target_changes: ClassVar[int] = 0

    def __init__(
        self,
        index: int,
        spec: LuminaireSpec,
        senses: bool,
        initial_level: float,
        *,
        standby: bool | None = None,
        t0_s: float = 0.0,
    ) -> None:
        if not isinstance(spec, LuminaireSpec):
            raise ValueError(f"Lamp.spec must be a LuminaireSpec, got {type(spec).__name__}")
        check_number("Lamp", "initial_level", initial_level, 0.0, 1.0)
        check_number("Lamp", "t0_s", t0_s, -math.inf)
        self.index = index
        self.spec = spec
        self.senses = bool(senses)
        self.standby = self.senses if standby is None else bool(standby)
        self.switches = 0
        self._anchor_t_s = float(t0_s)
        self._anchor_level = float(initial_level)
        self._target = float(initial_level)
        self._clock_t_s = float(t0_s)
        self._t0_s = float(t0_s)
        self._closed_level_s = 0.0  # integral of level over closed segments, level*s
        self._closed_on_s = 0.0
        self._reach_s = 0.0  # seconds from the anchor until the level reaches the target

    # ------------------------------------------------------------------ control
    @property
    def t_s(self) -> float:
        """Time (s) up to which energy and on-time are integrated."""
        return self._clock_t_s

    @property
    def target_level(self) -> float:
        """The level the lamp is heading to (0..1), set by the last ``set_target``."""
        return self._target

    def is_settled(self, t_s: float) -> bool:
        """True when ``level_at(t_s)`` is the target exactly (the test it makes), and so at any later time
        until the target changes."""
        return t_s - self._anchor_t_s >= self._reach_s

    def is_ramping(self, t_s: float) -> bool:
        """True while the level at ``t_s`` is still moving toward the target."""
        return t_s < self._anchor_t_s + self._reach_s

    def _is_on(self, level: float) -> bool:
        return level > self.spec.dim_level

    def set_target(self, t_s: float, level: float) -> None:
        """From ``t_s`` on, ramp toward ``level`` (0..1). Integrates up to ``t_s`` first."""
        check_number("Lamp.set_target", "level", level, 0.0, 1.0)
        self.advance(t_s)
        if level == self._target:
            return
        now_level, integral, on_s = _ramp(
            self._anchor_level, self._target, self.spec, t_s - self._anchor_t_s
        )
        self._closed_level_s += integral
        self._closed_on_s += on_s
        if self._is_on(level) != self._is_on(self._target):
            self.switches += 1
        self._anchor_t_s = float(t_s)
        self._anchor_level = now_level
        self._target = float(level)
        Lamp.target_changes += 1
        self._reach_s = abs(self._target - now_level) * (self.spec.ramp_up_s if self._target >= now_level
                                                          else self.spec.fade_s)  # fmt: skip

    def advance(self, t_s: float) -> None:
        """Move the lamp's clock to ``t_s``: energy_j and on_time_s now cover [t0, t_s]."""
        check_number("Lamp.advance", "t_s", t_s, -math.inf)
        if t_s < self._clock_t_s:
            raise ValueError(
                f"Lamp {self.index}: t_s={t_s} precedes the lamp's clock {self._clock_t_s}; "
                "time only moves forward"
            )
        self._clock_t_s = float(t_s)

    # ------------------------------------------------------------------ readings
    def level_at(self, t_s: float) -> float:
        """Visible light level (0..1) at ``t_s`` (any time since the last target change)."""
        if t_s < self._anchor_t_s:
            raise ValueError(
                f"Lamp {self.index}: level_at(t_s={t_s}) precedes the last target change at "
                f"{self._anchor_t_s}; past levels are not stored"
            )
        dt_s = t_s - self._anchor_t_s
        if dt_s >= self._reach_s:  # the test _ramp makes: past the ramp the level is the target exactly
            return self._target
        return _ramp(self._anchor_level, self._target, self.spec, dt_s)[0]

    def reached_at_s(self) -> float:
        """Time (s) at which the level reaches (or reached) the current target."""
        return self._anchor_t_s + self._reach_s

    def power_w(self, t_s: float) -> float:
        """Instantaneous electrical power (W) at ``t_s``."""
        return self.spec.rated_power_w * self.level_at(t_s) + self._fixed_power_w()

    def _fixed_power_w(self) -> float:
        return (self.spec.standby_power_w if self.standby else 0.0) + (
            self.spec.sensing_power_w if self.senses else 0.0
        )

    def _open_segment(self) -> tuple[float, float]:
        _, integral, on_s = _ramp(
            self._anchor_level, self._target, self.spec, self._clock_t_s - self._anchor_t_s
        )
        return integral, on_s

    @property
    def light_integral_s(self) -> float:
        """Integral of the level over [t0, t_s] (full-light-equivalent seconds)."""
        return self._closed_level_s + self._open_segment()[0]

    @property
    def on_time_s(self) -> float:
        """Seconds in [t0, t_s] with the level above ``dim_level``."""
        return self._closed_on_s + self._open_segment()[1]

    @property
    def luminaire_energy_j(self) -> float:
        return self.spec.rated_power_w * self.light_integral_s

    @property
    def standby_energy_j(self) -> float:
        return (self.spec.standby_power_w if self.standby else 0.0) * (self._clock_t_s - self._t0_s)

    @property
    def sensing_energy_j(self) -> float:
        return (self.spec.sensing_power_w if self.senses else 0.0) * (self._clock_t_s - self._t0_s)

    @property
    def energy_j(self) -> float:
        """Total electrical energy (J) over [t0, t_s]: luminaire + standby + sensing."""
        return self.luminaire_energy_j + self.standby_energy_j + self.sensing_energy_j

    def __repr__(self) -> str:
        return (
            f"Lamp(index={self.index}, t_s={self._clock_t_s}, target={self._target}, "
            f"energy_j={self.energy_j:.3f}, switches={self.switches})"
        )


def levels_at(lamps: Sequence[Lamp], t_s: float) -> np.ndarray:
    """Every lamp's visible-light level (0..1) at ``t_s``, in lamp order."""
    return np.array([lamp.level_at(t_s) for lamp in lamps])


class LampStates:
    """Every lamp's level and ramping, shared by the consumers of one run (the loop's collectors,
    the cameras, the controllers' light watches) instead of asked of each lamp by each of them.

    A level moves only during a ramp, and a ramp starts only when a target changes
    (``Lamp.target_changes``), so the levels read once every lamp has settled hold, bit for bit,
    until the next change: most physics steps of a night reuse them. The array returned is shared
    and read-only.
    """

    def __init__(self, lamps: Sequence[Lamp]):
        self.lamps = list(lamps)
        self._levels = np.zeros(0)
        self._levels_t_s = math.nan
        self._levels_changes = -1
        self._levels_settled = False
        self._reached_changes = -1
        self._reached_at_s: list[float] = []
        self._last_reached_s = math.inf
        self._none_ramping = (False,) * len(self.lamps)

    def levels_at(self, t_s: float) -> np.ndarray:
        """``levels_at(lamps, t_s)``, computed again only when a target changed or a lamp was ramping."""
        if self._levels_changes == Lamp.target_changes and (
            t_s == self._levels_t_s or (self._levels_settled and t_s >= self._levels_t_s)
        ):
            return self._levels
        levels = levels_at(self.lamps, t_s)
        levels.flags.writeable = False  # shared by every consumer of this step
        self._levels, self._levels_t_s, self._levels_changes = levels, t_s, Lamp.target_changes
        self._levels_settled = all(lamp.is_settled(t_s) for lamp in self.lamps)
        return levels

    def _update_reached(self) -> None:
        if self._reached_changes != Lamp.target_changes:
            self._reached_at_s = [lamp.reached_at_s() for lamp in self.lamps]
            self._last_reached_s = max(self._reached_at_s, default=-math.inf)
            self._reached_changes = Lamp.target_changes

    def any_ramping(self, t_s: float) -> bool:
        """Whether any lamp ``is_ramping(t_s)`` (asked per judged camera frame: no call while no target changed)."""
        if self._reached_changes != Lamp.target_changes:
            self._update_reached()
        return t_s < self._last_reached_s

    def ramping(self, t_s: float) -> Sequence[bool]:
        """``is_ramping(t_s)`` of every lamp, in lamp order."""
        self._update_reached()
        if t_s >= self._last_reached_s:
            return self._none_ramping
        return [t_s < reached_s for reached_s in self._reached_at_s]
