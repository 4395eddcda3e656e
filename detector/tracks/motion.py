"""A track that moves like a road vehicle is a target, whatever its frames look like.

``steady_speed_mps``: a straight-line fit of the track's ground path at a steady 5-20 m/s, not
towards the camera, at a steady size within a vehicle's bounds; such a track overrides the
reasons in ``OVERRIDDEN_REASONS`` (and ``VEHICLE_ONLY_REASONS`` above ``vehicle_above_mps``).
``motion_class`` gives its class. Speeds m/s on the ground, positions and sizes m, times s.

Design: docs/design/tracks.md (A track that moves like a road vehicle)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from detector.tracks.checks import require_int_at_least, require_positive
from detector.tracks.ground import line_of_sight_cos
from detector.tracks.track import Track, median

#: The rejections a steady vehicle-like motion outweighs (see the module docstring).
OVERRIDDEN_REASONS = frozenset(
    {"size outside Table 1", "classified noise", "erratic", "jumping", "too wide for its heading"}
)
#: Overridden only for a track at a vehicle's speed (above ``vehicle_above_mps``; module docstring).
VEHICLE_ONLY_REASONS = frozenset({"too wide for its heading"})


@dataclass(frozen=True)
class MotionLimits:
    """The motion a vehicle track keeps (see the module docstring); ``enabled`` False: never used."""

    enabled: bool = True
    window_s: float = 1.0
    min_age_s: float = 0.5
    min_points: int = 6
    min_speed_mps: float = 5.0  # faster than joggers (2.5-4 m/s) and walkers' flashlight spots
    max_speed_mps: float = 20.0
    max_residual_share: float = 0.08  # of the distance from the pole
    max_size_variation: float = 0.2
    #: Table 1's smallest vehicle (1.4 m wide and tall) less plausibility's 35 % size tolerance:
    #: a car or its beam is no smaller; pieces of road users and low specks are
    min_width_m: float = 0.9
    min_height_m: float = 0.9
    max_width_m: float = 12.0
    max_height_m: float = 5.0
    vehicle_above_mps: float = 8.5
    #: a fitted velocity within this of straight at the camera is a car coming: its headlamps face
    #: the camera, which sees them; its spot on the road ahead is no evidence of a second road user
    approach_deg: float = 60.0

    def __post_init__(self) -> None:
        require_int_at_least(self, ("min_points",), 3)
        require_positive(self, ("window_s", "min_age_s", "min_speed_mps", "max_speed_mps", "max_residual_share",
                                "max_size_variation", "min_width_m", "min_height_m", "max_width_m", "max_height_m",
                                "vehicle_above_mps", "approach_deg"))  # fmt: skip
        if not self.approach_deg < 180.0:
            raise ValueError(f"MotionLimits.approach_deg: must be < 180, got {self.approach_deg!r}")
        if not self.min_speed_mps < self.max_speed_mps:
            raise ValueError(f"MotionLimits: need min_speed_mps < max_speed_mps, got {self.min_speed_mps!r} "
                             f"and {self.max_speed_mps!r}")  # fmt: skip
        if not self.min_age_s <= self.window_s:
            raise ValueError(f"MotionLimits: need min_age_s <= window_s, got {self.min_age_s!r} and {self.window_s!r}")


def _variation(values) -> float:
    """Coefficient of variation (population standard deviation / mean); inf for a mean <= 0."""
    n = len(values)
    mean = sum(values) / n
    if mean <= 0:
        return math.inf
    return math.sqrt(sum((v - mean) ** 2 for v in values) / n) / mean


def line_fit(points) -> tuple[float, float, float, float]:
    """Least-squares straight line through (t_s, forward_m, right_m) points: (forward velocity m/s,
    right velocity m/s, RMS residual m of the 2-D positions, mean forward_m)."""
    # plain loops, not a sum() over a generator per figure (seven generators a call, the cost of the
    # fit): each running sum adds the same terms in the same order from 0.0 as sum() did (CPython
    # 3.11's sum() of floats adds them one by one in order), so the values are the same bit for bit
    n = len(points)
    sum_t_s = sum_forward_m = sum_right_m = 0.0
    for t_s, forward_m, right_m in points:
        sum_t_s += t_s
        sum_forward_m += forward_m
        sum_right_m += right_m
    mt, mf, mr = sum_t_s / n, sum_forward_m / n, sum_right_m / n
    # sums of squares and products of the deviations from the means: s^2, s m, s m
    stt = sft = srt = 0.0
    for t_s, forward_m, right_m in points:
        dt_s = t_s - mt
        stt += dt_s**2
        sft += dt_s * (forward_m - mf)
        srt += dt_s * (right_m - mr)
    vf, vr = sft / stt, srt / stt
    sq = 0.0
    for t_s, forward_m, right_m in points:
        dt_s = t_s - mt
        sq += (forward_m - mf - vf * dt_s) ** 2 + (right_m - mr - vr * dt_s) ** 2
    return vf, vr, math.sqrt(sq / n), mf


def recent_path(track: Track, window_s: float) -> list[tuple[float, float, float]]:
    """(t_s, forward_m, right_m) of the track's sightings within ``window_s`` of its last, t from its first."""
    fps, last = track.fps, track.last_frame
    return [((f - track.first_frame) / fps, a, b) for f, a, b in track.path if last - f <= window_s * fps]


def steady_speed_mps(track: Track, limits: MotionLimits) -> float | None:
    """The fitted ground speed, m/s, of a ``track`` that moved like a road vehicle over its last
    ``window_s`` (module docstring); None if it did not."""
    reason, speed_mps = _judge(track, limits)
    return speed_mps if reason is None else None


def overriding_speed_mps(track: Track, reason: str, limits: MotionLimits) -> float | None:
    """The fitted speed, m/s, if ``track``'s motion outweighs its rejection for ``reason`` (a reason of
    ``OVERRIDDEN_REASONS``; for ``VEHICLE_ONLY_REASONS`` only above ``vehicle_above_mps``); else None."""
    if reason not in OVERRIDDEN_REASONS:
        return None
    speed_mps = steady_speed_mps(track, limits)
    if speed_mps is None or (reason in VEHICLE_ONLY_REASONS and speed_mps <= limits.vehicle_above_mps):
        return None
    return speed_mps


def unsteady_because(track: Track, limits: MotionLimits) -> str | None:
    """Why ``track`` did not move like a road vehicle (None: it did), for diagnosis."""
    return _judge(track, limits)[0]


def _judge(track: Track, limits: MotionLimits) -> tuple[str | None, float]:
    """(why the track did not move like a road vehicle or None, its fitted speed m/s; nan unfitted)."""
    if not limits.enabled:
        return "disabled", math.nan
    points = recent_path(track, limits.window_s)
    if len(points) < limits.min_points or points[-1][0] - points[0][0] < limits.min_age_s:
        return "too young", math.nan
    vf, vr, residual_m, forward_m = line_fit(points)
    speed_mps = math.hypot(vf, vr)
    if not limits.min_speed_mps <= speed_mps <= limits.max_speed_mps:
        return "speed out of range", speed_mps
    right_m = sum(p[2] for p in points) / len(points)
    away = line_of_sight_cos(vf, vr, speed_mps, forward_m, right_m)
    if away is not None and -away > math.cos(math.radians(limits.approach_deg)):
        return "coming toward the camera", speed_mps
    if residual_m > limits.max_residual_share * max(forward_m, 1.0):
        return "not a straight steady path", speed_mps
    widths, heights = track.widths_m, track.heights_m
    if max(widths) > limits.max_width_m or max(heights) > limits.max_height_m:
        return "too big", speed_mps
    if median(widths) < limits.min_width_m or median(heights) < limits.min_height_m:
        return "too small", speed_mps
    if _variation(widths) > limits.max_size_variation or _variation(heights) > limits.max_size_variation:
        return "size unsteady", speed_mps
    return None, speed_mps


def motion_class(speed_mps: float, likeliest: str, limits: MotionLimits) -> str:
    """The class of a track taken for its motion at fitted ``speed_mps``: a vehicle above what walkers
    and cyclists go, else ``likeliest`` (its classifier's target class)."""
    return "vehicle" if speed_mps > limits.vehicle_above_mps else likeliest
