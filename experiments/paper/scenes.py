"""The paper's test scenes A-D, filmed in the simulator and scored frame by frame.

``PAPER_SCENES`` maps the paper's scene letters (Table 2) to their replicas in
``scenarios/``. ``film_scene`` lets the scene's traffic fill the street
(``Budget.preroll_s``, physics only), then renders the scene's camera(s) with
every lamp held at its dim level (no controller: the paper filmed fixed
lighting), feeds every frame to the real detector (``detector.detector.Detector``
with ``default_model()``, ``max_distance_m`` = the scene's range) and, after
``Budget.warmup_s`` of frames that only train the background model, scores
each frame against the renderer's ground truth with ``score_frame``.

Matching: truth boxes and detection boxes (OpenCV ``(x, y, w, h)`` px) are
paired greedily by IoU >= 0.3 (``citysim.metrics.confusion``). A scored *row*
is either a detection (its truth class is that of the matched object, 'noise'
for animals and for detections matching nothing) or a *missed object*: a
target fully in view (``TruthObject.fully_visible``) within the scene's range
that no detection matched; it is scored as the detector's answer "nothing
here" (P(noise) = 1). Objects outside the range, cut by the frame border or
mostly hidden are never counted as misses (the paper's annotation range).
"""

from __future__ import annotations

import math
import time
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from citysim.config.scenario import Scenario, load_scenario
from citysim.metrics.confusion import greedy_match, iou_matrix
from citysim.render.camera import TruthObject
from citysim.sim.night import build_night
from detector.classes import CLASSES
from detector.detector import Detection, Detector
from detector.general_model import default_model
from detector.segment import Regions

SCENARIO_DIR = Path(__file__).resolve().parents[2] / "scenarios"
#: IoU a detection needs with a truth box to be that object (as ``DetectionConfusion``).
IOU_MATCH = 0.3
#: A noise detection lying this much (share of its own box) on a target's box is a *fragment*:
#: part of a target, or two merged, that IoU matching could not give to one object.
FRAGMENT_COVER = 0.5
#: P(target) at which the detector calls a region a target (``Detector.target_threshold``).
TARGET_THRESHOLD = 0.5
NOISE_ONE_HOT = np.eye(len(CLASSES))[CLASSES.index("noise")]


@dataclass(frozen=True)
class PaperScene:
    """One of the paper's scenes (Table 2) and the scenario file replicating it."""

    key: str
    scenario_file: Path
    time_of_day: str  # the paper's: 'night' (A-C) or 'day' (D)
    range_m: float  # Table 2 "objects distance": detector max_distance_m and the truth range
    title: str
    table2_counts: dict[str, int]  # annotated regions per class in the paper's dataset
    cameras: tuple[int, ...] = (0,)  # lamp indices whose cameras are filmed (the paper had one)

    def load(self) -> Scenario:
        scenario = load_scenario(self.scenario_file)
        if scenario.environment.time_of_day != self.time_of_day:
            raise ValueError(
                f"{self.scenario_file}: environment.time_of_day must be {self.time_of_day!r} "
                f"for paper scene {self.key}, got {scenario.environment.time_of_day!r}"
            )
        return scenario


def _counts(noise: int, pedestrian: int, group: int, cyclist: int, vehicle: int) -> dict[str, int]:
    return dict(zip(CLASSES, (noise, pedestrian, group, cyclist, vehicle), strict=True))


PAPER_SCENES: dict[str, PaperScene] = {
    "A": PaperScene("A", SCENARIO_DIR / "scene_a_parking_night.yaml", "night", 25.0,
                    "parking area 1, night", _counts(4575, 1364, 108, 335, 0)),
    "B": PaperScene("B", SCENARIO_DIR / "scene_b_parking_night.yaml", "night", 25.0,
                    "parking area 2, night", _counts(13724, 6705, 473, 134, 26)),
    "C": PaperScene("C", SCENARIO_DIR / "scene_c_city_street_night.yaml", "night", 50.0,
                    "city street, night", _counts(2474, 326, 218, 183, 238)),
    "D": PaperScene("D", SCENARIO_DIR / "scene_d_city_street_day.yaml", "day", 50.0,
                    "city street, day", _counts(2258, 1990, 928, 730, 398)),
}  # fmt: skip


@dataclass(frozen=True)
class Budget:
    """How much of a scene is filmed, s.

    Traffic runs alone for ``preroll_s`` (the street starts empty); the camera
    then films until the scenario's ``duration_s`` (or for ``warmup_s +
    scored_s`` when ``scored_s`` is given); its first ``warmup_s`` only train
    the background model and are not scored.
    """

    preroll_s: float = 60.0
    warmup_s: float = 5.0
    scored_s: float | None = None

    def __post_init__(self) -> None:
        for name in ("preroll_s", "warmup_s"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"Budget.{name}: must be >= 0 s, got {getattr(self, name)!r}")
        if self.scored_s is not None and not self.scored_s > 0:
            raise ValueError(f"Budget.scored_s: must be > 0 s or None, got {self.scored_s!r}")

    def filmed_s(self, scenario: Scenario) -> float:
        """Seconds of camera time (warm-up included) for ``scenario``."""
        if self.scored_s is not None:
            return self.warmup_s + self.scored_s
        filmed = scenario.duration_s - self.preroll_s
        if filmed <= self.warmup_s:
            raise ValueError(
                f"{scenario.name}: duration_s ({scenario.duration_s:g} s) leaves nothing to score after "
                f"{self.preroll_s:g} s of traffic pre-roll and {self.warmup_s:g} s of background warm-up"
            )
        return filmed


@dataclass
class SceneRecords:
    """Everything scored in one scene (or several pooled with ``extend``).

    Rows (detections and missed objects): ``truth_cls``, ``probabilities``
    (``CLASSES`` order), ``detected`` (False for a missed object),
    ``distance_m`` (the matched object's forward distance, NaN for noise
    matching nothing), ``fragment`` (a noise detection lying mostly on a
    target's box: ``FRAGMENT_COVER``). Threshold
    baseline (section 7), on the detector's own segmentation (every region,
    border ones too): ``target_area_frac`` per eligible target instance (the
    area of the region matching it / frame area, 0 if none), ``noise_area_frac``
    per region matching no object, and per frame the largest region's fraction
    with whether an eligible target / any target was in view. ``hits``:
    per (scene, camera, object) the (frame index, detected as target) of every
    frame it was eligible (eq. 12 check).
    """

    truth_cls: list[str] = field(default_factory=list)
    probabilities: list[np.ndarray] = field(default_factory=list)
    detected: list[bool] = field(default_factory=list)
    distance_m: list[float] = field(default_factory=list)
    fragment: list[bool] = field(default_factory=list)
    target_area_frac: list[float] = field(default_factory=list)
    noise_area_frac: list[float] = field(default_factory=list)
    frame_max_frac: list[float] = field(default_factory=list)
    frame_has_target: list[bool] = field(default_factory=list)
    frame_target_free: list[bool] = field(default_factory=list)
    hits: dict[tuple[str, int, int], list[tuple[int, bool]]] = field(default_factory=dict)
    row_track: list[tuple[str, int, int] | None] = field(default_factory=list)
    row_track_target: list[bool] = field(default_factory=list)
    row_plausible: list[bool] = field(default_factory=list)
    row_reason: list[str | None] = field(default_factory=list)
    object_rows: dict[tuple[str, int, int], list[int]] = field(default_factory=dict)
    truth_instances: Counter = field(default_factory=Counter)
    frames: int = 0
    detector_cpu_s: float = 0.0
    detector_wall_s: float = 0.0
    detector_frames: int = 0

    def extend(self, other: SceneRecords) -> SceneRecords:
        """Pool ``other`` into this one (returns self)."""
        offset = len(self.truth_cls)
        for key, rows in other.object_rows.items():
            self.object_rows[key] = [r + offset if r >= 0 else -1 for r in rows]
        for name in ("row_track", "row_track_target", "row_plausible", "row_reason", "truth_cls", "probabilities", "detected", "distance_m", "fragment", "target_area_frac", "noise_area_frac",
                     "frame_max_frac", "frame_has_target", "frame_target_free"):  # fmt: skip
            getattr(self, name).extend(getattr(other, name))
        self.hits.update(other.hits)
        self.truth_instances.update(other.truth_instances)
        self.frames += other.frames
        self.detector_cpu_s += other.detector_cpu_s
        self.detector_wall_s += other.detector_wall_s
        self.detector_frames += other.detector_frames
        return self

    @property
    def probability_matrix(self) -> np.ndarray:
        """(rows, 5) class probabilities in ``CLASSES`` order."""
        if not self.probabilities:
            return np.zeros((0, len(CLASSES)))
        return np.vstack(self.probabilities)


def _eligible(t: TruthObject, range_m: float) -> bool:
    """A target the detector must find: fully in view (not cut, at most half hidden) within range."""
    return t.cls in CLASSES[1:] and t.fully_visible and 0.0 < t.distance_m <= range_m


def _cover(box_px: Sequence[int], others_px: Sequence[Sequence[int]]) -> float:
    """Largest share of ``box_px``'s area that one of ``others_px`` covers (OpenCV rects, px)."""
    x, y, w, h = box_px
    best = 0.0
    for ox, oy, ow, oh in others_px:
        iw = min(x + w, ox + ow) - max(x, ox)
        ih = min(y + h, oy + oh) - max(y, oy)
        if iw > 0 and ih > 0:
            best = max(best, iw * ih / max(w * h, 1))
    return best


def score_frame(
    records: SceneRecords,
    truth: Sequence[TruthObject],
    detections: Sequence[Detection],
    regions: Regions,
    range_m: float,
    frame_px: int,
    key: tuple[str, int],
    frame_index: int,
) -> None:
    """Add one frame's rows to ``records`` (see the module docstring for the matching rules)."""
    truth_cls = [t.cls if t.cls in CLASSES else "noise" for t in truth]
    eligible = [_eligible(t, range_m) for t in truth]
    truth_boxes = [(t.x, t.y, t.w, t.h) for t in truth]
    pairs = greedy_match(iou_matrix(truth_boxes, [d.box_px for d in detections]), IOU_MATCH)
    det_of_truth = dict(pairs)
    truth_of_det = {c: r for r, c in pairs}
    target_boxes = [b for b, t in zip(truth_boxes, truth, strict=True) if t.cls in CLASSES[1:]]
    for c, d in enumerate(detections):
        r = truth_of_det.get(c)
        records.truth_cls.append("noise" if r is None else truth_cls[r])
        records.probabilities.append(np.asarray(d.probabilities, dtype=float))
        records.detected.append(True)
        records.distance_m.append(math.nan if r is None else truth[r].distance_m)
        records.fragment.append(r is None and _cover(d.box_px, target_boxes) >= FRAGMENT_COVER)
        records.row_track.append(None if d.track_id is None else (*key, d.track_id))
        records.row_track_target.append(bool(d.track_target))
        records.row_plausible.append(d.track_reason in (None, "classified noise"))
        records.row_reason.append(d.track_reason)
    first_row = len(records.truth_cls) - len(detections)
    for r, t in enumerate(truth):
        if not eligible[r]:
            continue
        records.truth_instances[t.cls] += 1
        c = det_of_truth.get(r)
        records.object_rows.setdefault((*key, t.object_id), []).append(-1 if c is None else first_row + c)
        if c is None:
            records.row_track.append(None)
            records.row_track_target.append(False)
            records.row_plausible.append(False)
            records.row_reason.append("not segmented")
            records.truth_cls.append(t.cls)
            records.probabilities.append(NOISE_ONE_HOT)
            records.detected.append(False)
            records.distance_m.append(t.distance_m)
            records.fragment.append(False)
        hit = c is not None and detections[c].p_target >= TARGET_THRESHOLD
        records.hits.setdefault((*key, t.object_id), []).append((frame_index, hit))

    # the naive baseline sees every segmented region (border ones too) by its contour area
    area_frac = np.asarray(regions.areas_px, dtype=float) / frame_px
    region_pairs = greedy_match(iou_matrix(truth_boxes, regions.boxes_px), IOU_MATCH)
    region_of_truth = dict(region_pairs)
    matched_regions = {c for _, c in region_pairs}
    for r in range(len(truth)):
        if eligible[r]:
            c = region_of_truth.get(r)
            records.target_area_frac.append(0.0 if c is None else float(area_frac[c]))
    records.noise_area_frac.extend(
        float(a) for c, a in enumerate(area_frac) if c not in matched_regions
    )
    records.frame_max_frac.append(float(area_frac.max()) if len(area_frac) else 0.0)
    records.frame_has_target.append(any(eligible))
    records.frame_target_free.append(not any(t.cls in CLASSES[1:] for t in truth))
    records.frames += 1


def film_scene(
    scene: PaperScene,
    budget: Budget,
    on_frame: Callable[[], None] | None = None,
    full_frame: bool = False,
) -> SceneRecords:
    """Film and score ``scene`` (see the module docstring); ``on_frame`` is called per camera frame.
    ``full_frame``: the detector segments the whole frame, not the band where a target within
    range can appear (``detector.roi``; the comparison that shows the band loses nothing)."""
    scenario = scene.load()
    night = build_night(scenario)
    for lamp in scene.cameras:
        if not 0 <= lamp < night.n_lamps:
            raise ValueError(
                f"paper scene {scene.key}: camera lamp {lamp} not in {scene.scenario_file} "
                f"(0..{night.n_lamps - 1})"
            )
    night.start_physics()
    model = default_model()
    renderers = night.renderers(scene.cameras)
    cams = [r.camera for r in renderers]
    detectors = [Detector(c, model=model, max_distance_m=scene.range_m, crop_to_range=not full_frame) for c in cams]
    levels = np.full(night.n_lamps, scenario.lamps.luminaire.dim_level)

    def advance(t_s: float) -> None:
        night.run_until(t_s + 1e-6)  # the physics tick at t_s included

    fps = cams[0].fps
    n_frames = int(round(budget.filmed_s(scenario) * fps))
    n_warm = int(round(budget.warmup_s * fps))
    records = SceneRecords()
    advance(budget.preroll_s)
    for k in range(n_frames):
        t_s = budget.preroll_s + k / fps
        advance(t_s)
        agents = night.agents
        for j, (renderer, det) in enumerate(zip(renderers, detectors, strict=True)):
            frame = renderer.render(t_s, agents, levels, frame_index=k)
            cpu0, wall0 = time.process_time(), time.perf_counter()
            detections = det.process(frame.image)
            cpu1, wall1 = time.process_time(), time.perf_counter()
            if k >= n_warm:
                records.detector_cpu_s += cpu1 - cpu0
                records.detector_wall_s += wall1 - wall0
                records.detector_frames += 1
                score_frame(records, frame.truth, detections, det.last_regions, scene.range_m,
                            frame.image.size, (scene.key, scene.cameras[j]), k)  # fmt: skip
            if on_frame is not None:
                on_frame()
    return records


def frames_to_film(scene: PaperScene, budget: Budget) -> int:
    """Camera frames ``film_scene`` will render for ``scene`` (for a progress bar)."""
    scenario = scene.load()
    fps = scenario.lamps.camera_model.fps
    return int(round(budget.filmed_s(scenario) * fps)) * len(scene.cameras)
