"""Cameras looking steeply down: a track's size, class and target decision by its footprint.

The paper's track rules (``detector.tracks.plausibility``) and the classifier's features measure a
region as an upright body standing on its box's bottom row (``detector.features``). A camera
looking steeply down (``detector.tracks.footprint.is_steep``) sees bodies from above, where that
measure fails both ways: a car joined from its pieces (``footprint``) measures 2-3 m wide and 3-5 m
"tall" as an upright body, outside every Table 1 class (on the car-park development clip the two
cars' tracks were 'size outside Table 1' or 'size unsteady' in every frame); and a walker or
cyclist far up the view, whose legs or wheels alone are segmented in half of the frames, measures
0.4-0.9 m "tall" there, which the classifier calls noise at P 0.99 or more, so the pooled
P(target) of his track stays under the threshold (the clip's walker: 0.08-0.49 once judged; the
cyclist: 0.003-0.14; the person wheeling a bicycle: 0.003-0.13). Retraining is no way out: the
classifier already is one trained for this camera on the spot (its view is shorter than the
general model's), on upright bodies; it calls the joined cars' regions 'group' (25 on the clip)
about as often as 'vehicle' (26), and the cars' tracks were 'group' by their summed log-
probabilities in every frame. For these cameras the track is judged on the ground instead:

**Least footprint** (``least_sides_m``): the smallest ground extents a body at most Table 1's
tallest (2.0 m, ``FootprintParams.roof_m``) could have made the box with, along the camera's
heading: seen from above a box's bottom row is the body's nearest point, on the ground, and its
top row its farthest, at most ``roof_m`` up, so its depth is at least from the bottom corners on
the ground to the top corners on the roof plane (0 where they cross). Across the view: the box's
width on the ground at its bottom row or on the roof plane at its top row, the smaller (an
upright body off the view's centre leans outward in the image and widens its box: the clip's
walker 0.43-0.77 m, a 0.5 m walker 5 m off the centre at 13 m 0.94 m; a strict bound, taking each
side at whichever height puts it innermost, shrank the clip's cars' widths to 0.2-1.4 m).
Unlike the joiner's extents (``FootprintGeometry.extents_m``, the hull of the four corners, an upper bound test for joining),
this holds no roof parallax: the hull of a small box far up the view spans metres between its
corners on the ground and on the roof plane (the clip's walker: 1.1-1.8 m across), his least
footprint does not (long side 0.43-0.77 m, 10th-90th percentile). An upright walker's least depth
is 0: his head's ray meets the roof plane before his feet.

**Size** (``size_reason``): over the last ``SIZE_FRAMES`` frames the median least footprint's long
and short sides must stay within what some Table 1 class can cover in some heading
(``FOOTPRINT_MAX_M``: a width x length rectangle turned any way covers at most its diagonal on its
long side and (width + length) / sqrt 2 on its short side), widened by ``size_tolerance``:
otherwise 'footprint outside Table 1'. Only upper bounds: the least footprint is a lower bound of
the body's. It replaces the upright-body rules 'size outside Table 1', 'size unsteady' (the
height as an upright body of a car whose pieces come and go) and 'too wide for its heading' (an
upright body's width over height); the motion rules (too few frames, too fast, erratic, jumping,
oscillating in place) stay.

**Jumps** (``piece_shift_share``): the paper's jump (the box centre moving more than half the box's
size in one frame: an insect near the lens) measured against the track's largest box of its last
``SIZE_FRAMES`` frames too, not only this frame's and the last: from above, a body whose legs or
wheels alone were segmented is a piece moving inside its own outline (the clip's cyclist: boxes of
6 x 4 px between 30 x 32 px ones, 'jumping' in 21 of his 29 frames, now 6), not a blob jumping by
its own size. An insect's blob keeps about its own size; its jumps are measured as before. The
return test (a box back where it was the sighting before) is the paper's.

**Class** (``footprint_class``): 'vehicle' if the footprint fits a vehicle and the least footprint
reaches Table 1's smallest vehicle, 3.7 x 1.4 m less ``size_tolerance`` (2.4 x 0.91 m), in its long
and short sides' upper quartiles over the window (a lower bound: a frame where pieces of the car
were lost shrinks it, so not the median; a single frame, a region wrongly joined, does not
decide; the clip's cars, pieces only in their first frames, were 'group' there by the median
until 6-10 frames in): no lone
walker or cyclist covers that, and a moving region that large is what the joiner already takes for
one vehicle (``footprint``; the clip's cars: 90th percentiles 3.0-3.4 x 2.4 m, medians
2.1-2.8 x 1.7-2.0 m, the camera being an estimate);
else the classifier's likeliest (``Track.log_sums``) among the classes the footprint fits. Its
upright-body features still tell a walker from a group or a cyclist when his whole body is
segmented. Two walkers abreast across the view's diagonal can cover a vehicle's least footprint: a
known limit (the track is still a target; only its class is wrong).

**Target** (``whole_frames``): a track the rules above find plausible is a target when its pooled
P(target) reaches the threshold (as the paper's), or when at least ``MIN_WHOLE_FRAMES`` of its
pooling window's frames were classified target on their own: the frames where the whole body was
segmented, the only ones the upright-body features measure right from above. Noise seldom looks
like a whole road user even for a frame and then also has to keep a road user's footprint and
motion; still regions (ghosts) follow no track (``detector.ghosts``).

Not for the paper's or the lamps' cameras (13-22 degrees down): ``TrackSet`` uses this only where
``is_steep``. Sizes m on the ground, boxes OpenCV ``(x, y, w, h)`` px (``footprint`` conventions).
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
