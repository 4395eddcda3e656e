"""A camera's tracks: each frame's regions associated, fragments joined, classes pooled, physics checked.

``TrackSet`` is what ``detector.detector.Detector`` calls per frame, in two steps around the
classifier: ``prepare(boxes, areas, rows, still)`` (ground points, association, joining) returns
the regions to classify; ``update(prepared, probabilities)`` continues or starts every track,
decides its target and returns one ``TrackView`` per region. Track ids are ints from 1, never
reused.

Design: docs/design/tracks.md
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

from detector.camera import CameraModel
from detector.features import RegionGeometry
from detector.tracks.associate import Gates, associate
from detector.tracks.footprint import FootprintJoiner, FootprintParams, continue_inside, is_steep
from detector.tracks.ground import GroundProjector
from detector.tracks.motion import MotionLimits, motion_class, overriding_speed_mps
from detector.tracks.plausibility import (
    PlausibilityLimits,
    note_acceleration,
    note_heading,
    note_jump,
    reject_reason,
)
from detector.tracks.reunite import ReuniteParams, fragment_groups, union_box
from detector.tracks.steep import (
    MIN_WHOLE_FRAMES,
    footprint_class,
    note_footprint,
    piece_shift_share,
    size_reason,
    whole_frames,
)
from detector.tracks.track import POOLINGS, Track

#: A box whose bottom is this close to the frame's last row reaches the frame's bottom edge (the
#: mask's opening trims the rows at the border: walkers leaving suburban_night's view under the
#: pole ended at rows 237-239 of 240).
EXIT_MARGIN_PX = 3
#: ``Prepared.track_of`` of a still region (``detector.ghosts``): it follows no track
STILL = -2
#: Why a still region is no target
STILL_REASON = "still (a ghost)"
#: an established target (a target in at least this many seconds' frames) stays one through a
#: passing doubt (``PASSING_DOUBTS``: a walker whose region flickers as he turns, or merges with
#: his reflection for a few frames) while its pooled P(target) stays at least ``ESTABLISHED_MIN_P``
ESTABLISHED_TARGET_S = 3.0
ESTABLISHED_MIN_P = 0.25
PASSING_DOUBTS = frozenset({"erratic", "size unsteady", "classified noise"})
_DEFAULT_LIMITS = PlausibilityLimits()
_DEFAULT_MOTION = MotionLimits()
_DEFAULT_GATES = Gates()
_DEFAULT_REUNITE = ReuniteParams()
_DEFAULT_FOOTPRINT = FootprintParams()


class TrackView(NamedTuple):
    """What a region's track says about it this frame (world ground frame, m and m/s).

    A named tuple, not a frozen dataclass: one is made per region per frame, and a frozen
    dataclass sets its ten fields one call at a time (0.8 us against 0.2 us, measured)."""

    track_id: int | None  # None: a still region (``detector.ghosts``), on no track
    cls: str
    p_target: float
    target: bool
    reason: str | None  # why it is not a target (None: it is one)
    ground_x_m: float
    ground_y_m: float
    velocity_x_mps: float | None
    velocity_y_mps: float | None
    speed_mps: float | None


@dataclass
class Prepared:
    """A frame's regions after association and reunification, ready to classify."""

    boxes_px: list
    areas_px: list
    rows: list
    grounds: list
    track_of: list[int]  # track index per region, -1 for a new track
    absorbed: list[tuple[int, int]]  # (track index, region it joined) for tracks joined into another


class TrackSet:
    """The tracks of one camera (see the module docstring)."""

    def __init__(
        self,
        camera: CameraModel,
        class_names: Sequence[str],
        target_threshold: float = 0.5,
        *,
        geometry: RegionGeometry | None = None,
        limits: PlausibilityLimits = _DEFAULT_LIMITS,
        motion: MotionLimits = _DEFAULT_MOTION,
        gates: Gates = _DEFAULT_GATES,
        reunite: ReuniteParams | None = _DEFAULT_REUNITE,
        footprint: FootprintParams | None = _DEFAULT_FOOTPRINT,
        pooling: str = "mean_log",
        max_missed_frames: int = 5,
        still_hold_s: float = 10.0,
        confirm_k: int = 2,
        confirm_n: int = 6,
        keep_ended: bool = False,
    ) -> None:
        if pooling not in POOLINGS:
            raise ValueError(f"TrackSet pooling: must be one of {POOLINGS}, got {pooling!r}")
        if "noise" not in class_names:
            raise ValueError(f"TrackSet class_names: must include 'noise', got {list(class_names)}")
        if not 1 <= confirm_k <= confirm_n:
            raise ValueError(f"TrackSet: need 1 <= confirm_k <= confirm_n, got k={confirm_k}, n={confirm_n}")
        self.fps = camera.fps
        self.exit_row_px = camera.height_px - EXIT_MARGIN_PX
        self.geometry = RegionGeometry(camera) if geometry is None else geometry
        self.ground = GroundProjector(camera, self.geometry)
        # a camera looking steeply down joins a car's pieces by their footprint (``footprint``)
        self.footprint = (
            FootprintJoiner(camera, self.geometry, footprint) if footprint is not None and is_steep(camera) else None
        )
        # where a region stands: its box's bottom centre (an upright body's feet), or for a steep
        # camera the middle of its footprint (a body seen from above; ``footprint``)
        self._grounds = self.ground.bottom_centres if self.footprint is None else self.footprint.footprints.centres_m
        self.class_names = list(class_names)
        self.noise_col = self.class_names.index("noise")
        self._target_cols = [c for c in range(len(self.class_names)) if c != self.noise_col]
        self.target_threshold = float(target_threshold)
        self.limits, self.gates, self.reunite, self.pooling = limits, gates, reunite, pooling
        self.motion = motion
        self.max_missed_frames = int(max_missed_frames)
        self.still_hold_frames = round(still_hold_s * camera.fps)
        # a track missed no more frames than either limit is kept without asking which applies
        self._surely_kept_frames = min(self.max_missed_frames, self.still_hold_frames)
        self.confirm_k, self.confirm_n = int(confirm_k), int(confirm_n)
        self._mask = (1 << self.confirm_n) - 1
        self.keep_ended = keep_ended
        self.tracks: list[Track] = []
        self.ended: list[Track] = []
        self.frame = -1
        self._next_id = 1

    def __len__(self) -> int:
        return len(self.tracks)

    def reset(self) -> None:
        """Forget every track (ids keep counting up)."""
        for track in self.tracks:
            self._end(track)
        self.tracks = []

    def is_confirmed(self, track_id: int) -> bool:
        """Whether the track was a target in at least k of its last n frames."""
        return any(t.track_id == track_id and t.hit_bits.bit_count() >= self.confirm_k for t in self.tracks)

    # ------------------------------------------------------------------ step 1
    def prepare(self, boxes_px: list, areas_px: list, rows: list, still: list[bool] | None = None) -> Prepared:
        """Associate this frame's regions (feature rows all with a ground point) and join fragments.

        ``still``: per region, whether nothing moved in it (``detector.ghosts``); still regions
        join nothing and follow no track (``STILL``), listed after the others."""
        self.frame += 1
        ghosts = None
        if still is not None and any(still):
            ghosts = [(b, a, r) for b, a, r, s in zip(boxes_px, areas_px, rows, still, strict=True) if s]
            moving = [i for i, s in enumerate(still) if not s]
            boxes_px, areas_px, rows = [boxes_px[i] for i in moving], [areas_px[i] for i in moving], [rows[i] for i in moving]
        if self.footprint is not None and len(boxes_px) > 1:
            boxes_px, areas_px, rows = self.footprint.join(boxes_px, areas_px, rows)
        grounds = self._grounds(boxes_px)
        track_of = associate(self.tracks, boxes_px, grounds, self.frame, self.gates)
        if self.footprint is not None and self.reunite is not None:
            continue_inside(self.tracks, boxes_px, track_of, self.reunite.min_inside_share)
        prepared = Prepared(boxes_px, areas_px, rows, grounds, track_of, [])
        if self.reunite is not None and len(boxes_px) > 1:
            self._join(prepared)
        if ghosts:
            boxes, areas, ghost_rows = (list(column) for column in zip(*ghosts, strict=True))
            p = prepared
            p.boxes_px, p.areas_px, p.rows = p.boxes_px + boxes, p.areas_px + areas, p.rows + ghost_rows
            p.grounds = p.grounds + self._grounds(boxes)
            p.track_of = p.track_of + [STILL] * len(boxes)
        return prepared

    def _join(self, p: Prepared) -> None:
        geometry = self.geometry

        def union_row(indices):
            box = union_box([p.boxes_px[i] for i in indices])
            return geometry.rows([box], [sum(p.areas_px[i] for i in indices)])[0]

        groups = fragment_groups(self.tracks, p.boxes_px, p.rows, p.track_of, union_row, self.reunite)
        if not groups:
            return
        drop = set()
        for group in groups:
            keep = group[0]
            box = union_box([p.boxes_px[i] for i in group])
            area = sum(p.areas_px[i] for i in group)
            row = geometry.rows([box], [area])[0]
            ground = self._grounds([box])[0]
            if row is None or ground is None:
                continue
            p.boxes_px[keep], p.areas_px[keep], p.rows[keep], p.grounds[keep] = box, area, row, ground
            for i in group[1:]:
                drop.add(i)
                if p.track_of[i] >= 0 and p.track_of[i] != p.track_of[keep]:
                    p.absorbed.append((p.track_of[i], keep))
            if p.track_of[keep] < 0:  # a group of new regions: the first's place in the order
                p.track_of[keep] = next((p.track_of[i] for i in group if p.track_of[i] >= 0), -1)
        kept = [i for i in range(len(p.boxes_px)) if i not in drop]
        new_index = {i: k for k, i in enumerate(kept)}
        p.absorbed = [(t, new_index[keep]) for t, keep in p.absorbed]
        for name in ("boxes_px", "areas_px", "rows", "grounds", "track_of"):
            values = getattr(p, name)
            setattr(p, name, [values[i] for i in kept])

    # ------------------------------------------------------------------ step 2
    def update(self, p: Prepared, probabilities: list[list[float]]) -> list[TrackView]:
        """Continue or start each region's track with its class probabilities; one view per region."""
        frame, tracks = self.frame, self.tracks
        seen = set()
        views_tracks: list[Track] = []
        for i, t in enumerate(p.track_of):
            row, proba = p.rows[i], probabilities[i]
            if t == STILL:
                views_tracks.append(None)
                continue
            if t >= 0:
                track = tracks[t]
                track.observe(frame, p.boxes_px[i], p.grounds[i], row, proba)
                seen.add(t)
            else:
                track = Track(self._next_id, frame, self.fps, list(p.boxes_px[i]), *p.grounds[i])
                self._next_id += 1
                track.start(p.boxes_px[i], p.grounds[i], row, proba)
                tracks.append(track)
                seen.add(len(tracks) - 1)
            self._judge(track)
            views_tracks.append(track)
        # (most frames join nothing: no comprehension to run for them)
        absorbed = {t: views_tracks[i].track_id for t, i in p.absorbed} if p.absorbed else {}
        survivors = []
        for t, track in enumerate(tracks):
            if t not in seen:
                track.missed += 1
                track.hit_bits = (track.hit_bits << 1) & self._mask
            if t in absorbed and t not in seen:
                track.merged_into = absorbed[t]
                self._end(track)
            elif track.missed > self._surely_kept_frames and track.missed > self._missed_limit(track):
                self._end(track)
            else:
                survivors.append(track)
        self.tracks = survivors
        if STILL in p.track_of:  # still regions: views of no track
            return [self._view(t) if t is not None else self._still_view(p.grounds[i]) for i, t in enumerate(views_tracks)]
        return list(map(self._view, views_tracks))

    def age(self) -> None:
        """A frame with no region to classify: every track missed."""
        self.frame += 1
        if not self.tracks:
            return
        mask = self._mask
        survivors = []
        for track in self.tracks:
            track.missed += 1
            track.hit_bits = (track.hit_bits << 1) & mask
            if track.missed > self._surely_kept_frames and track.missed > self._missed_limit(track):
                self._end(track)
            else:
                survivors.append(track)
        self.tracks = survivors

    def _missed_limit(self, track: Track) -> int:
        """Frames a track may go unseen: longer for a target that stood still (see the module docstring)."""
        # the fading region of an absorbed still body moves its box: "stood" means within a second
        last, fps = track.last_frame, self.fps
        stood = track.target_frames and track.still_frame is not None and last - track.still_frame <= fps
        # stalled at the bottom edge is leaving the view under the camera, not standing
        left = track.exit_frame is not None and last - track.exit_frame <= fps
        return self.still_hold_frames if stood and not left else self.max_missed_frames

    def _judge(self, track: Track) -> None:
        limits = self.limits
        note_acceleration(track, limits)
        if self.footprint is not None:  # a steep camera: a piece inside its body's outline is no jump
            track.shift_share = piece_shift_share(track)
            note_footprint(track, self.footprint.footprints)
        note_jump(track, limits)
        note_heading(track, limits)
        speed = track.speed_mps
        if speed is not None and speed < limits.still_mps:
            track.still_frame = track.last_frame
        _, y, _, h = track.box_px
        if y + h >= self.exit_row_px:
            track.exit_frame = track.last_frame
        track.pooled = pooled = track.pooled_probabilities(self.pooling)
        track.p_target = 1.0 - pooled[self.noise_col]
        # the likeliest target class over its life (the first of equals, as max takes it)
        track.cls = self.class_names[max(self._target_cols, key=track.log_sums.__getitem__)]
        if self.footprint is None:
            reason = reject_reason(track, limits)
            if reason is None and track.p_target < self.target_threshold:
                reason = "classified noise"
        else:
            reason = self._steep_reason(track)
        if reason in PASSING_DOUBTS and track.target_frames >= ESTABLISHED_TARGET_S * self.fps \
                and track.p_target >= ESTABLISHED_MIN_P:  # fmt: skip
            reason = None
        # a steady vehicle's motion outweighs frames that look like noise (a car's headlight spot)
        if reason is not None:
            speed_mps = overriding_speed_mps(track, reason, self.motion)
            if speed_mps is not None:
                reason = None
                track.cls = motion_class(speed_mps, track.cls, self.motion)
        track.reason = reason
        track.target = reason is None
        track.hit_bits = ((track.hit_bits << 1) | track.target) & self._mask
        if track.target:
            track.target_frames += 1
            track.target_classes[track.cls] = track.target_classes.get(track.cls, 0) + 1
        else:
            track.reasons[reason] = track.reasons.get(reason, 0) + 1

    def _steep_reason(self, track: Track) -> str | None:
        """A steep camera's judgement on the ground (``steep``): the footprint for the upright-body
        size rules and the class, and whole-body frames for a pooled P(target) under the threshold."""
        tolerance, threshold = self.limits.size_tolerance, self.target_threshold
        reason = reject_reason(track, self.limits, lambda t: size_reason(t, tolerance))
        track.cls = footprint_class(track, self.class_names, tolerance)
        if reason is None and track.p_target < threshold and whole_frames(track, self.noise_col, threshold) < MIN_WHOLE_FRAMES:
            reason = "classified noise"
        return reason

    def _view(self, track: Track) -> TrackView:
        ground = self.ground
        x_m, y_m = ground.to_world(track.forward_m, track.right_m)
        velocity = track.velocity_mps
        if velocity is None:
            vx = vy = speed = None
        else:
            vx, vy = ground.velocity_to_world(*velocity)
            speed = math.hypot(*velocity)  # track.speed_mps without the property's second look-up
        cls = track.cls if track.target else "noise"
        return TrackView(track.track_id, cls, track.p_target, track.target, track.reason, x_m, y_m, vx, vy, speed)

    def _still_view(self, ground) -> TrackView:
        """A still region's view (``detector.ghosts``): no track, noise, where it stands."""
        x_m, y_m = self.ground.to_world(*ground)
        return TrackView(None, "noise", 0.0, False, STILL_REASON, x_m, y_m, None, None, None)

    def _end(self, track: Track) -> None:
        if self.keep_ended:
            self.ended.append(track)
