"""Cameras looking steeply down: a track's size, class and target decision by its footprint.

Used by ``TrackSet`` only where ``detector.tracks.footprint.is_steep``: the least footprint
(``least_sides_m``), its size rule (``size_reason``), jumps against the track's largest box
(``piece_shift_share``), the class (``footprint_class``) and whole-body frames (``whole_frames``).
Sizes m on the ground, boxes OpenCV ``(x, y, w, h)`` px.

Design: docs/design/steep-cameras.md
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from detector.classes import TABLE1
from detector.tracks.footprint import FootprintGeometry
from detector.tracks.track import Track, box_shift_share, median

#: Frames of the pooling window classified target on their own that make a plausible track a
#: target whatever its pooled P(target) (module docstring): more than one, as a single frame can
#: be a fluke (the jump rule counts likewise)
MIN_WHOLE_FRAMES = 2


def footprint_max_m() -> dict[str, tuple[float, float]]:
    """Per target class, the largest (long side, short side) of the ground box a body of Table 1's
    widest and longest covers in any heading, m: its diagonal, and (width + length) / sqrt 2 at 45
    degrees."""
    out = {}
    for cls, r in TABLE1.items():
        w, length = r.width_m[1], r.length_m[1]
        out[cls] = (math.hypot(w, length), (w + length) / math.sqrt(2))
    return out


FOOTPRINT_MAX_M = footprint_max_m()


def vehicle_min_m(size_tolerance: float) -> tuple[float, float]:
    """(long, short) sides of Table 1's smallest vehicle less ``size_tolerance``, m."""
    v = TABLE1["vehicle"]
    return v.length_m[0] * (1 - size_tolerance), v.width_m[0] * (1 - size_tolerance)


def least_sides_m(footprints: FootprintGeometry, boxes_px: Sequence[Sequence[float]]) -> list[tuple[float, float] | None]:
    """(depth_m, width_m) of each box's least footprint (module docstring); None for a box with a
    corner at or above the horizon."""
    out: list[tuple[float, float] | None] = []
    roof_m = footprints.params.roof_m
    for box in boxes_px:
        on_ground, on_roof = footprints.corners_m(box, 0.0), footprints.corners_m(box, roof_m)
        if on_ground is None or on_roof is None:
            out.append(None)
            continue
        # corners bottom-left, bottom-right, top-left, top-right: (forward_m, right_m)
        depth_m = max(0.0, min(on_roof[2][0], on_roof[3][0]) - max(on_ground[0][0], on_ground[1][0]))
        width_m = min(on_ground[1][1] - on_ground[0][1], on_roof[3][1] - on_roof[2][1])
        out.append((depth_m, width_m))
    return out


def note_footprint(track: Track, footprints: FootprintGeometry) -> None:
    """Record the least footprint (long, short) of the track's box this frame (call once per
    observed frame)."""
    sides = least_sides_m(footprints, [track.box_px])[0]
    if sides is not None:
        track.footprints_m.append((max(sides), min(sides)))


def median_sides_m(track: Track) -> tuple[float, float] | None:
    """Median (long, short) of the track's recorded least footprints, m; None before any."""
    if not track.footprints_m:
        return None
    return median([s[0] for s in track.footprints_m]), median([s[1] for s in track.footprints_m])


def upper_quartile_sides_m(track: Track) -> tuple[float, float]:
    """Upper quartiles (long, short) of the track's recorded least footprints, m (at least one)."""
    longs = sorted(s[0] for s in track.footprints_m)
    shorts = sorted(s[1] for s in track.footprints_m)
    k = (3 * len(longs)) // 4  # of 1-3 frames the largest; of 15 the 12th
    return longs[min(k, len(longs) - 1)], shorts[min(k, len(shorts) - 1)]


def fitting_classes(sides_m: tuple[float, float], size_tolerance: float) -> list[str]:
    """The target classes whose largest footprint (``FOOTPRINT_MAX_M`` widened by
    ``size_tolerance``) holds ``sides_m`` (long, short)."""
    long_m, short_m = sides_m
    grow = 1 + size_tolerance
    return [c for c, (lo, sh) in FOOTPRINT_MAX_M.items() if long_m <= lo * grow and short_m <= sh * grow]


def size_reason(track: Track, size_tolerance: float) -> str | None:
    """'footprint outside Table 1' when no class fits the track's median least footprint (or none
    is known); None otherwise (module docstring)."""
    sides = median_sides_m(track)
    if sides is None or not fitting_classes(sides, size_tolerance):
        return "footprint outside Table 1"
    return None


def footprint_class(track: Track, class_names: Sequence[str], size_tolerance: float) -> str:
    """The track's class (module docstring): 'vehicle' if its median least footprint reaches the
    smallest vehicle's, else the classifier's likeliest among the classes the footprint fits (all
    target classes if it fits none)."""
    sides = median_sides_m(track)
    fits = [] if sides is None else fitting_classes(sides, size_tolerance)
    if "vehicle" in fits:
        long_min, short_min = vehicle_min_m(size_tolerance)
        long_m, short_m = upper_quartile_sides_m(track)
        if long_m >= long_min and short_m >= short_min:
            return "vehicle"
    candidates = [c for c in class_names if c != "noise" and (not fits or c in fits)]
    return max(candidates, key=lambda c: track.log_sums[class_names.index(c)])


def piece_shift_share(track: Track) -> float | None:
    """``Track.shift_share`` with each box taken at least as large as the track's largest box of its
    last ``SIZE_FRAMES`` frames (module docstring: a piece moving inside its body's outline); None
    on the first frame."""
    prior, path = track.prior_box_px, track.path
    if prior is None or len(path) < 2:
        return track.shift_share
    tw, th = max(track.widths_px), max(track.heights_px)

    def grown(box):
        x, y, w, h = box
        return (x + w / 2 - max(w, tw) / 2, y + h / 2 - max(h, th) / 2, max(w, tw), max(h, th))

    return box_shift_share(grown(prior), grown(track.box_px), max(path[-1][0] - path[-2][0], 1))


def whole_frames(track: Track, noise_col: int, threshold: float) -> int:
    """Frames of the pooling window classified target on their own (P(noise) <= 1 - threshold)."""
    return sum(1 for p in track.probabilities if 1.0 - p[noise_col] >= threshold)
