"""Calibration records: what the real detector did with every candidate of every judged frame.

A calibration run is an ordinary full-fidelity run (rendered frames, the real detector) of a
camera controller whose detectors are wrapped by ``RecordingSensors`` (each judged frame's
learning rate and detections are kept, and the threshold baselines' whole-frame segmenter is
run on the same frame) and with ``CalibrationRecorder`` among the collectors. The recorder
matches the detector's target detections to the renderer's truth boxes (IoU >= 0.3, greedy, as
``citysim.metrics.confusion`` does; an unmatched one standing on the ground near a candidate,
3 m, or 20 m for one carrying a light, is that candidate's) and writes one row per candidate (``citysim.fast.geometry``)
and one per judged frame: the columns ``citysim.fast.model.fit_sensor_model`` reads.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from citysim.config.kinds import DETECTOR_CLASSES
from citysim.control.track_windows import (
    PAPER_K,
    PAPER_N,
    TrackWindows,
    frame_hit,
    keyed_marks,
)
from citysim.fast.geometry import CameraGeometry, LevelChanges, beam_id, beam_x_m
from citysim.fast.model import (
    BEAM,
    DECISION_SETS,
    KINDS,
    YOUNG_FRAMES,
    background_age_bin,
    nearest_in_view,
)
from citysim.metrics.collector import Collector
from citysim.metrics.confusion import greedy_match, iou_matrix
from citysim.world.agents import AgentState
from citysim.world.placement import agents_in_world

IOU_MATCH = 0.3
#: A target detection matching no truth box whose ground point is this near a candidate is that
#: candidate's (its own light spot, a shadow, a part cut off), m; for an agent carrying a light
#: (headlights, a flashlight) its beam on the ground reaches farther.
NEAR_M = 3.0
LIT_REACH_M = 20.0
#: Half the width of a beam on the ground ahead of a road user out of view, m: dipped headlights
#: light about the lane they drive in and the next (2 x 3.5 m lanes, plus the verge).
BEAM_HALF_WIDTH_M = 4.0
#: The detector's decisions recorded per candidate and judged frame, by column prefix: each frame's
#: own ("": ``detector``, ``detector_confirmed`` per frame), its track's ("track_":
#: ``detector_tracked``, ``detector_located``), and a frame's own while its track is plausible and
#: its k-of-n window full ("plausible_": ``detector_confirmed`` per track). Fast mode draws each
#: controller's hits from the fit of its own decisions (``SensorModel.for_decisions``).
DECISION_PREFIXES = ("", *(f"{name}_" for name in DECISION_SETS))
ROW_COLUMNS = ("camera", "frame", "object_id", "kind", "forward_m", "bearing_rad", "speed_mps", "light", "young",
               *(f"{p}{c}" for p in DECISION_PREFIXES for c in ("hit", "det_class", "hit_ahead_m")))  # fmt: skip
FRAME_COLUMNS = ("camera", "frame", "light", "has_candidates", "regions", "near_kind", "near_forward_m",
                 "area_fraction", "age_bin", "far_change_s",
                 *(f"{p}{c}" for p in DECISION_PREFIXES for c in ("fa", "fa_distance_m", "fa_box", "fa_class")))  # fmt: skip


def is_young(learning_rate: float | None) -> bool:
    """Whether MOG2's automatic rate says its background is younger than ``YOUNG_FRAMES`` frames."""
    return learning_rate is None or learning_rate >= 1.0 / (2 * (YOUNG_FRAMES + 1))


class RecordingDetector:
    """A real ``detector.detector.Detector`` that keeps what it saw, plus a whole-frame threshold segmenter."""

    def __init__(self, detector, threshold_segmenter):
        self.inner = detector
        self.threshold_segmenter = threshold_segmenter
        self.last_rate: float | None = None
        self.last_detections: list = []
        self.last_area_fraction = 0.0

    def __getattr__(self, name):  # camera, segmenter, tracker, last_regions, target_threshold...
        return getattr(self.inner, name)

    def reset_background(self) -> None:
        self.inner.reset_background()
        self.threshold_segmenter.reset()

    def is_target(self, detections) -> bool:
        return self.inner.is_target(detections)

    def process(self, image: np.ndarray, learning_rate: float | None = None) -> list:
        self.last_rate = learning_rate
        self.last_detections = self.inner.process(image, learning_rate)
        regions = self.threshold_segmenter.apply(image, learning_rate)
        n_px = image.shape[0] * image.shape[1]
        self.last_area_fraction = float(regions.areas_px.max()) / n_px if len(regions.areas_px) else 0.0
        return self.last_detections


class RecordingSensors:
    """``ControlContext.sensors`` for a calibration run: real detectors, recorded."""

    def __init__(self):
        self.detectors_made: list[RecordingDetector] = []

    def detectors(self, ctx, threshold: float) -> list[RecordingDetector]:
        from detector.detector import Detector
        from detector.general_model import default_model
        from detector.segment import Segmenter, SegmenterParams

        model = default_model()
        fps = 1.0 / ctx.frame_period_s
        self.detectors_made = [
            RecordingDetector(Detector(site.camera, model=model, target_threshold=threshold),
                              Segmenter(SegmenterParams(), fps=fps))
            for site in ctx.street.cameras  # every camera (two per pole with backward cameras)
        ]  # fmt: skip
        return self.detectors_made

    def segmenters(self, ctx):
        raise ValueError("calibration records a detector controller, not a threshold baseline")


class StreetWatch(Collector):
    """What every calibration recorder keeps of the street each step: the agents, the lamps' levels
    and when they changed, and each camera's candidates (``in_view``)."""

    def __init__(self, geometry: CameraGeometry, fps: float):
        self.geometry = geometry
        self.fps = fps
        self.agents: list[AgentState] = []
        self.world_agents: list[AgentState] = []
        self.levels = np.zeros(geometry.n_lamps)  # per lamp
        self.changes = LevelChanges(geometry)
        self._placed = None

    def on_step(self, t_s: float, agents: Sequence[AgentState], levels: np.ndarray) -> None:
        self.agents = list(agents)
        self.world_agents = agents_in_world(self.geometry.line, self.agents)  # where the cameras see them
        self.levels = np.asarray(levels, dtype=np.float64).copy()
        self.changes.update(t_s, self.levels)
        self._placed = None

    def _candidates(self):
        if self._placed is None:
            cand = self.geometry.candidates(self.agents)
            xs = np.array([a.x_m for a in self.agents], dtype=np.float64)
            self._placed = (cand, self.geometry.light_at(xs, self.levels) if len(xs) else xs)
        return self._placed

    def in_view(self, lamp_index: int) -> tuple[np.ndarray, int, float]:
        """Camera ``lamp_index``'s candidates this frame (indices into the step's agents) and the
        subject of its threshold condition (``nearest_in_view``: KINDS index, forward m)."""
        cand, _ = self._candidates()
        idx = np.flatnonzero(cand.seen[:, lamp_index]) if len(self.agents) else np.zeros(0, int)
        beams = np.flatnonzero(cand.beam_seen[:, lamp_index]) if len(self.agents) else idx
        kinds = np.array([KINDS.index(self.agents[j].cls) for j in idx.tolist()])
        return (idx, *nearest_in_view(kinds, cand.forward_m[idx, lamp_index], cand.beam_forward_m[beams, lamp_index]))


class CalibrationRecorder(StreetWatch):
    """Collector of a detector's calibration run: candidate rows and judged-frame rows (column lists)."""

    def __init__(self, geometry: CameraGeometry, sensors: RecordingSensors, fps: float, target_threshold: float = 0.5):
        super().__init__(geometry, fps)
        self.sensors = sensors
        self.target_threshold = target_threshold
        self.rows: dict[str, list] = {c: [] for c in ROW_COLUMNS}
        self.frames: dict[str, list] = {c: [] for c in FRAME_COLUMNS}
        # each camera's tracks' sightings and windows, kept as detector_confirmed keeps them
        self.windows = [TrackWindows(PAPER_K, PAPER_N, full_window=True) for _ in range(geometry.n)]

    def on_frame(self, lamp_index: int, t_s: float, truth: Sequence, detections: Sequence | None) -> None:
        if detections is None:
            return  # not judged (the light in view was changing)
        recorded = self.sensors.detectors_made[lamp_index]
        frame = int(round(t_s * self.fps))
        cand, light = self._candidates()
        idx, near_kind, near_forward_m = self.in_view(lamp_index)
        decided = {prefix: self._decided(lamp_index, idx, truth, targets)
                   for prefix, targets in self._targets(lamp_index, detections).items()}  # fmt: skip
        young = is_young(recorded.last_rate)
        for a_i in idx.tolist():
            agent = self.agents[a_i]
            row = {"camera": lamp_index, "frame": frame, "object_id": agent.object_id, "kind": KINDS.index(agent.cls),
                   "forward_m": cand.forward_m[a_i, lamp_index], "bearing_rad": cand.bearing_rad[a_i, lamp_index],
                   "speed_mps": agent.speed_mps, "light": light[a_i], "young": young}  # fmt: skip
            self._add_row({**row, **_decision_values(decided, agent.object_id)})
        self._beam_rows(lamp_index, frame, cand, young, decided)
        values = {"camera": lamp_index, "frame": frame, "light": float(self.levels[self.geometry.camera_lamps[lamp_index]]),
                  "has_candidates": len(idx) > 0, "regions": len(recorded.inner.last_regions) > 0,
                  "near_kind": near_kind, "near_forward_m": near_forward_m,
                  "area_fraction": recorded.last_area_fraction, "age_bin": background_age_bin(recorded.last_rate),
                  "far_change_s": self.changes.far_change_age_s(lamp_index, t_s)}  # fmt: skip
        for prefix, (_, fa, _) in decided.items():
            values.update(zip((f"{prefix}{c}" for c in ("fa", "fa_distance_m", "fa_box", "fa_class")), _fa_values(fa),
                              strict=True))  # fmt: skip
        for col in FRAME_COLUMNS:
            self.frames[col].append(values[col])

    def _targets(self, lamp_index: int, detections: Sequence) -> dict[str, list]:
        """This frame's target detections under each decision set (``DECISION_PREFIXES``)."""
        threshold, window = self.target_threshold, self.windows[lamp_index]
        keys, marks = keyed_marks(detections, threshold, window)
        window.update(marks)
        return {"": [d for d in detections if d.p_target >= threshold],
                "track_": [d for d in detections if _track_target(d, threshold)],
                "plausible_": [d for d, key in zip(detections, keys, strict=True)
                               if marks.get(key) and frame_hit(d, threshold) and window.seen_enough(key)]}  # fmt: skip

    def _decided(self, lamp_index: int, idx: np.ndarray, truth: Sequence, targets: list) -> tuple:
        """(candidate id -> detected class index, false alarms, candidate id -> m its hit stands ahead of it)."""
        hits, fa = self._match(truth, targets)
        ahead: dict[int, float] = {}
        fa = self._near_candidates(lamp_index, idx, hits, fa, ahead)
        return hits, fa, ahead

    def _near_candidates(self, lamp_index: int, idx: np.ndarray, hits: dict[int, int], fa: list,
                         ahead: dict[int, float] | None = None) -> list:  # fmt: skip
        """Unmatched target detections that stand on the ground near a candidate are that candidate's
        (a walker's light spot, a car's beam on the road ahead of it): a hit, not a false alarm;
        those in the beam of a road user out of view are nobody's false alarm either."""
        if not fa or not self.agents:
            return fa
        cam = self.geometry.cameras[lamp_index]
        left = []
        for d in fa:
            x, y, w, h = d.box_px
            ground = cam.pixel_to_ground(np.array([[x + w / 2 - 0.5, y + h - 0.5]], dtype=np.float64))[0]
            owner = None
            if np.all(np.isfinite(ground)):
                for a_i in idx.tolist():
                    agent = self.world_agents[a_i]
                    reach_m = LIT_REACH_M if agent.light_on else NEAR_M
                    if agent.object_id not in hits and math.hypot(ground[0] - agent.x_m, ground[1] - agent.y_m) <= reach_m:
                        owner = agent
                        break
            if owner is not None:
                hits[owner.object_id] = DETECTOR_CLASSES.index(d.cls)
                if ahead is not None:  # how far ahead of its road user the real detector puts it
                    ahead[owner.object_id] = _along_heading(owner, ground)[0]
                continue
            lighter = self._beam_owner(ground)
            if lighter is None:
                left.append(d)
            elif lighter.object_id not in hits:  # a candidate's second patch of light is just that
                hits.setdefault(beam_id(lighter.object_id), DETECTOR_CLASSES.index(d.cls))
        return left

    def _beam_owner(self, ground_m: np.ndarray) -> AgentState | None:
        """The road user carrying a light whose beam a detection standing at ``ground_m`` lies in (up to
        ``LIT_REACH_M`` ahead of it, ``BEAM_HALF_WIDTH_M`` either side), if any. A candidate's beam
        is its own (``_near_candidates``); a beam of a road user out of view (a car behind the camera
        lighting the road ahead of it) is that road user's *beam candidate*'s hit, not a false alarm:
        fast mode draws false alarms at random times, beams where the light is."""
        if not np.all(np.isfinite(ground_m)):
            return None
        for a in self.world_agents:
            if not a.light_on:
                continue
            ahead_m, across_m = _along_heading(a, ground_m)
            if 0.0 < ahead_m <= LIT_REACH_M and abs(across_m) <= BEAM_HALF_WIDTH_M:
                return a
        return None

    def _beam_rows(self, lamp_index: int, frame: int, cand, young: bool, decided: dict[str, tuple]) -> None:
        """One row per beam candidate of the camera (kind ``BEAM``, at its beam's middle); ``decided``
        per decision set as ``on_frame`` has it (a beam's hit stands on its beam: 0 m ahead)."""
        if not len(self.agents):
            return
        for a_i in np.flatnonzero(cand.beam_seen[:, lamp_index]).tolist():
            agent = self.agents[a_i]
            key = beam_id(agent.object_id)
            light = float(self.geometry.light_at(np.array([beam_x_m(agent)]), self.levels)[0])
            row = {"camera": lamp_index, "frame": frame, "object_id": key, "kind": KINDS.index(BEAM),
                   "forward_m": cand.beam_forward_m[a_i, lamp_index], "bearing_rad": cand.beam_bearing_rad[a_i, lamp_index],
                   "speed_mps": agent.speed_mps, "light": light, "young": young}  # fmt: skip
            self._add_row({**row, **_decision_values(decided, key)})

    def _add_row(self, row: dict) -> None:
        """One candidate row: a value for every column of ``ROW_COLUMNS``."""
        for col in ROW_COLUMNS:
            self.rows[col].append(row[col])

    def _match(self, truth: Sequence, targets: Sequence) -> tuple[dict[int, int], list]:
        """Truth object id -> detected class index of its target detection; unmatched target detections."""
        if not targets:
            return {}, []
        if not truth:
            return {}, targets
        iou = iou_matrix(np.array([(o.x, o.y, o.w, o.h) for o in truth]), np.array([d.box_px for d in targets]))
        pairs = greedy_match(iou, IOU_MATCH)
        matched = {c for _, c in pairs}
        hits = {truth[r].object_id: DETECTOR_CLASSES.index(targets[c].cls) for r, c in pairs}
        return hits, [d for j, d in enumerate(targets) if j not in matched]

    def columns(self) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
        rows = {c: np.asarray(v) for c, v in self.rows.items()}
        for c in ("camera", "frame", "object_id", "kind", *(f"{p}det_class" for p in DECISION_PREFIXES)):
            rows[c] = rows[c].astype(np.int64).reshape(-1)
        for c in ("forward_m", "bearing_rad", "speed_mps", "light", *(f"{p}hit_ahead_m" for p in DECISION_PREFIXES)):
            rows[c] = rows[c].astype(np.float64).reshape(-1)
        for c in ("young", *(f"{p}hit" for p in DECISION_PREFIXES)):
            rows[c] = rows[c].astype(bool).reshape(-1)
        frames = {c: np.asarray(v) for c, v in self.frames.items()}
        for c in (f"{p}fa_box" for p in DECISION_PREFIXES):
            frames[c] = frames[c].astype(np.float64).reshape(-1, 4)
        return rows, frames


def _decision_values(decided: dict[str, tuple], key: int) -> dict:
    """A candidate row's decision columns: per decision set (``DECISION_PREFIXES``), whether
    candidate ``key`` was hit, the class it was hit as (-1: not) and how far ahead of it the hit
    stood, m (0 unless recorded: its body, or a beam's own patch; NaN when not hit)."""
    values = {}
    for prefix, (hits, _, ahead) in decided.items():
        det_class = hits.get(key, -1)
        values.update({f"{prefix}hit": det_class >= 0, f"{prefix}det_class": det_class,
                       f"{prefix}hit_ahead_m": ahead.get(key, 0.0) if det_class >= 0 else np.nan})
    return values


def _along_heading(agent: AgentState, ground_m) -> tuple[float, float]:
    """Where the ground point ``ground_m`` (world x, y, m) lies from ``agent``: metres ahead along
    its heading, and across it (positive to its left)."""
    dx, dy = ground_m[0] - agent.x_m, ground_m[1] - agent.y_m
    cos_h, sin_h = math.cos(agent.heading_rad), math.sin(agent.heading_rad)
    return dx * cos_h + dy * sin_h, -dx * sin_h + dy * cos_h


def _track_target(detection, threshold: float) -> bool:
    """Whether a detection is a target by its track (``detector.detector.Detector.is_target`` with tracks):
    its track's decision, or its own P(target) where it carries no track."""
    if detection.track_p_target is not None:
        return bool(detection.track_target)
    return detection.p_target >= threshold


def _fa_values(fa: list) -> tuple:
    """A judged frame's false-alarm columns from its unmatched target detections (the first one)."""
    if not fa:
        return False, np.nan, (0, 0, 0, 0), -1
    first = fa[0]
    return True, float(first.features[3]), tuple(first.box_px), DETECTOR_CLASSES.index(first.cls)


def merge_columns(parts: Sequence[dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """Columns of several calibration runs as one; run i's frame numbers are shifted by i x 10^9 so
    frames of different runs are never consecutive (rows and frames of a run shift alike)."""
    shifted = [{**part, "frame": part["frame"] + i * 10**9} for i, part in enumerate(parts)]
    return {key: np.concatenate([p[key] for p in shifted]) for key in shifted[0]}
