"""Could a road user have made this track? If not, it is noise, and this says why.

The paper's section 8 proposes deciding over time; a frame alone cannot tell an insect at
the infrared emitter from a walker 20 m away (both can have a walker's estimated size),
but its track can: seen through the camera model an insect near the lens jumps metres on the
ground from frame to frame, changes size as it flutters and rarely lasts. The rules, each a
reason (checked in this order, the first that holds is given):

* ``too few frames``: seen in fewer than ``min_frames`` frames (rain streaks, flickers);
* ``too fast``: ground speed above ``max_speed_mps`` (60 km/h, the fastest road user here,
  plus a margin for the estimate's noise);
* ``erratic``: the ground velocity changed faster than ``max_accel_mps2`` in at least
  ``max_accel_violations`` of the last frames (no road user accelerates like that; a single
  violation can be one bad bottom row);
* ``size outside Table 1``: the median estimated width or height over the last frames lies
  outside every Table 1 class (widened by ``size_tolerance``; a car side on is as wide as it is
  long);
* ``size unsteady``: the estimated height varies more than ``max_height_variation``
  (coefficient of variation over the last frames): a body keeps its height, an insect or a
  flickering light does not;
* ``oscillating in place``: over ``SWAY_FRAMES`` frames the box centre swung across a good
  share of its width yet ended where it began, while the ground velocity stays under
  ``still_mps``: a swaying branch or flag. A walker standing still hardly moves at all.

Speeds are m/s on the ground, sizes m (``detector.features``), frames counted at the camera's.
"""

from __future__ import annotations

from dataclasses import dataclass

from detector.classes import TABLE1
from detector.tracks.checks import require_int_at_least, require_positive
from detector.tracks.track import SWAY_FRAMES, Track, median


def apparent_size_ranges_m() -> dict[str, tuple[tuple[float, float], tuple[float, float]]]:
    """Per target class, (width, height) ranges as a camera sees them, m: a body seen from any
    side spans from its width to its length across the image (Table 1)."""
    return {
        cls: ((r.width_m[0], max(r.width_m[1], r.length_m[1])), r.height_m) for cls, r in TABLE1.items()
    }


APPARENT_SIZES_M = apparent_size_ranges_m()


def _outside(value: float, lo: float, hi: float) -> float:
    """How far ``value`` lies outside [lo, hi], relative to the nearer bound (0 inside)."""
    if value < lo:
        return (lo - value) / lo
    if value > hi:
        return (value - hi) / hi
    return 0.0


def table1_misfit(width_m: float, height_m: float) -> float:
    """The smallest relative distance of (width, height) from a Table 1 class's apparent sizes (0: fits one)."""
    return min(_outside(width_m, *w) + _outside(height_m, *h) for w, h in APPARENT_SIZES_M.values())


@dataclass(frozen=True)
class PlausibilityLimits:
    """The physical bounds a target track keeps (see the module docstring)."""

    min_frames: int = 5
    max_speed_mps: float = 60 / 3.6 * 1.5
    max_accel_mps2: float = 15.0
    max_accel_violations: int = 3
    size_tolerance: float = 0.35
    max_height_variation: float = 0.35
    still_mps: float = 0.5
    min_sway_share: float = 0.3  # of the box width
    max_sway_drift_share: float = 0.3  # of the swing

    def __post_init__(self) -> None:
        require_int_at_least(self, ("min_frames", "max_accel_violations"), 1)
        require_positive(self, ("max_speed_mps", "max_accel_mps2", "size_tolerance", "max_height_variation",
                                "still_mps", "min_sway_share", "max_sway_drift_share"))  # fmt: skip


def note_acceleration(track: Track, limits: PlausibilityLimits) -> None:
    """Record whether this frame's acceleration broke the bound (call once per observed frame).

    Not while the track ``settling`` (``detector.tracks.track.SETTLE_S``): its first velocities
    are noise and their change is no acceleration.
    """
    accel = None if track.settling else track.acceleration_mps2()
    track.accel_violations.append(accel is not None and accel > limits.max_accel_mps2)


def reject_reason(track: Track, limits: PlausibilityLimits) -> str | None:
    """Why no road user could have made ``track`` (None: one could)."""
    if track.sightings < limits.min_frames:
        return "too few frames"
    speed = track.speed_mps
    if speed is not None and speed > limits.max_speed_mps:
        return "too fast"
    if sum(track.accel_violations) >= limits.max_accel_violations:
        return "erratic"
    heights = track.heights_m
    if table1_misfit(median(track.widths_m), median(heights)) > limits.size_tolerance:
        return "size outside Table 1"
    n = len(heights)
    if n >= limits.min_frames:
        mean_m = sum(heights) / n
        variance = sum((h - mean_m) ** 2 for h in heights) / n
        if mean_m <= 0 or variance > (limits.max_height_variation * mean_m) ** 2:
            return "size unsteady"
    if _sways(track, limits):
        return "oscillating in place"
    return None


def _sways(track: Track, limits: PlausibilityLimits) -> bool:
    centres = track.centres_x_px
    if len(centres) < SWAY_FRAMES or (speed := track.speed_mps) is None or speed >= limits.still_mps:
        return False
    swing_px = max(centres) - min(centres)
    width_px = track.box_px[2]
    return swing_px >= max(3.0, limits.min_sway_share * width_px) and abs(
        centres[-1] - centres[0]
    ) <= limits.max_sway_drift_share * swing_px
