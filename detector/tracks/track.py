"""One object followed across frames: where it is on the ground, how fast, how big, what it is.

A ``Track`` keeps short windows of its history (positions in the camera's ground frame, m;
sizes; per-frame class probabilities) so every figure costs O(window) per frame. Velocities
(m/s) are the difference of the medians of the window's halves; P(target) pools the last
frames (``POOLINGS``, default ``mean_log``); the class takes the track's whole life.

Design: docs/design/tracks.md (What a track measures)
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from itertools import repeat
from operator import add, sub, truediv

#: Frames whose class probabilities are pooled into the track's class.
POOL_FRAMES = 15
#: Positions spanning about this long give a track's ground velocity, s.
VELOCITY_WINDOW_S = 0.5
#: A track's first seconds, when its outline is least steady (an object entering the view, or
#: one the background model is still learning around: a synthetic walker's ground point jumps
#: 10 -> 12 -> 9.6 m in his first five frames). Its acceleration is not judged and its speed
#: not averaged into ``mean_speed_mps`` until then.
SETTLE_S = 1.0
#: Frames of size history kept for the steadiness test.
SIZE_FRAMES = 15
#: Frames over which acceleration violations are counted.
ACCEL_FRAMES = 15
#: Frames of image-centre history kept for the oscillation test.
SWAY_FRAMES = 30
#: Frames of ground positions kept for the vehicle-motion test (``detector.tracks.motion``).
PATH_FRAMES = 30
#: A track unseen for longer than this is only still kept because it had stopped
#: (``TrackSet``'s still hold, up to 10 s): its box and ground point are predicted where it
#: stood, not carried on by the velocities of its last steps for seconds (on suburban_night at
#: 02:00 a walker leaving the view under the pole, his box bottom pinned to the frame's edge,
#: was carried 35 px across the image in 41 frames and an insect there took his track over).
#: The tracker's default ``max_missed_frames`` (5) plus the frame being predicted.
MAX_COAST_FRAMES = 6
#: Boxes are taken at least this wide and tall when their shift is measured (a pixel's jitter
#: of a box of a few pixels is no jump).
MIN_SHIFT_BOX_PX = 4.0
#: Probabilities are floored here before the logarithm (a 0 would veto a class for good).
_P_FLOOR = 1e-4
POOLINGS = ("mean_log", "mean", "last")


def pool_probabilities(frames: deque | list, pooling: str = "mean_log") -> list[float]:
    """The pooled class probabilities of per-frame probability rows (newest last)."""
    if pooling == "last":
        return list(frames[-1])
    n = len(frames)
    k = len(frames[0])
    if pooling == "mean":
        return [sum(p[c] for p in frames) / n for c in range(k)]
    if pooling != "mean_log":
        raise ValueError(f"pooling: must be one of {POOLINGS}, got {pooling!r}")
    logs = [sum(math.log(p[c] if p[c] > _P_FLOOR else _P_FLOOR) for p in frames) / n for c in range(k)]
    top = max(logs)
    exp = [math.exp(v - top) for v in logs]
    total = sum(exp)
    return [e / total for e in exp]


def median(values) -> float:
    """The median, as ``statistics.median`` (which costs more than the rest of a track's frame)."""
    ordered = sorted(values)
    n = len(ordered)
    return ordered[n // 2] if n % 2 else (ordered[n // 2 - 1] + ordered[n // 2]) / 2


def box_shift_share(before_px, after_px, frames: int) -> float:
    """How far a box's centre moved per frame between two boxes ``frames`` apart, in shares of
    the larger box's size on each axis (Euclidean over both axes).

    The larger box: a body whose legs were lost for a frame, or joined with a fragment, changes
    size and moves its centre by at most half the change, which this keeps under 0.5.
    """
    ox, oy, ow, oh = before_px
    x, y, w, h = after_px
    wide = max(w, ow, MIN_SHIFT_BOX_PX)
    tall = max(h, oh, MIN_SHIFT_BOX_PX)
    dx = (x + w / 2) - (ox + ow / 2)
    dy = (y + h / 2) - (oy + oh / 2)
    return math.hypot(dx / wide, dy / tall) / max(frames, 1)


def _median_halves_velocity(positions, fps: float, min_span_frames: float) -> tuple[float, float] | None:
    """(forward, right) velocity, m/s, from the medians of the window's older and newer halves.

    Not the two end points: a region's bottom row can jump for a frame or a few (the feet lost
    in the dark, a shadow or reflection joined below them: on the night_walk clip the walker's
    ground point flips between 9 m and 5.7 m), and through the end points every such jump is a
    burst of speed and, twice, of acceleration. The median of each half ignores jumps in fewer
    than half its frames, and a steady motion gives the same velocity as the end points.
    None while the halves' middle frames are under ``min_span_frames`` apart.
    """
    items = list(positions)
    n = len(items)
    # each half's columns in one transpose, not a list per column (this runs every frame of every track)
    older_frames, older_forward_m, older_right_m = zip(*items[: n // 2], strict=True)
    newer_frames, newer_forward_m, newer_right_m = zip(*items[n - n // 2:], strict=True)
    span_frames = median(newer_frames) - median(older_frames)
    if span_frames < min_span_frames:
        return None
    dt_s = span_frames / fps
    return (
        (median(newer_forward_m) - median(older_forward_m)) / dt_s,
        (median(newer_right_m) - median(older_right_m)) / dt_s,
    )


@dataclass(slots=True)
class Track:
    """The state of one track; ``TrackSet`` updates it, everyone else reads it."""

    track_id: int
    first_frame: int
    fps: float
    box_px: list[float]
    forward_m: float
    right_m: float
    last_frame: int = 0
    sightings: int = 1
    missed: int = 0
    image_velocity_px: tuple[float, float] = (0.0, 0.0)  # box bottom centre, px per frame
    velocity_mps: tuple[float, float] | None = None  # (forward, right), m/s; None until known
    #: (frame, forward_m, right_m), the last ``VELOCITY_WINDOW_S`` and a bit
    positions: deque = field(default_factory=deque)
    #: (frame, forward_m, right_m) of the last ``PATH_FRAMES`` sightings, for the vehicle-motion test
    path: deque = field(default_factory=lambda: deque(maxlen=PATH_FRAMES))
    #: (frame, forward_mps, right_mps): velocities, for the acceleration test
    velocities: deque = field(default_factory=deque)
    widths_m: deque = field(default_factory=lambda: deque(maxlen=SIZE_FRAMES))
    heights_m: deque = field(default_factory=lambda: deque(maxlen=SIZE_FRAMES))
    #: a steep camera's least footprints (long, short) m (``detector.tracks.steep``; else empty)
    footprints_m: deque = field(default_factory=lambda: deque(maxlen=SIZE_FRAMES))
    #: box sizes in the image, px, and their medians (the prediction's size)
    widths_px: deque = field(default_factory=lambda: deque(maxlen=SIZE_FRAMES))
    heights_px: deque = field(default_factory=lambda: deque(maxlen=SIZE_FRAMES))
    typical_size_px: tuple[float, float] = (0.0, 0.0)
    centres_x_px: deque = field(default_factory=lambda: deque(maxlen=SWAY_FRAMES))
    probabilities: deque = field(default_factory=lambda: deque(maxlen=POOL_FRAMES))
    pooled: list[float] = field(default_factory=list)
    #: summed log-probabilities per class over every frame of the track (its class)
    log_sums: list[float] = field(default_factory=list)
    #: per-frame log-probabilities of the pooling window and their running sum (``mean_log``)
    window_logs: deque = field(default_factory=lambda: deque(maxlen=POOL_FRAMES))
    window_log_sums: list[float] = field(default_factory=list)
    #: frames (within the acceleration window) whose acceleration exceeded the bound
    accel_violations: deque = field(default_factory=lambda: deque(maxlen=ACCEL_FRAMES))
    #: how far the box centre moved since the last sighting, per frame, in shares of the box's
    #: size (``box_shift_share``; None on the first frame); how far the box is from the one of
    #: the sighting before (as if one frame apart; None until there is one): near it, the last
    #: box was an excursion (another region taken for one frame) and this is the return; and the
    #: frames (within the acceleration window) that were jumps (``plausibility.note_jump``)
    shift_share: float | None = None
    return_share: float | None = None
    prior_box_px: list | None = None
    box_jumps: deque = field(default_factory=lambda: deque(maxlen=ACCEL_FRAMES))
    #: frames judged moving faster than walkers along the line of sight, and of those the frames
    #: too wide for it (``detector.tracks.plausibility.note_heading``)
    head_on_frames: int = 0
    wide_frames: int = 0
    #: the last n target decisions as bits, newest in bit 0 (k-of-n confirmation)
    hit_bits: int = 0
    target: bool = False
    reason: str | None = "too few frames"
    cls: str = "noise"
    p_target: float = 0.0
    speed_sum_mps: float = 0.0
    speed_frames: int = 0
    target_frames: int = 0
    #: frames per target class while the track was a target; frames per reason while it was not
    target_classes: dict = field(default_factory=dict)
    reasons: dict = field(default_factory=dict)
    merged_into: int | None = None
    #: the last frame the track's ground speed was under the still limit, and the last its box
    #: reached the frame's bottom edge (``TrackSet``; None: never)
    still_frame: int | None = None
    exit_frame: int | None = None
    #: frames a velocity difference must span: half the velocity window, at least 2 (from ``fps``)
    min_span_frames: float = field(init=False, default=2.0)

    def __post_init__(self) -> None:
        if self.typical_size_px == (0.0, 0.0):  # until the first frame is noted: the given box
            self.typical_size_px = (self.box_px[2], self.box_px[3])
        self.min_span_frames = max(2.0, VELOCITY_WINDOW_S * self.fps / 2)

    @property
    def speed_mps(self) -> float | None:
        if self.velocity_mps is None:
            return None
        return math.hypot(*self.velocity_mps)

    @property
    def settling(self) -> bool:
        """Whether the track is in its first ``SETTLE_S`` (see there)."""
        return self.last_frame - self.first_frame < SETTLE_S * self.fps

    @property
    def mean_speed_mps(self) -> float | None:
        return self.speed_sum_mps / self.speed_frames if self.speed_frames else None

    def predicted_box(self) -> tuple[float, float, float, float]:
        """The last box, at least as wide and tall as the track's typical box (median width and
        height of its last frames), standing on its last bottom centre moved on by its image
        velocity over the frames since it was last seen.

        At least typical: a frame where only the legs (or a speck) were segmented would
        otherwise shrink the prediction to that piece, and the whole body the next frame would
        no longer fit it; but a box grown since (a car coming closer, pieces joined into one
        region by ``reunite``) is the size to expect. Standing on the bottom centre because the
        feet are what a partly segmented body keeps (and what the ground point is).
        """
        x, y, w, h = self.box_px
        vx, vy = self.image_velocity_px
        steps = min(self.missed + 1, MAX_COAST_FRAMES)
        tw, th = self.typical_size_px
        tw, th = max(tw, w), max(th, h)
        cx, bottom = x + w / 2 + vx * steps, y + h + vy * steps
        return (cx - tw / 2, bottom - th, tw, th)

    def predicted_ground(self, frame: int) -> tuple[float, float]:
        """(forward_m, right_m) at ``frame`` at the track's ground velocity (its last position if unknown)."""
        if self.velocity_mps is None:
            return self.forward_m, self.right_m
        dt_s = min(frame - self.last_frame, MAX_COAST_FRAMES) / self.fps
        return self.forward_m + self.velocity_mps[0] * dt_s, self.right_m + self.velocity_mps[1] * dt_s

    def observe(self, frame: int, box_px, ground, features, probabilities, smoothing: float = 0.5) -> None:
        """One frame's region: box, (forward_m, right_m), feature row and class probabilities."""
        x, y, w, h = box_px
        ox, oy, ow, oh = self.box_px
        steps = max(frame - self.last_frame, 1)
        sx = ((x + w / 2) - (ox + ow / 2)) / steps  # of the bottom centre (see predicted_box)
        sy = ((y + h) - (oy + oh)) / steps
        self.shift_share = box_shift_share(self.box_px, box_px, steps)
        prior = self.prior_box_px
        self.return_share = None if prior is None else box_shift_share(prior, box_px, 1)
        self.prior_box_px = self.box_px
        if self.sightings == 1:
            self.image_velocity_px = (sx, sy)
        else:
            vx, vy = self.image_velocity_px
            self.image_velocity_px = (smoothing * sx + (1 - smoothing) * vx, smoothing * sy + (1 - smoothing) * vy)
        self.box_px = list(box_px)
        self._note_size_px(w, h)
        self.sightings += 1
        self.missed = 0
        self.last_frame = frame
        self.forward_m, self.right_m = ground
        self._update_velocity(frame)
        self.widths_m.append(features[0])
        self.heights_m.append(features[1])
        self.centres_x_px.append(x + w / 2)
        self._add_probabilities(probabilities)

    def _add_probabilities(self, probabilities) -> None:
        self.probabilities.append(probabilities)
        logs = [math.log(p if p > _P_FLOOR else _P_FLOOR) for p in probabilities]
        if not self.log_sums:
            self.log_sums, self.window_log_sums = list(logs), list(logs)
            self.window_logs.append(logs)
            return
        # element by element in C (map of operator's add and sub), the same float operations as
        # comprehensions over zip, for a fraction of the bytecode: this runs every frame of every track
        self.log_sums = list(map(add, self.log_sums, logs))
        sums = self.window_log_sums
        if len(self.window_logs) == self.window_logs.maxlen:  # the oldest frame leaves the window
            sums = map(sub, sums, self.window_logs[0])
        self.window_logs.append(logs)
        self.window_log_sums = list(map(add, sums, logs))

    def pooled_probabilities(self, pooling: str = "mean_log") -> list[float]:
        """``pool_probabilities`` of the window; ``mean_log`` from the running sums (O(classes))."""
        if pooling != "mean_log":
            return pool_probabilities(self.probabilities, pooling)
        n = len(self.window_logs)
        means = [v / n for v in self.window_log_sums]
        top = max(means)
        # maps of math and operator functions, not comprehensions: the same float operations (v - top,
        # exp, e / total) without a Python function per comprehension, every frame of every track
        exp = list(map(math.exp, map(sub, means, repeat(top))))
        return list(map(truediv, exp, repeat(sum(exp))))

    def start(self, box_px, ground, features, probabilities) -> None:
        """The first frame's region (the fields the constructor did not set)."""
        x, _, w, h = box_px
        self._note_size_px(w, h)
        self.last_frame = self.first_frame
        self.positions.append((self.first_frame, *ground))
        self.path.append((self.first_frame, *ground))
        self.widths_m.append(features[0])
        self.heights_m.append(features[1])
        self.centres_x_px.append(x + w / 2)
        self._add_probabilities(probabilities)

    def _note_size_px(self, w: float, h: float) -> None:
        self.widths_px.append(w)
        self.heights_px.append(h)
        self.typical_size_px = (median(self.widths_px), median(self.heights_px))

    def _update_velocity(self, frame: int) -> None:
        positions, fps = self.positions, self.fps
        position = (frame, self.forward_m, self.right_m)  # one (immutable) tuple for both windows
        positions.append(position)
        self.path.append(position)
        window = VELOCITY_WINDOW_S * fps
        while len(positions) > 2 and frame - positions[1][0] >= window:
            positions.popleft()
        velocity = _median_halves_velocity(positions, fps, self.min_span_frames)
        if velocity is None:  # a frame or two of jitter is no velocity
            return
        self.velocity_mps = velocity
        velocities = self.velocities
        velocities.append((frame, *velocity))
        while len(velocities) > 2 and frame - velocities[1][0] >= window:
            velocities.popleft()
        if not self.settling:
            self.speed_sum_mps += math.hypot(*velocity)
            self.speed_frames += 1

    def acceleration_mps2(self) -> float | None:
        """Change of the ground velocity over the last velocity window, m/s^2 (None until known)."""
        velocities = self.velocities
        if len(velocities) < 2:
            return None
        f0, a0, b0 = velocities[0]
        f1, a1, b1 = velocities[-1]
        if f1 - f0 < self.min_span_frames:
            return None
        return math.hypot(a1 - a0, b1 - b0) * self.fps / (f1 - f0)
