"""Scenario vocabulary for motion: speed limits, speed distributions, motion parameters, drawing knobs.

Plain frozen records that the kinds (``citysim.config.kinds``) and the traffic schema
(``citysim.config.traffic``) are written in and the world (``citysim.world``) reads; no
behaviour beyond drawing a speed. Units are in the names (m/s, km/h, m, s, rad).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

KMH_PER_MPS = 3.6
#: No simulated agent is ever faster than this (the paper's street scenes).
MAX_SPEED_KMH = 60.0
MAX_SPEED_MPS = MAX_SPEED_KMH / KMH_PER_MPS


@dataclass(frozen=True)
class SpeedDistribution:
    """Desired (free-flow) speed of one agent, m/s.

    Uniform on [min_mps, max_mps], or, when ``mean_mps`` and ``std_mps`` are
    given, normal(mean, std) clipped to [min_mps, max_mps].
    """

    min_mps: float
    max_mps: float
    mean_mps: float | None = None
    std_mps: float | None = None

    def __post_init__(self) -> None:
        if not 0.0 < self.min_mps <= self.max_mps <= MAX_SPEED_MPS + 1e-9:
            raise ValueError(
                f"speed range must satisfy 0 < min <= max <= {MAX_SPEED_MPS:.2f} m/s "
                f"({MAX_SPEED_KMH:g} km/h), got min={self.min_mps} max={self.max_mps}"
            )

    @classmethod
    def kmh(cls, min_kmh: float, max_kmh: float) -> SpeedDistribution:
        """Uniform between two speeds given in km/h."""
        return cls(min_kmh / KMH_PER_MPS, max_kmh / KMH_PER_MPS)

    def draw(self, rng: np.random.Generator) -> float:
        if self.mean_mps is not None and self.std_mps is not None:
            return float(
                np.clip(rng.normal(self.mean_mps, self.std_mps), self.min_mps, self.max_mps)
            )
        return float(rng.uniform(self.min_mps, self.max_mps))


@dataclass(frozen=True, kw_only=True)
class MotionParams:
    """How an agent of one kind moves (the world's behaviour model reads these).

    Longitudinal control is the Intelligent Driver Model (Treiber et al. 2000):
    ``accel_mps2`` (a), ``comfort_decel_mps2`` (b), ``headway_s`` (T),
    ``min_gap_m`` (s0); ``max_decel_mps2`` bounds braking. Lateral control picks
    an offset within the path's band: ``lateral_speed_mps`` bounds sidestepping,
    ``lateral_margin_m`` is the clearance kept to others when passing, and
    ``horizon_s`` the look-ahead time used to score free space. ``yaw_rate_rps``
    bounds how fast the body turns toward its direction of motion; ``max_tilt_rad``
    how far it turns away from its path's direction while swerving (walkers and
    animals sidestep facing forward: 0).
    """

    accel_mps2: float
    comfort_decel_mps2: float
    max_decel_mps2: float
    headway_s: float
    min_gap_m: float
    lookahead_m: float
    lateral_speed_mps: float
    lateral_margin_m: float
    horizon_s: float
    yaw_rate_rps: float
    max_tilt_rad: float = 0.0


@dataclass(frozen=True)
class DrawOptions:
    """Per-scenario knobs for drawing one agent (from ``config`` traffic specs)."""

    speed: SpeedDistribution | None = None  # None: the kind's default
    running_fraction: float = 0.0  # walkers: share that run
    running_speed: SpeedDistribution | None = None  # None: the kind's default
    light_fraction: float = 0.0  # flashlight (walkers) or headlight (riders, vehicles)
    night: bool = True  # lights are only switched on at night
    group_size: tuple[int, int] = (2, 4)
    max_group_width_m: float = 3.0  # the path's room: wider groups walk in two rows
