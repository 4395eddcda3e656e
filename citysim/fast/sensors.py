"""Fast mode's stand-ins for the detector and the threshold segmenter: no pixels, calibrated draws.

``FastSensors`` is a ``ControlContext.sensors``: camera controllers build their per-camera
``SensedDetector`` (the ``detector.detector.Detector`` interface they use: ``process``, ``is_target``,
``last_regions``, ``reset_background``, ``segmenter.automatic_learning_rate``, ``camera``,
``tracker.is_confirmed``, ``target_threshold``) or ``SensedSegmenter`` (the threshold baselines'
``apply`` / ``reset``) through it. The sense process (``citysim.fast.sense``) tells it the
agents and lamp levels of each frame (``observe``) and passes a ``SensedFrame`` where a frame
would be; each stand-in then draws what the real one would report from the ``SensorModel``.

Draws come from one generator per camera (the night's camera streams), in the order frames are
judged, so a seed gives the same detections bit for bit.
"""

from __future__ import annotations

import bisect
import math

import numpy as np

from citysim.config.kinds import DETECTOR_CLASSES
from citysim.fast.drawn import SensedTracker, drawn_detection
from citysim.fast.frame import SensedFrame
from citysim.fast.geometry import CameraGeometry, Candidates, LevelChanges, beam_id, beam_x_m
from citysim.fast.model import (
    BEAM,
    KINDS,
    LIT_LEVEL,
    SensorModel,
    background_age_bin,
    cell_of,
    nearest_in_view,
    threshold_conditions,
    threshold_key,
)
from citysim.fast.pairs import CandidatePairs, StepPairs
from citysim.fast.records import is_young
from citysim.fast.step_agents import StepAgents
from citysim.fast.steps import StepGeometries
from detector.detector import Detection
from detector.segment import SegmenterParams

_NO_INDICES = np.zeros(0, np.int64)
#: A hit standing more than this ahead of its road user (m) is its light's patch, not its body.
AHEAD_OF_BODY_M = 2.0


class FastSensors:
    """The sensor model applied to one night's agents: the factory camera controllers call."""

    #: detections are drawn from calibrated tables, which already hold what the real detector's
    #: track windows wait for (``citysim.control.track_windows``)
    drawn = True

    def __init__(self, model: SensorModel, street, rngs: list[np.random.Generator], fps: float):
        self.model = model
        self.geometry = CameraGeometry(street)
        self.frame_shapes = [(cam.height_px, cam.width_px) for cam in self.geometry.cameras]
        self.rngs = rngs
        self.fps = fps
        self.p_hit = model.p_hit_array()
        self.p_hit_flat: list[float] = self.p_hit.ravel().tolist()  # read per pair (``StepPairs.p_hit``)
        self.persistence = np.array([model.persistence.get(k, 0.0) for k in KINDS])
        self.persistence_list: list[float] = self.persistence.tolist()
        self.class_cdf = {k: np.cumsum(v).tolist() for k, v in model.class_given_hit.items()}
        self.area_samples = {k: np.sort(np.asarray(v, dtype=np.float64)) for k, v in model.area_fraction.items()}
        self._samples_by_key: dict[tuple, np.ndarray | None] = {}
        self.ahead_samples = {k: np.asarray(v, dtype=np.float64) for k, v in model.hit_ahead_m.items() if v}
        self.frame_k = -1
        self.agents: list = []
        self.any_agents = False  # bool(agents), kept: a replayed step's sequence answers it by a call
        #: ``agents[j]`` as sensing reads them, without a replayed step's snapshots made (``citysim.fast.step_agents``)
        self.step_agents = StepAgents(self.agents)
        self.levels = np.zeros(self.geometry.n_lamps)  # per lamp
        #: when the lamps' levels last changed: only the threshold baselines' segmenters read it, so
        #: it is kept (every observed frame) only once one of them is made
        self.changes: LevelChanges | None = None
        self.steps = StepGeometries(self.geometry, self.p_hit.shape)
        #: the agents' geometry this frame (``citysim.fast.steps``); ``cand`` its candidates
        self.step = self.steps.of([], None)
        self._boxes: dict[tuple[int, int], tuple[int, int, int, int]] = {}
        #: per ``cand`` matrix ("seen", "beam_seen"), this step: the pairs it marks, camera by camera
        self._pairs: dict[str, CandidatePairs] = {}
        self._step_pairs: StepPairs | None = None  # this step's candidate pairs as lists
        self._awake: list[bool] | None = None
        self._lamps_lit: list[int] | None = None  # ``lit`` of every lamp this frame, on first ask
        self._lit_levels: np.ndarray | None = None  # the levels it was read from

    def detectors(self, ctx, threshold: float) -> list[SensedDetector]:
        return [SensedDetector(self, i, threshold) for i in range(self.geometry.n)]

    def segmenters(self, ctx) -> list[SensedSegmenter]:
        self.changes = LevelChanges(self.geometry)
        return [SensedSegmenter(self, i) for i in range(self.geometry.n)]

    def observe(self, frame_k: int, agents: list, levels: np.ndarray, rows: tuple | None = None) -> None:
        """The agents and lamp levels of frame ``frame_k`` (before any camera of it is judged);
        ``rows``: where ``agents`` stand in a replayed chunk's columns (``TrafficReplay.rows_of``)."""
        self.frame_k = frame_k
        if agents is not self.agents:
            # an empty street has no candidates, whichever empty list the step gave
            if agents or self.agents:
                self.step = self.steps.of(agents, rows)
            self.agents = agents
            self.any_agents = bool(agents)
            self.step_agents = StepAgents(agents)
            self._boxes = {}
            self._pairs = {}
            self._step_pairs = None
            self._awake = None
        self.levels = levels
        if self.changes is not None:
            self.changes.update(frame_k / self.fps, levels)
        if levels is not self._lit_levels or levels.flags.writeable:
            self._lamps_lit = None  # a read-only array seen before (``LampStates``'): no level changed

    @property
    def cand(self) -> Candidates:
        """This step's candidates (``citysim.fast.geometry``)."""
        return self.step.cand

    def awake_cameras(self) -> list[bool]:
        """``cand.awake`` as a list, made once per step: the sense loop reads it per camera per frame."""
        if self._awake is None:
            self._awake = self.step.awake() if self.any_agents else [False] * self.geometry.n
        return self._awake

    def candidates_of(self, lamp_index: int) -> np.ndarray:
        """Indices of camera ``lamp_index``'s road-user candidates this frame."""
        return self._indices_seen("seen", lamp_index)

    def beams_of(self, lamp_index: int) -> np.ndarray:
        """Indices of camera ``lamp_index``'s beam candidates this frame (``citysim.fast.geometry``)."""
        if not self.any_agents or not self.step_pairs().beams:  # most steps: no beam in any camera's view
            return _NO_INDICES
        return self._indices_seen("beam_seen", lamp_index)

    def _indices_seen(self, matrix: str, lamp_index: int) -> np.ndarray:
        """The candidates ``cand.<matrix>`` marks for camera ``lamp_index`` (ascending)."""
        if not self.any_agents:
            return _NO_INDICES
        return self.pairs(matrix).of(lamp_index)

    def pairs(self, matrix: str) -> CandidatePairs:
        """The (agent, camera) pairs ``cand.<matrix>`` marks this step, as index arrays: every
        camera's found in one pass once a step."""
        pairs = self._pairs.get(matrix)
        if pairs is None:
            pairs = self._pairs[matrix] = CandidatePairs(getattr(self.cand, matrix), self.geometry.n)
        return pairs

    def step_pairs(self) -> StepPairs:
        """This step's candidates ("seen" pairs) of every camera as lists (``citysim.fast.pairs``)."""
        if self._step_pairs is None:
            self._step_pairs = self.step.pairs(self.p_hit.shape)
        return self._step_pairs

    def box_px(self, lamp_index: int, agent_index: int) -> tuple[int, int, int, int]:
        """Agent ``agent_index``'s box in camera ``lamp_index`` this frame; the first ask projects
        all the camera's candidates at once (a box is asked for a hit, and for every candidate when
        the frame's truth is scored)."""
        key = (lamp_index, agent_index)
        if key not in self._boxes:
            pairs = self.step_pairs()
            first, end = pairs.bounds(lamp_index)
            idx = pairs.agents[first:end]
            if agent_index not in idx:
                idx = [agent_index]
            for j, box in zip(idx, self.geometry.boxes_px(lamp_index, [self.step_agents[j] for j in idx]), strict=True):
                self._boxes[(lamp_index, j)] = box
        return self._boxes[key]

    def area_samples_of(self, kind: int, forward_m: float, lit: bool, age_bin: int, far_s: float) -> np.ndarray | None:
        """The area samples of the first of a frame's ``threshold_conditions`` calibration saw (None:
        none), looked up once per ``threshold_key``."""
        key = threshold_key(kind, forward_m, lit, age_bin, far_s)
        if key not in self._samples_by_key:
            conditions = threshold_conditions(kind, forward_m, lit, age_bin, far_s)
            self._samples_by_key[key] = next((self.area_samples[c] for c in conditions if c in self.area_samples), None)
        return self._samples_by_key[key]

    def lit(self, lamp_index: int) -> int:
        """1 when lamp ``lamp_index`` is lit this frame, else 0 (every lamp's read once per frame)."""
        return self.lamps_lit()[lamp_index]

    def lamps_lit(self) -> list[int]:
        """``lit`` of every lamp this frame (its light bin: the level as float64 against ``LIT_LEVEL``)."""
        if self._lamps_lit is None:
            self._lamps_lit = (np.asarray(self.levels, dtype=np.float64) >= LIT_LEVEL).astype(int).tolist()
            self._lit_levels = self.levels
        return self._lamps_lit


class _LearningRate:
    """The segmenter attribute camera controllers read: MOG2's automatic learning rate."""

    def __init__(self, fps: float):
        self.history_frames = SegmenterParams().history_frames(fps)

    def automatic_learning_rate(self, frames_before: int) -> float:
        if frames_before <= 0:
            return 1.0
        return 1.0 / min(2 * (frames_before + 1), self.history_frames)

    def reset(self) -> None:
        """Nothing to forget: a young background shows in the learning rate fast mode is given."""


class SensedDetector:
    """One camera's detector in fast mode: per judged frame, calibrated target draws per candidate
    (a Markov chain per candidate: misses come in streaks) and false-alarm episodes."""

    def __init__(self, sensors: FastSensors, lamp_index: int, threshold: float):
        self.sensors = sensors
        self.lamp_index = lamp_index
        self.camera = sensors.geometry.cameras[lamp_index]
        self.target_threshold = float(threshold)
        self.segmenter = _LearningRate(sensors.fps)
        self.tracker = SensedTracker()
        self.rng = sensors.rngs[lamp_index]
        self.last_regions: tuple = ()
        #: ``Detector.motion_in_band``: a drawn frame's regions are all within range, so whether it
        #: has any (a plain attribute: the sense loop reads every camera's every frame)
        self.motion_in_band = False
        self.previous: dict[int, tuple[int, bool]] = {}  # object id -> (frame, hit)
        self.fa_left = 0
        self.fa_may_start = bool(sensors.model.fa_reports)  # else ``_false_alarm`` draws nothing, reports nothing
        self.fa_report: tuple | None = None
        self.fa_track = 0

    def reset_background(self) -> None:
        self.segmenter.reset()

    def is_target(self, detections) -> bool:
        return any(d.p_target >= self.target_threshold for d in detections)

    def process(self, frame: SensedFrame, learning_rate: float | None = None) -> list[Detection]:
        s, i, k = self.sensors, self.lamp_index, self.sensors.frame_k
        lamps_lit = s.lamps_lit()
        detections: list[Detection] = []
        seen = has_beams = False
        if s.any_agents:  # else an empty street: no candidate, no beam
            pairs = s._step_pairs or s.step_pairs()
            seen = pairs.counts[i] > 0
            if seen:
                detections = self._candidates(k, is_young(learning_rate), lamps_lit)
            if pairs.beams:  # most steps: no beam in any camera's view
                beams = s.beams_of(i)
                has_beams = len(beams) > 0
                if has_beams:
                    detections += self._beams(beams, k, is_young(learning_rate))
        lit = lamps_lit[s.geometry.camera_lamps[i]]  # the light of the pole camera i hangs on
        if self.fa_left == 0 and self.fa_may_start and self.rng.random() < s.model.fa_start_p[lit]:
            self._start_false_alarm()
        fa = self._false_alarm(k) if self.fa_left else None
        if fa is not None:
            detections.append(fa)
        busy = seen or has_beams or fa is not None or self.rng.random() < s.model.p_regions_idle[lit]
        self.last_regions = (True,) if busy else ()
        self.motion_in_band = bool(busy)
        return detections

    def _candidates(self, k: int, young: bool, lamps_lit: list[int]) -> list[Detection]:
        """Frame ``k``'s draws for the camera's candidates (``young``: its background is young;
        ``lamps_lit``: ``FastSensors.lamps_lit``)."""
        s, i = self.sensors, self.lamp_index
        pairs = s.step_pairs()
        first, end = pairs.bounds(i)
        idx = pairs.agents[first:end]
        step_agents, persistence = s.step_agents, s.persistence_list
        agents = [step_agents[j] for j in idx]
        p = pairs.p_hit(i, s.p_hit_flat, lamps_lit, young)
        rho = [persistence[kind] for kind in pairs.kind[first:end]]
        hits = self._chain_draws([a.object_id for a in agents], p, rho, k)
        out = []
        if True in hits:  # most frames with someone in view: no hit
            fwd = pairs.forward_m
            out = [self._hit_detection(a, idx[n], fwd[first + n], self._drawn_class(a.cls))
                   for n, a in enumerate(agents) if hits[n]]  # fmt: skip
        if len(self.previous) > 512:
            self.previous = {o: v for o, v in self.previous.items() if k - v[0] <= 1}
        return out

    def _chain_draws(self, keys: list[int], p: list[float], rho: list[float], k: int) -> list[bool]:
        """Frame ``k``'s hits of the candidates ``keys`` (object or beam ids): each a two-state chain
        with the cell's P and its kind's persistence ``rho``, stepped from the last frame's draw;
        every draw is kept for the next frame and told to the k-of-n tracker. Plain floats: the
        same IEEE operations numpy's float64 did, a tenth of the cost on a frame's few candidates."""
        previous, k_before = self.previous, k - 1
        for n, key in enumerate(keys):
            prev = previous.get(key)
            if prev is not None and prev[0] == k_before:  # the chain's step from the last frame's draw
                p[n] = p[n] + rho[n] * (1.0 - p[n]) if prev[1] else p[n] * (1.0 - rho[n])
        hits = []
        for key, draw, p_hit in zip(keys, self.rng.random(len(keys)).tolist(), p, strict=True):
            hit = draw < p_hit
            previous[key] = (k, hit)
            hits.append(hit)
        self.tracker.update_all(k, keys, hits)
        return hits

    def _drawn_class(self, kind: str) -> str:
        """The detector class a hit of ``kind`` is reported as, drawn from calibration's shares."""
        cdf = self.sensors.class_cdf.get(kind)  # bisect_right on a sorted list: searchsorted(side="right")
        return DETECTOR_CLASSES[bisect.bisect_right(cdf, self.rng.random()) if cdf is not None else 0]

    def _hit_detection(self, agent, agent_index: int, forward_m: float, cls: str) -> Detection:
        """A hit where the real detector puts it: on the road user's body, or (a sample of how far
        ahead calibration found its hits) on the patch its light throws ahead, as a car going away
        is seen by its headlights' spot; where it stands decides the zones a located track lights."""
        s = self.sensors
        samples = s.ahead_samples.get(agent.cls)
        ahead_m = float(samples[int(self.rng.integers(len(samples)))]) if samples is not None else 0.0
        if ahead_m < AHEAD_OF_BODY_M:
            return drawn_detection(s.box_px(self.lamp_index, agent_index), forward_m, cls, agent.object_id)
        box = s.geometry.beam_box_px(self.lamp_index, agent, ahead_m)
        return drawn_detection(box, forward_m + ahead_m, cls, agent.object_id)

    def _beams(self, idx: np.ndarray, k: int, young: bool) -> list[Detection]:
        """Draws for the beams of road users out of view (kind ``BEAM``, each its own chain and
        track), reported where the light is: the patch at the beam's middle."""
        s, i, kind = self.sensors, self.lamp_index, KINDS.index(BEAM)
        agents = [s.step_agents[j] for j in idx.tolist()]
        fwd = s.cand.beam_forward_m[idx, i]
        light = s.geometry.light_at(np.array([beam_x_m(a) for a in agents]), s.levels)
        cells = cell_of(np.full(len(agents), kind), fwd, s.cand.beam_bearing_rad[idx, i], light,
                        np.full(len(agents), young), np.array([a.speed_mps for a in agents]))  # fmt: skip
        keys = [beam_id(a.object_id) for a in agents]
        hits = self._chain_draws(keys, s.p_hit[cells].tolist(), [float(s.persistence[kind])] * len(agents), k)
        return [drawn_detection(s.geometry.beam_box_px(i, a), float(fwd[n]), self._drawn_class(BEAM), keys[n])
                for n, a in enumerate(agents) if hits[n]]  # fmt: skip

    def _start_false_alarm(self) -> None:
        """A false-alarm episode starts: its length (frames) and report drawn from calibration's."""
        model = self.sensors.model
        lengths = model.fa_length_frames
        self.fa_left = int(lengths[int(self.rng.integers(len(lengths)))])
        self.fa_report = tuple(model.fa_reports[int(self.rng.integers(len(model.fa_reports)))])
        self.fa_track -= 1  # negative ids: never an agent's

    def _false_alarm(self, k: int) -> Detection | None:
        """Frame ``k``'s report of the running false-alarm episode (None once it has ended)."""
        if self.fa_left == 0:
            return None
        self.fa_left -= 1
        distance_m, x, y, w, h, cls = self.fa_report
        self.tracker.update(k, self.fa_track, True)
        return drawn_detection((int(x), int(y), int(w), int(h)), distance_m, DETECTOR_CLASSES[int(cls)], self.fa_track)


class _Areas:
    """The part of ``detector.segment.Regions`` the threshold baselines read."""

    def __init__(self, areas_px: np.ndarray):
        self.areas_px = areas_px

    def __len__(self) -> int:
        return len(self.areas_px)


class SensedSegmenter(_LearningRate):
    """One camera's whole-frame segmenter for the threshold baselines: per judged frame, the
    largest region's share of the frame drawn from calibration frames of the same condition."""

    def __init__(self, sensors: FastSensors, lamp_index: int):
        super().__init__(sensors.fps)
        self.sensors = sensors
        self.lamp_index = lamp_index
        self.rng = sensors.rngs[lamp_index]
        self.last_frame_k = -2
        self.rank = 0.0

    def reset(self) -> None:
        """A rebuilt background starts a new episode (its young frames have samples of their own)."""
        self.last_frame_k = -2

    def apply(self, frame: SensedFrame, learning_rate: float | None = None) -> _Areas:
        s, i = self.sensors, self.lamp_index
        idx, beams = s.candidates_of(i), s.beams_of(i)
        if len(idx) or len(beams):
            kind, forward_m = nearest_in_view(np.array([KINDS.index(s.step_agents[j].cls) for j in idx.tolist()]),
                                              s.cand.forward_m[idx, i], s.cand.beam_forward_m[beams, i])
        else:  # nothing in view: what nearest_in_view says of no candidate and no beam
            kind, forward_m = -1, math.nan
        far_s = s.changes.far_change_age_s(i, s.frame_k / s.fps) if kind < 0 else math.inf
        samples = s.area_samples_of(kind, forward_m, bool(s.lit(s.geometry.camera_lamps[i])), background_age_bin(learning_rate), far_s)
        # the frame's rank among its condition's (sorted) samples: kept from the last judged frame
        # with the model's persistence, so a big region lasts an episode as in the real frames
        if not (s.frame_k == self.last_frame_k + 1 and self.rng.random() < s.model.area_persistence):
            self.rank = self.rng.random()
        self.last_frame_k = s.frame_k
        if samples is None or not len(samples):
            return _Areas(np.zeros(0))
        fraction = float(samples[min(int(self.rank * len(samples)), len(samples) - 1)])
        n_px = frame.shape[0] * frame.shape[1]
        return _Areas(np.array([fraction * n_px]) if fraction > 0 else np.zeros(0))
