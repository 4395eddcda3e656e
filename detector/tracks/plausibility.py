"""Could a road user have made this track? If not, it is noise, and this says why.

``reject_reason`` checks the rules in order (too few frames, too fast, erratic, jumping, size
outside Table 1, size unsteady, too wide for its heading, oscillating in place) and gives the
first that holds. Speeds are m/s on the ground, sizes m (``detector.features``), frames counted
at the camera's.

Design: docs/design/plausibility.md
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from detector.classes import TABLE1
from detector.tracks.checks import require_int_at_least, require_positive
from detector.tracks.ground import line_of_sight_cos
from detector.tracks.track import SWAY_FRAMES, Track, median


def apparent_size_ranges_m() -> dict[str, tuple[tuple[float, float], tuple[float, float]]]:
    """Per target class, (width, height) ranges as a camera sees them, m: a body seen from any
    side spans from its width to its length across the image (Table 1)."""
    return {
        cls: ((r.width_m[0], max(r.width_m[1], r.length_m[1])), r.height_m) for cls, r in TABLE1.items()
    }


APPARENT_SIZES_M = apparent_size_ranges_m()

#: Classes a road user moving faster than walkers can be (groups and pedestrians walk; a jogger
#: is a pedestrian no wider than a walker).
FAST_CLASSES = ("cyclist", "vehicle")


def front_aspect() -> float:
    """The largest width / height (Table 1: widest over lowest) a cyclist or vehicle shows from the
    front or back: a vehicle's 1.8 m over 1.4 m, 1.29."""
    return max(TABLE1[c].width_m[1] / TABLE1[c].height_m[0] for c in FAST_CLASSES)


FRONT_ASPECT = front_aspect()


#: ``APPARENT_SIZES_M``' bounds as flat (width lo, width hi, height lo, height hi) rows, m
_APPARENT_BOUNDS_M = tuple((*w, *h) for w, h in APPARENT_SIZES_M.values())


def table1_misfit(width_m: float, height_m: float) -> float:
    """The smallest relative distance of (width, height) from a Table 1 class's apparent sizes (0: fits one)."""
    # per class: how far each value lies outside its [lo, hi], relative to the nearer bound (0
    # inside); written out in one comprehension, as this runs every frame of every track and ten
    # calls of a helper cost more than the arithmetic
    return min([
        ((w_lo - width_m) / w_lo if width_m < w_lo else (width_m - w_hi) / w_hi if width_m > w_hi else 0.0)
        + ((h_lo - height_m) / h_lo if height_m < h_lo else (height_m - h_hi) / h_hi if height_m > h_hi else 0.0)
        for w_lo, w_hi, h_lo, h_hi in _APPARENT_BOUNDS_M
    ])  # fmt: skip


@dataclass(frozen=True)
class PlausibilityLimits:
    """The physical bounds a target track keeps (see the module docstring)."""

    min_frames: int = 5
    max_speed_mps: float = 60 / 3.6 * 1.5
    max_accel_mps2: float = 15.0
    max_accel_violations: int = 3
    #: a box centre moving more than this share of the box's size in one frame jumped (module
    #: docstring: insects about 1, road users under 0.4)
    max_box_shift: float = 0.5
    #: jumps within the acceleration window that make a track 'jumping' (one can be a fragment
    #: joined or lost)
    max_box_jumps: int = 2
    size_tolerance: float = 0.35
    max_height_variation: float = 0.35
    still_mps: float = 0.5
    #: walkers, groups and joggers stay under this (citysim's walkers 1.0-1.8 m/s, runners to 4 m/s,
    #: but a runner is a pedestrian: narrow); above it a track is a cyclist or a vehicle
    walk_max_mps: float = 2.5
    #: within this of the line of sight a body shows the camera its front or back (cos 25 deg = 0.91:
    #: a car's 4.6 m length then adds at most 1.9 m to its width)
    head_on_deg: float = 25.0
    min_sway_share: float = 0.3  # of the box width
    max_sway_drift_share: float = 0.3  # of the swing

    def __post_init__(self) -> None:
        require_int_at_least(self, ("min_frames", "max_accel_violations", "max_box_jumps"), 1)
        require_positive(self, ("max_speed_mps", "max_accel_mps2", "max_box_shift", "size_tolerance",
                                "max_height_variation", "still_mps", "walk_max_mps", "head_on_deg",
                                "min_sway_share", "max_sway_drift_share"))  # fmt: skip
        if not self.size_tolerance < 1.0:
            raise ValueError(f"PlausibilityLimits.size_tolerance: must be < 1, got {self.size_tolerance!r}")
        if not self.head_on_deg < 90.0:
            raise ValueError(f"PlausibilityLimits.head_on_deg: must be < 90, got {self.head_on_deg!r}")


def note_acceleration(track: Track, limits: PlausibilityLimits) -> None:
    """Record whether this frame's acceleration broke the bound (call once per observed frame).

    Not while the track ``settling`` (``detector.tracks.track.SETTLE_S``): its first velocities
    are noise and their change is no acceleration.
    """
    accel = None if track.settling else track.acceleration_mps2()
    track.accel_violations.append(accel is not None and accel > limits.max_accel_mps2)


def note_jump(track: Track, limits: PlausibilityLimits) -> None:
    """Record whether the box jumped this frame (call once per observed frame; module docstring).
    Unlike the acceleration, judged from the track's second frame on."""
    share, back = track.shift_share, track.return_share
    # back where it was the sighting before: the last box was another region taken for a frame
    # (on the paper's scene C a car's track took a region 3.5 m beside it for one frame); the
    # excursion was one jump, the return is none
    returned = back is not None and back <= limits.max_box_shift
    track.box_jumps.append(share is not None and share > limits.max_box_shift and not returned)


def note_heading(track: Track, limits: PlausibilityLimits) -> None:
    """Count this frame for 'too wide for its heading' (call once per observed frame)."""
    speed = track.speed_mps
    if speed is None or speed <= limits.walk_max_mps:
        return
    cos = heading_cos(track)
    if cos is None or abs(cos) < math.cos(math.radians(limits.head_on_deg)):
        return
    track.head_on_frames += 1
    height_m = median(track.heights_m)
    if height_m <= 0.0 or median(track.widths_m) / height_m > FRONT_ASPECT / (1.0 - limits.size_tolerance):
        track.wide_frames += 1


def reject_reason(track: Track, limits: PlausibilityLimits, size_reason=None) -> str | None:
    """Why no road user could have made ``track`` (None: one could).

    ``size_reason(track)``, if given, replaces the upright-body size rules ('size outside Table 1',
    'size unsteady', 'too wide for its heading'): a camera looking steeply down judges the track's
    footprint instead (``detector.tracks.steep``)."""
    # said as soon as seen: an insect's mark before its velocity is known (the jumps are counted
    # again below for a track whose velocity is known, so a young track's count is the only extra)
    if track.velocity_mps is None and track.box_jumps.count(True) >= limits.max_box_jumps:
        return "jumping"
    if track.sightings < limits.min_frames or track.velocity_mps is None:
        return "too few frames"
    speed = track.speed_mps
    if speed > limits.max_speed_mps:
        return "too fast"
    # the windows hold bools: count them in C (sum() adds them one by one)
    if track.accel_violations.count(True) >= limits.max_accel_violations:
        return "erratic"
    if track.box_jumps.count(True) >= limits.max_box_jumps:
        return "jumping"
    if size_reason is not None:
        reason = size_reason(track)
        if reason is None and not speed >= limits.still_mps and _sways(track, limits):
            return "oscillating in place"
        return reason
    heights = track.heights_m
    if table1_misfit(median(track.widths_m), median(heights)) > limits.size_tolerance:
        return "size outside Table 1"
    n = len(heights)
    if n >= limits.min_frames:
        mean_m = sum(heights) / n
        variance = sum([(h - mean_m) ** 2 for h in heights]) / n
        if mean_m <= 0 or variance > (limits.max_height_variation * mean_m) ** 2:
            return "size unsteady"
    if 2 * track.wide_frames > track.head_on_frames > 0:
        return "too wide for its heading"
    # only a track under the still limit can sway (_sways' own test, made here to skip the call for
    # the moving ones; 'not >=' as there)
    if not speed >= limits.still_mps and _sways(track, limits):
        return "oscillating in place"
    return None


def heading_cos(track: Track) -> float | None:
    """Cosine between the track's ground velocity and the line of sight from the pole foot (1: going
    straight away, -1: coming straight at the camera); None while either is unknown."""
    speed = track.speed_mps
    if speed is None:
        return None
    vf, vr = track.velocity_mps
    return line_of_sight_cos(vf, vr, speed, track.forward_m, track.right_m)


def _sways(track: Track, limits: PlausibilityLimits) -> bool:
    centres = track.centres_x_px
    if len(centres) < SWAY_FRAMES or (speed := track.speed_mps) is None or speed >= limits.still_mps:
        return False
    swing_px = max(centres) - min(centres)
    width_px = track.box_px[2]
    return swing_px >= max(3.0, limits.min_sway_share * width_px) and abs(
        centres[-1] - centres[0]
    ) <= limits.max_sway_drift_share * swing_px
