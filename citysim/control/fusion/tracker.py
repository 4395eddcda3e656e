"""Street tracks from every camera's measurements: predict, associate, update, be born, fade, merge.

One ``StreetTracker`` serves the whole street. Each judged camera frame (``observe``) brings that
camera's measurements (``citysim.control.fusion.measurement``): every track is predicted to the
frame's time (``kalman``), the measurements are associated (``association``: the detector's own
links, then gated Mahalanobis distance, which is the hand-over between cameras), associated tracks
are updated and their existence raised; a measurement no track explains starts a track whose
prior existence says whether a road user can appear there (``births``); every other track the
camera should have seen is made less likely and moved out of the stretch it sees (``negative``). A track is
dropped when its existence falls below ``existence.P_DROP``, when it leaves the street, or when its
position is so uncertain that it says nothing (``MAX_SIGMA_S_M``). Street coordinates throughout.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from citysim.control.fusion import existence, kalman
from citysim.control.fusion.association import GATE, associate
from citysim.control.fusion.births import BirthMap
from citysim.control.fusion.measurement import Measurement
from citysim.control.fusion.negative import missed
from citysim.control.fusion.street_frame import StreetFrame
from citysim.control.fusion.views import CameraViews

#: A track whose position along the street is this uncertain (one standard deviation, m) says nothing: dropped.
MAX_SIGMA_S_M = 40.0
#: Speed prior of a newborn track whose speed is unknown, one standard deviation, m/s (walkers go
#: either way at up to a jog; a car or bicycle off its lanes could go anywhere).
BIRTH_SIGMA_V_MPS = {"pedestrian": 1.5, "group": 1.2, "cyclist": 5.0, "vehicle": 10.0}
#: Standard deviation of a speed the detector or a lane gave, m/s.
KNOWN_SIGMA_V_MPS = 2.5
#: Two tracks closer than this (along, across the street, m; speeds along within the third, m/s) are one road user.
MERGE_M = (2.0, 1.5, 1.5)
#: The class a track keeps when its detections disagree: the one carried furthest (a car's glare
#: reads as a cyclist or a walker now and then, never a walker as a car for long).
CLASS_RANK = {"pedestrian": 0, "group": 1, "cyclist": 2, "vehicle": 3}


@dataclass
class StreetTrack:
    """One road user on the street: its state (s, d, v_s, v_d) as a Gaussian and its existence."""

    id: int
    cls: str
    mean: np.ndarray
    cov: np.ndarray
    t_s: float
    existence: float
    last_seen_s: float
    last_camera: int
    hits: int = 1
    keys: set = field(default_factory=set)

    @property
    def s_m(self) -> float:
        return float(self.mean[0])

    @property
    def sigma_s_m(self) -> float:
        return math.sqrt(max(float(self.cov[0, 0]), 0.0))


class StreetTracker:
    """Every camera's measurements fused into one set of street tracks.

    Parameters
    ----------
    frame : StreetFrame
        Ground <-> street coordinates.
    views : CameraViews
        What each camera sees (for negative information).
    births : BirthMap
        Where a road user can appear.
    lane_speed : callable (cls, d_m) -> float | None
        A newborn car's or bicycle's speed along the street from its lane (m/s), None if unknown.
    """

    def __init__(self, frame: StreetFrame, views: CameraViews, births: BirthMap,
                 lane_speed: Callable[[str, float], float | None] | None = None):  # fmt: skip
        self.frame, self.views, self.births = frame, views, births
        self.lane_speed = lane_speed or (lambda cls, d_m: None)
        self.tracks: list[StreetTrack] = []
        self.links: dict[tuple[int, int], int] = {}  # detector track key -> street track id
        self.next_id = 1

    def predict_to(self, t_s: float) -> None:
        """Every track's state at ``t_s`` (s; never backwards)."""
        for track in self.tracks:
            if t_s > track.t_s:
                track.mean, track.cov = kalman.predict(track.mean, track.cov, t_s - track.t_s, track.cls)
                track.t_s = t_s

    def observe(self, camera: int, t_s: float, measurements: Sequence[Measurement]) -> None:
        """One judged frame of camera ``camera`` at ``t_s`` with its ``measurements`` (maybe none)."""
        if not self.tracks and not measurements:
            return
        self.predict_to(t_s)
        pairs = associate(self.tracks, measurements, self.links)
        updated = set()
        for m_i, t_i in pairs.items():
            self._update(self.tracks[t_i], measurements[m_i], t_s)
            updated.add(t_i)
        seen_tracks = [self.tracks[i] for i in updated]
        for m_i, m in enumerate(measurements):
            if m_i not in pairs and not self._fragment(m, seen_tracks):
                self.tracks.append(self._born(m, t_s))
        for t_i, track in enumerate(self.tracks):
            if t_i in updated or track.last_seen_s == t_s:
                continue
            interval = self.views.interval_s(camera, track.s_m, float(track.mean[1]),
                                             math.sqrt(max(float(track.cov[1, 1]), 0.0)))
            if interval is not None:
                track.mean, track.cov, mass = missed(track.mean, track.cov, *interval, existence.p_detect(track.cls))
                track.existence = track.existence * mass / (1.0 - track.existence + track.existence * mass)
        self._merge()
        self._prune()

    def _update(self, track: StreetTrack, m: Measurement, t_s: float) -> None:
        track.mean, track.cov = kalman.update(track.mean, track.cov, m.z, m.cov_m2)
        track.existence = existence.after_hit(track.existence)
        track.last_seen_s, track.last_camera = t_s, m.camera
        track.hits += 1
        if CLASS_RANK.get(m.cls, 0) > CLASS_RANK.get(track.cls, 0):
            track.cls = m.cls
        if m.key is not None:
            track.keys.add(m.key)
            self.links[m.key] = track.id

    @staticmethod
    def _fragment(m: Measurement, tracks: Sequence[StreetTrack]) -> bool:
        """A measurement within the gate of a track this frame already updated: another piece of that road user."""
        return any(kalman.mahalanobis2(t.mean, t.cov, m.z, m.cov_m2) <= GATE for t in tracks)

    def _born(self, m: Measurement, t_s: float) -> StreetTrack:
        if m.vs_mps is not None:
            vs, sigma_v = m.vs_mps, KNOWN_SIGMA_V_MPS
        else:
            lane = self.lane_speed(m.cls, m.d_m)
            vs, sigma_v = (lane, KNOWN_SIGMA_V_MPS) if lane is not None else (0.0, BIRTH_SIGMA_V_MPS.get(m.cls, 3.0))
        cov = np.zeros((4, 4))
        cov[:2, :2] = m.cov_m2
        cov[2, 2] = sigma_v**2
        cov[3, 3] = min(sigma_v, 1.5) ** 2
        track = StreetTrack(self.next_id, m.cls, np.array([m.s_m, m.d_m, vs, 0.0]), cov, t_s,
                            self.births.prior(m.s_m), t_s, m.camera)  # fmt: skip
        if m.key is not None:
            track.keys.add(m.key)
            self.links[m.key] = track.id
        self.next_id += 1
        return track

    def _merge(self) -> None:
        """Two tracks on the same spot at the same speed are one road user: the likelier one stays."""
        if len(self.tracks) < 2:
            return
        ds, dd, dv = MERGE_M
        keep: list[StreetTrack] = []
        for track in sorted(self.tracks, key=lambda t: (-t.existence, t.id)):
            twin = next((k for k in keep if abs(k.mean[0] - track.mean[0]) < ds and abs(k.mean[1] - track.mean[1]) < dd
                         and abs(k.mean[2] - track.mean[2]) < dv), None)  # fmt: skip
            if twin is None:
                keep.append(track)
                continue
            twin.existence = max(twin.existence, track.existence)
            twin.hits += track.hits
            for key in track.keys:
                self.links[key] = twin.id
            twin.keys |= track.keys
        self.tracks = sorted(keep, key=lambda t: t.id)

    def _prune(self) -> None:
        alive = []
        for track in self.tracks:
            if (track.existence < existence.P_DROP or track.sigma_s_m > MAX_SIGMA_S_M
                    or not self.frame.on_street(track.s_m, margin_m=5.0)):  # fmt: skip
                for key in track.keys:
                    if self.links.get(key) == track.id:
                        del self.links[key]
                continue
            alive.append(track)
        self.tracks = alive

    def prune(self, t_s: float) -> None:
        """Predict to ``t_s`` and drop tracks that left the street or say nothing any more."""
        self.predict_to(t_s)
        self._prune()
