"""The sensor model: what the real detector reports about the agents a camera may see.

``fit_sensor_model`` fits it from calibration records (``citysim.fast.records``): hit
probabilities per candidate cell, their persistence, the class reported, false alarms, the
same on track and plausible-frame decisions, idle regions and the threshold baselines'
region sizes. Saved as JSON.

Design: docs/design/fast-mode-sensor-model.md
"""

from __future__ import annotations

import bisect
import json
import math
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path

import numpy as np

from citysim.config.kinds import AGENT_KINDS, DETECTOR_CLASSES

#: The pseudo-kind of a *beam candidate* (``citysim.fast.geometry``): the light a road user out of
#: a camera's view throws into it. Its own rows in every table: the real detector reports such a
#: patch of lit road as often as it does, and fast mode draws it where the light is.
BEAM = "beam"
KINDS = (*AGENT_KINDS, BEAM)
#: The detector class a beam's hits are given before calibration has seen any (the prior).
BEAM_PRIOR_CLASS = "vehicle"
#: Bin edges; a value falls in bin i when edges[i] <= value < edges[i + 1] (the last bin is open).
DISTANCE_EDGES_M = (0.0, 5.0, 8.0, 11.0, 14.0, 17.0, 20.0, 23.0, 26.0)
BEARING_EDGES_DEG = (0.0, 10.0, 20.0, 30.0)
SPEED_EDGES_MPS = (0.0, 0.5, 2.5, 6.0)
#: A lamp at or above this level counts as lit (the light bin).
LIT_LEVEL = 0.5
#: A background model younger than this many frames since its reset counts as young.
YOUNG_FRAMES = 15
PRIOR_FRAMES = 4.0
#: Sample lists are capped at this many values (a deterministic, evenly spaced subset).
MAX_SAMPLES = 2000
#: Background ages (frames since its reset) the threshold samples are kept apart by: a young
#: MOG2 model reports big foreground regions on its own, and how often a background is young
#: depends on how often the lamps in view switch, which differs between controllers.
AGE_EDGES_FRAMES = (0, 15, 90)
#: Bumped whenever the model's meaning changes, so cached models are refitted.
MODEL_VERSION = 14
#: The shares of the frame a threshold baseline triggers at (the paper's 5 % and 0.5 %): the
#: persistence of a big foreground region is fitted on how long it stays above these.
PERSISTENCE_FRACTIONS = (0.05, 0.005)
#: The persistence is capped below 1 so a drawn episode always ends.
MAX_AREA_PERSISTENCE = 0.99
#: Seconds since a lamp in a camera's far view changed level: the bins of recent changes (under
#: 5 s, 5-20 s); older changes count as none (calibration: 2 % of the frames with nothing in view
#: held a region over 0.5 % of the frame 20-40 s after the change, as without one).
FAR_CHANGE_EDGES_S = (5.0, 20.0)
#: The decision sets fitted beside each frame's own decisions, each a ``SensorModel`` field; their
#: record columns carry the set's name and '_' before the frame-level name (``citysim.fast.records``).
DECISION_SETS = ("track", "plausible")
#: The record columns each decision set's fit reads in place of the frame-level ones.
DECISION_COLUMNS = ("hit", "det_class", "hit_ahead_m", "fa", "fa_distance_m", "fa_box", "fa_class")
#: The fields ``SensorModel.track`` and ``SensorModel.plausible`` hold: those fitted again on their decisions.
TRACK_FIELDS = ("p_hit", "persistence", "class_given_hit", "hit_ahead_m", "fa_start_p", "fa_length_frames", "fa_reports",
                "fa_per_camera_hour")


def bin_of(values: np.ndarray, edges: tuple[float, ...]) -> np.ndarray:
    # the same integers as np.clip(..., 0, len(edges) - 1), at a third of its per-call cost
    below = np.searchsorted(np.asarray(edges), np.asarray(values, dtype=np.float64), side="right") - 1
    return np.minimum(np.maximum(below, 0), len(edges) - 1)


def cell_of(kind: np.ndarray, forward_m, bearing_rad, light, young, speed_mps) -> tuple[np.ndarray, ...]:
    """The p_hit cell indices (kind, distance, bearing, light, young, speed) of candidate rows."""
    return (np.asarray(kind, dtype=np.int64), bin_of(forward_m, DISTANCE_EDGES_M),
            bin_of(np.degrees(np.abs(bearing_rad)), BEARING_EDGES_DEG),
            (np.asarray(light) >= LIT_LEVEL).astype(np.int64), np.asarray(young, dtype=np.int64),
            bin_of(speed_mps, SPEED_EDGES_MPS))  # fmt: skip


def table_shape() -> tuple[int, ...]:
    return (len(KINDS), len(DISTANCE_EDGES_M), len(BEARING_EDGES_DEG), 2, 2, len(SPEED_EDGES_MPS))


def background_age_bin(learning_rate: float | None) -> int:
    """The ``AGE_EDGES_FRAMES`` bin of a background fed at MOG2's automatic ``learning_rate``
    (1 / min(2 (n + 1), history) after n frames; 1 for the first frame, None: unknown, young)."""
    if learning_rate is None or learning_rate >= 1.0:
        return 0
    frames_before = 0.5 / learning_rate - 1.0
    return scalar_bin_of(frames_before, AGE_EDGES_FRAMES)


def scalar_bin_of(value: float, edges: tuple[float, ...]) -> int:
    """``bin_of`` of one value, without numpy's per-call cost (asked once per judged frame)."""
    return min(max(bisect.bisect_right(edges, value) - 1, 0), len(edges) - 1)


def threshold_key(kind: int, forward_m: float, lit: bool, age_bin: int,
                  far_change_age_s: float = math.inf) -> tuple:  # fmt: skip
    """What a frame's ``threshold_conditions`` depend on: (kind, distance bin, lit, age bin, far
    change bin); frames of equal keys have the same conditions (fast mode looks them up once)."""
    if kind >= 0:
        return kind, scalar_bin_of(forward_m, DISTANCE_EDGES_M), lit, age_bin, None
    far = FAR_CHANGE_EDGES_S  # None: no far lamp changed level recently enough to matter
    return kind, None, lit, age_bin, (None if far_change_age_s >= far[-1]
                                      else bisect.bisect_right(far, far_change_age_s))


def threshold_conditions(kind: int, forward_m: float, lit: bool, age_bin: int,
                         far_change_age_s: float = math.inf) -> tuple[str, ...]:  # fmt: skip
    """The keys of the threshold samples of a frame, finest first (fast mode takes the first one
    calibration saw): the subject (the nearest candidate's kind and distance bin, or nothing in
    view, split by how long ago a lamp in the camera's far view changed level), the camera's own
    lamp lit or dim, the background's age bin; then without the age; then, for a candidate,
    without the light, and for a recent far change, nothing in view's keys. The light matters: in
    calibration a walker made a region over 0.5 % of the frame in 15 % of the frames under a lit
    lamp and in none under a dim one; so does a far lamp switching (its pool changes the top of
    the frame; see ``citysim.fast.geometry.LevelChanges``)."""
    _, distance_bin, _, _, far_bin = threshold_key(kind, forward_m, lit, age_bin, far_change_age_s)
    own = "lit" if lit else "dim"
    if kind >= 0:
        subject = f"{KINDS[kind]}/{distance_bin}"
        return f"{subject}/{own}/age{age_bin}", f"{subject}/{own}", subject
    keys = (f"none/{own}/age{age_bin}", f"none/{own}")
    if far_bin is None:
        return keys
    return (f"none/far{far_bin}/{own}/age{age_bin}", f"none/far{far_bin}/{own}") + keys


def nearest_in_view(kinds: np.ndarray, forward_m: np.ndarray, beam_forward_m: np.ndarray) -> tuple[int, float]:
    """The subject of a camera frame's threshold condition: its nearest candidate (``KINDS`` index,
    forward m); with no candidate the nearest beam of a road user out of view (a beam sweeping
    the road makes big foreground regions with nobody in view); else (-1, nan)."""
    if len(kinds):
        j = int(np.argmin(forward_m))
        return int(kinds[j]), float(forward_m[j])
    if len(beam_forward_m):
        return KINDS.index(BEAM), float(np.min(beam_forward_m))
    return -1, math.nan


@dataclass
class SensorModel:
    """A fitted sensor model (see the module docstring); ``key`` is the hash it is cached by."""

    key: str
    p_hit: list  # nested lists of table_shape()
    persistence: dict[str, float]
    class_given_hit: dict[str, list[float]]  # kind -> P over DETECTOR_CLASSES
    fa_start_p: list[float]  # [dim, lit] of the camera's own lamp
    fa_length_frames: list[int]
    fa_reports: list[list[float]]  # [distance_m, x, y, w, h, class index]
    p_regions_idle: list[float]  # [dim, lit]
    area_fraction: dict[str, list[float]]  # threshold condition -> samples of the largest region's share
    #: P(a judged frame keeps the last frame's rank among its condition's area samples)
    area_persistence: float = 0.0
    #: kind -> samples of how far ahead of the road user (m, along its heading) a hit stands on the
    #: ground: 0 for its own body, 10-20 m for a car seen by its headlights' spot going away
    hit_ahead_m: dict[str, list[float]] = field(default_factory=dict)
    frames: int = 0  # judged camera frames it was fitted on
    candidate_frames: int = 0
    fa_per_camera_hour: float = 0.0  # false alarms started per camera-hour of calibration
    track: dict | None = None  # TRACK_FIELDS fitted on the track decisions (None: not recorded)
    #: TRACK_FIELDS fitted on the frames of plausible tracks (``detector_confirmed`` per track)
    plausible: dict | None = None

    def p_hit_array(self) -> np.ndarray:
        return np.asarray(self.p_hit, dtype=np.float64)

    def for_decisions(self, decisions: str) -> SensorModel:
        """The model of a controller counting the detector's ``decisions`` ('frame': each frame's
        own; 'track': its track's; 'plausible': a frame's own while its track is plausible, from its
        n-th sighting on): this one with that decision set's tables."""
        if decisions == "frame":
            return self
        tables = getattr(self, decisions) if decisions in DECISION_SETS else None
        if tables is None:
            raise ValueError(f"sensor model {self.key}: fitted without {decisions} decisions; recalibrate "
                             "(citysim calibrate)")
        # the tables are shared, not copied (asdict's deep copy took ~0.3 CPU-s a controller): no
        # model changes its tables after loading
        own = {f.name: getattr(self, f.name) for f in fields(self)}
        return SensorModel(**{**own, **tables, **dict.fromkeys(DECISION_SETS)})

    def save(self, path: Path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".tmp")
        tmp.write_text(json.dumps({"version": MODEL_VERSION, **asdict(self)}))
        tmp.replace(path)  # never half-written

    @classmethod
    def load(cls, path: Path) -> SensorModel:
        data = json.loads(Path(path).read_text())
        if data.pop("version", None) != MODEL_VERSION:
            raise ValueError(f"{path}: sensor model of another version; recalibrate (citysim calibrate)")
        return cls(**data)


def _shrunk(hits: np.ndarray, n: np.ndarray, parent: np.ndarray) -> np.ndarray:
    return (hits + PRIOR_FRAMES * parent) / (n + PRIOR_FRAMES)


def fit_p_hit(cells: tuple[np.ndarray, ...], hit: np.ndarray) -> np.ndarray:
    """The p_hit table from candidate rows' cells and hits, each level shrunk toward its parent."""
    shape = table_shape()
    hits = np.zeros(shape)
    n = np.zeros(shape)
    np.add.at(hits, cells, hit.astype(np.float64))
    np.add.at(n, cells, 1.0)
    # a beam is no road user: unseen, it falls back to the non-targets' pooled rate
    target = np.array([k in AGENT_KINDS and AGENT_KINDS[k].is_target for k in KINDS])
    # a kind never seen in calibration falls back to the pooled rate of its group (targets or not)
    pooled = np.zeros(len(KINDS))
    for group in (True, False):
        sel = target == group
        total = n[sel].sum()
        pooled[sel] = hits[sel].sum() / total if total else 0.0
    kind_p = _shrunk(hits.sum(axis=(1, 2, 3, 4, 5)), n.sum(axis=(1, 2, 3, 4, 5)), pooled)
    dist_p = _shrunk(hits.sum(axis=(2, 3, 4, 5)), n.sum(axis=(2, 3, 4, 5)), kind_p[:, None])
    view_p = _shrunk(hits.sum(axis=(4, 5)), n.sum(axis=(4, 5)), dist_p[:, :, None, None])
    return _shrunk(hits, n, view_p[..., None, None])


def fit_persistence(rows: dict[str, np.ndarray], p: np.ndarray) -> dict[str, float]:
    """Per kind, the lag-1 correlation of (hit - p) / sd over consecutive frames of one candidate."""
    order = np.lexsort((rows["frame"], rows["object_id"], rows["camera"]))
    cam, obj, frame = rows["camera"][order], rows["object_id"][order], rows["frame"][order]
    z = (rows["hit"][order] - p[order]) / np.sqrt(np.clip(p[order] * (1 - p[order]), 1e-6, None))
    next_ok = (cam[1:] == cam[:-1]) & (obj[1:] == obj[:-1]) & (frame[1:] == frame[:-1] + 1)
    kind = rows["kind"][order][:-1]
    out = {}
    for k, name in enumerate(KINDS):
        sel = next_ok & (kind == k)
        if sel.sum() < 10:
            out[name] = 0.0
            continue
        a, b = z[:-1][sel], z[1:][sel]
        out[name] = float(np.clip(np.mean(a * b) / max(np.sqrt(np.mean(a * a) * np.mean(b * b)), 1e-9), 0.0, 0.95))
    return out


def fit_classes(rows: dict[str, np.ndarray]) -> dict[str, list[float]]:
    out = {}
    for k, name in enumerate(KINDS):
        counts = np.full(len(DETECTOR_CLASSES), 0.0)
        prior = AGENT_KINDS[name].detector_class if name in AGENT_KINDS else BEAM_PRIOR_CLASS
        counts[DETECTOR_CLASSES.index(prior)] += 0.5  # its own class, as a prior
        sel = (rows["kind"] == k) & rows["hit"].astype(bool) & (rows["det_class"] >= 0)
        np.add.at(counts, rows["det_class"][sel], 1.0)
        out[name] = (counts / counts.sum()).tolist()
    return out


def _capped(values: np.ndarray) -> list:
    values = np.asarray(values)
    if len(values) > MAX_SAMPLES:
        values = values[np.linspace(0, len(values) - 1, MAX_SAMPLES).round().astype(int)]
    return values.tolist()


def fit_false_alarms(frames: dict[str, np.ndarray], camera_hours: float) -> dict:
    """False-alarm episodes: runs of consecutive judged frames of a camera with an unmatched target."""
    order = np.lexsort((frames["frame"], frames["camera"]))
    cam, fa = frames["camera"][order], frames["fa"][order].astype(bool)
    lit = (frames["light"][order] >= LIT_LEVEL).astype(int)
    prev_fa = np.concatenate([[False], fa[:-1] & (cam[1:] == cam[:-1])])
    start = fa & ~prev_fa
    eligible = ~(fa & prev_fa)  # a start is drawn on every frame not continuing an episode
    start_p = [float(start[eligible & (lit == b)].sum() / max(1, (eligible & (lit == b)).sum())) for b in (0, 1)]
    lengths, run = [], 0
    for i in range(len(fa)):
        if fa[i] and (run == 0 or cam[i] == cam[i - 1]):
            run += 1
        elif fa[i]:
            lengths.append(run)
            run = 1
        elif run:
            lengths.append(run)
            run = 0
    if run:
        lengths.append(run)
    reports = np.column_stack([frames["fa_distance_m"], frames["fa_box"], frames["fa_class"]])[order][fa]
    regions = frames["regions"][order].astype(bool)
    empty = ~frames["has_candidates"][order].astype(bool)
    p_regions = [float(regions[empty & (lit == b)].mean()) if (empty & (lit == b)).any() else 0.0 for b in (0, 1)]
    return {"fa_start_p": start_p, "fa_length_frames": _capped(np.array(lengths or [1], dtype=int)),
            "fa_reports": _capped(reports) if len(reports) else [], "p_regions_idle": p_regions,
            "fa_per_camera_hour": float(start.sum() / camera_hours) if camera_hours > 0 else 0.0}  # fmt: skip


def fit_area_fractions(frames: dict[str, np.ndarray], idle_frame_stride: int = 1) -> dict[str, list[float]]:
    """Samples under every key of ``threshold_conditions`` a calibration frame has. Frames with
    nothing in view count only where every camera is judged (frame k with k % ``idle_frame_stride``
    == 0): an idle camera is judged every frame only while its last frame held a region, so its
    other judged frames are mostly an episode's continuation, which fast mode's chain adds itself
    (in calibration 1.9 % of all judged frames with nothing in view held a region over 5 % of the
    frame, 0.4 % of the frames every camera is judged)."""
    by_key: dict[str, list[float]] = {}
    stride = max(1, int(idle_frame_stride))
    far_change = frames["far_change_s"] if "far_change_s" in frames else np.full(len(frames["frame"]), np.inf)
    for k, d, lit, age, frac, f, far_s in zip(frames["near_kind"], frames["near_forward_m"], frames["light"],
                                              frames["age_bin"], frames["area_fraction"].tolist(), frames["frame"],
                                              far_change.tolist(), strict=True):  # fmt: skip
        if k < 0 and f % stride:
            continue
        keys = threshold_conditions(int(k), float(d), bool(lit >= LIT_LEVEL), int(age), far_s)
        # a frame with nothing in view counts under its own two keys (with and without the age), not
        # under a recent far change's fallbacks, which are the frames without one
        for key in keys[:2] if k < 0 else keys:
            by_key.setdefault(key, []).append(frac)
    return {key: _capped(np.array(v)) for key, v in sorted(by_key.items())}


def fit_area_persistence(frames: dict[str, np.ndarray]) -> float:
    """P(keep) of a chain that keeps the last frame's rank among the area samples, else draws anew:
    for such a chain P(over f next | over f now) = keep + (1 - keep) P(over f), so each of the
    ``PERSISTENCE_FRACTIONS`` f seen in calibration's consecutive judged frames (same camera, frame
    k then k + 1) gives keep = (P(over f next | over f now) - P(over f)) / (1 - P(over f)); their mean."""
    order = np.lexsort((frames["frame"], frames["camera"]))
    camera, frame, share = frames["camera"][order], frames["frame"][order], frames["area_fraction"][order]
    pairs = (camera[1:] == camera[:-1]) & (frame[1:] == frame[:-1] + 1)
    now, after = share[:-1][pairs], share[1:][pairs]
    keeps = []
    for fraction in PERSISTENCE_FRACTIONS:
        over_now, over_after = now > fraction, after > fraction
        p_over = float(over_now.mean()) if len(now) else 0.0
        if 0.0 < p_over < 1.0:
            keeps.append((float(over_after[over_now].mean()) - p_over) / (1.0 - p_over))
    return float(np.clip(np.mean(keeps), 0.0, MAX_AREA_PERSISTENCE)) if keeps else 0.0


def fit_sensor_model(rows: dict[str, np.ndarray], frames: dict[str, np.ndarray], camera_hours: float,
                     key: str = "", idle_frame_stride: int = 1, area_frames: dict | None = None) -> SensorModel:  # fmt: skip
    """Fit from candidate ``rows`` and judged ``frames`` (column arrays, ``citysim.fast.records``) of runs that
    judged idle cameras every ``idle_frame_stride``-th frame; region sizes from ``area_frames`` (default: ``frames``)."""
    area_frames = frames if area_frames is None else area_frames
    if len(frames["camera"]) == 0:
        raise ValueError("calibration: no judged camera frames to fit a sensor model on")
    cells = cell_of(rows["kind"], rows["forward_m"], rows["bearing_rad"], rows["light"], rows["young"],
                    rows["speed_mps"])  # fmt: skip
    decisions = _fit_decisions(cells, rows, frames, camera_hours)
    others = {}
    for prefix in DECISION_SETS:  # the same fit on another decision set's columns
        if f"{prefix}_hit" in rows:
            named = {c: f"{prefix}_{c}" for c in DECISION_COLUMNS}
            set_rows = {**rows, **{c: rows[t] for c, t in named.items() if t in rows}}
            set_frames = {**frames, **{c: frames[t] for c, t in named.items() if t in frames}}
            fitted = _fit_decisions(cells, set_rows, set_frames, camera_hours)
            others[prefix] = {name: fitted[name] for name in TRACK_FIELDS}
    return SensorModel(
        key=key, **decisions, area_fraction=fit_area_fractions(area_frames, idle_frame_stride),
        area_persistence=fit_area_persistence(area_frames), frames=int(len(frames["camera"])),
        candidate_frames=int(len(rows["hit"])), **others,
    )  # fmt: skip


def _fit_decisions(cells: tuple, rows: dict[str, np.ndarray], frames: dict[str, np.ndarray],
                   camera_hours: float) -> dict:  # fmt: skip
    """The hit, persistence, class and false-alarm fields fitted on ``rows``' hits and ``frames``' fa."""
    table = fit_p_hit(cells, rows["hit"])
    p = table[cells] if len(rows["hit"]) else np.zeros(0)
    return {"p_hit": table.tolist(), "persistence": fit_persistence(rows, p), "class_given_hit": fit_classes(rows),
            "hit_ahead_m": fit_hit_ahead(rows), **fit_false_alarms(frames, camera_hours)}  # fmt: skip


def fit_hit_ahead(rows: dict[str, np.ndarray]) -> dict[str, list[float]]:
    """Per kind, samples of its hits' ground offset ahead of it along its heading, m (0: its body)."""
    if "hit_ahead_m" not in rows:
        return {}
    known = rows["hit"].astype(bool) & np.isfinite(rows["hit_ahead_m"])
    return {name: [round(float(v), 2) for v in _capped(rows["hit_ahead_m"][known & (rows["kind"] == k)])]
            for k, name in enumerate(KINDS) if (known & (rows["kind"] == k)).any()}  # fmt: skip
