"""Synthetic training features for the dimensional classifier (paper section 5.3).

Each sample is one object (``detector.train.shapes``, sizes in Table 1) seen by one random
camera, projected, rasterised, cleaned with the segmenter's morphology and measured with
``detector.features.region_features``, the very code the detector runs; ``noise_ratio`` noise
rows per target row (``detector.train.samplers`` draws each kind).

The camera stands at the origin looking along +x, so the "forward distance" of the features is
the world x of the ground point (m). Determinism: everything is drawn from the one
``numpy.random.Generator`` passed in; the same seed gives the same arrays, bit for bit.

Design: docs/design/modules.md (Synthetic training data)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from detector.camera import CameraModel
from detector.features import N_FEATURES, region_features
from detector.train.config import DEFAULT_CONFIG, TrainingConfig
from detector.train.regions import ground_points, jitter, shape_region
from detector.train.samplers import FEATURE_NOISE, NOISE_SAMPLERS, TARGET_SAMPLERS, uniform

#: A kind seen whole in fewer than 1 of HOPELESS_ODDS tries, after MIN_ATTEMPTS, fails training
#: (the general set sees every kind in more than 1 of 8).
HOPELESS_ODDS = 200
MIN_ATTEMPTS = 2000


class UnseenKindError(RuntimeError):
    """The cameras (almost) never see one kind of object whole, so its samples cannot be drawn."""

    def __init__(self, kind: str, seen: int, attempts: int) -> None:
        self.kind, self.seen, self.attempts = kind, seen, attempts
        super().__init__(
            f"make_training_set: the cameras saw {kind!r} whole in only {seen} of {attempts} "
            "attempts; check the cameras and the TrainingConfig"
        )


# -------------------------------------------------------------------- cameras
def random_camera(
    rng: np.random.Generator, config: TrainingConfig = DEFAULT_CONFIG
) -> CameraModel:
    """A camera at the origin looking along +x with random height, tilt and Table 2 intrinsics.

    Cameras whose top image row meets the ground nearer than ``config.min_view_range_m``
    are drawn again.
    """
    for _ in range(1000):
        intr = config.intrinsics[int(rng.integers(len(config.intrinsics)))]
        cam = CameraModel(
            height_m=uniform(rng, config.camera_height_m),
            tilt_deg=uniform(rng, config.tilt_deg),
            focal_mm=intr.focal_mm,
            sensor_w_mm=intr.sensor_w_mm,
            sensor_h_mm=intr.sensor_h_mm,
            width_px=intr.width_px,
            height_px=intr.height_px,
        )
        top_depression_deg = cam.tilt_deg - cam.vertical_fov_deg / 2
        if (
            top_depression_deg <= 0
            or cam.height_m / math.tan(math.radians(top_depression_deg)) >= config.min_view_range_m
        ):
            return cam
    raise ValueError(
        f"TrainingConfig: no camera in the configured ranges sees {config.min_view_range_m} m far"
    )


# ----------------------------------------------------------------- the set
@dataclass(frozen=True)
class TrainingSet:
    """Features ``X`` (N, 6), class names ``y`` (N,) and what made each row, ``kind`` (N,):
    the class for targets, the noise sampler's name (``NOISE_SAMPLERS``) for noise."""

    X: np.ndarray
    y: np.ndarray
    kind: np.ndarray


def make_training_set(
    n_per_class: int,
    rng: np.random.Generator,
    cameras: Sequence[CameraModel] | None = None,
    config: TrainingConfig = DEFAULT_CONFIG,
) -> tuple[np.ndarray, np.ndarray]:
    """Synthetic features ``(X (N, 6) float, y (N,) str class names)``.

    ``n_per_class`` rows for each target class and ``config.noise_ratio`` noise
    rows per target row (N = 4n + 4n * noise_ratio), noise first, then the
    targets in CLASSES order. ``cameras``: draw every sample from one of these
    (any pose; it is moved to the origin, heading +x) instead of random Table 2
    cameras, for a model specialised to an installation.
    """
    data = make_training_samples(n_per_class, rng, cameras, config)
    return data.X, data.y


def make_training_samples(
    n_per_class: int,
    rng: np.random.Generator,
    cameras: Sequence[CameraModel] | None = None,
    config: TrainingConfig = DEFAULT_CONFIG,
) -> TrainingSet:
    """``make_training_set`` that also says which sampler made each row."""
    if not isinstance(n_per_class, int | np.integer) or n_per_class < 1:
        raise ValueError(
            f"make_training_set: n_per_class must be an integer >= 1, got {n_per_class!r}"
        )
    if cameras is not None:
        cameras = [c.placed(x_m=0.0, y_m=0.0, yaw_deg=0.0) for c in cameras]
        if not cameras:
            raise ValueError(
                "make_training_set: cameras must hold at least one CameraModel, got an empty list"
            )
    kernel = cv2.getStructuringElement(
        cv2.MORPH_ELLIPSE, (config.open_kernel_px, config.open_kernel_px)
    )
    wanted = _quotas(n_per_class, config)
    rows: dict[str, list[np.ndarray]] = {k: [] for k in wanted}

    attempts = dict.fromkeys(wanted, 0)
    while True:
        todo = [k for k in wanted if len(rows[k]) < wanted[k]]
        if not todo:
            break
        # a kind the cameras (almost) never see whole fails loudly instead of looping for ever:
        # once MIN_ATTEMPTS tries show it seen in fewer than 1 of HOPELESS_ODDS, it fails at
        # once; a kind seen more often reaches its quota within HOPELESS_ODDS x quota tries
        for k in todo:
            if attempts[k] >= MIN_ATTEMPTS and len(rows[k]) * HOPELESS_ODDS < attempts[k]:
                raise UnseenKindError(k, len(rows[k]), attempts[k])
        cam = (
            random_camera(rng, config)
            if cameras is None
            else cameras[int(rng.integers(len(cameras)))]
        )
        for k in todo:
            attempts[k] += config.attempts_per_camera
        _sample_camera(rng, cam, todo, rows, wanted, config, kernel)
    noise_kinds = [k for k in wanted if k not in TARGET_SAMPLERS]
    order = [*noise_kinds, *TARGET_SAMPLERS]  # noise first, then targets in CLASSES order
    X = np.concatenate([np.array(rows[k]).reshape(-1, N_FEATURES) for k in order])
    kind = np.repeat(np.array(order), [wanted[k] for k in order])
    y = np.where(np.isin(kind, noise_kinds), "noise", kind)
    return TrainingSet(X, y, kind)


def _quotas(n_per_class: int, config: TrainingConfig) -> dict[str, int]:
    """Rows wanted per kind: ``n_per_class`` per target class, the noise split by weight."""
    # one quota per kind, so the noise mix is the configured one whatever each kind's loss rate
    total_weight = sum(config.noise_weights.values())
    n_noise = config.noise_ratio * n_per_class * len(TARGET_SAMPLERS)
    wanted = {c: n_per_class for c in TARGET_SAMPLERS}
    wanted.update(
        {k: round(n_noise * w / total_weight) for k, w in config.noise_weights.items() if w > 0}
    )
    return wanted


def _sample_camera(
    rng: np.random.Generator,
    cam: CameraModel,
    todo: list[str],
    rows: dict[str, list[np.ndarray]],
    wanted: dict[str, int],
    config: TrainingConfig,
    kernel: np.ndarray,
) -> None:
    """Draw ``config.attempts_per_camera`` samples of each kind in ``todo`` seen by ``cam``;
    append the feature rows of those it sees whole to ``rows``, up to each kind's quota."""
    kinds = [k for k in todo for _ in range(config.attempts_per_camera)]
    ground = ground_points(rng, cam, len(kinds), config)
    boxes, areas, kept = [], [], []
    for kind, (gx, gy) in zip(kinds, ground, strict=True):
        if not np.isfinite(gx):
            continue
        if kind in FEATURE_NOISE:
            width_m, height_m = FEATURE_NOISE[kind](rng)
            area_m2 = rng.uniform(0.3, 0.95) * width_m * height_m
            if len(rows[kind]) < wanted[kind]:
                rows[kind].append(
                    np.array([width_m, height_m, area_m2, gx, cam.tilt_deg, cam.height_m])
                )
            continue
        sampler = NOISE_SAMPLERS.get(kind) or TARGET_SAMPLERS[kind]
        shape, velocity = sampler(rng, cam, float(gx), float(gy), rng.uniform(0, 2 * math.pi))
        region = shape_region(
            cam, shape, velocity, uniform(rng, config.exposure_ms) / 1000.0, config, kernel
        )
        if region is None:
            continue
        box, area = jitter(rng, *region, config.jitter_px)
        boxes.append(box)
        areas.append(area)
        kept.append(kind)
    if not kept:
        return
    feats, valid = region_features(cam, np.array(boxes), np.array(areas))
    ok = (
        valid
        & (feats[:, 3] > 0)
        & (feats[:, 3] <= config.max_distance_m)
        & np.all(np.isfinite(feats), axis=1)
    )
    for kind, row, good in zip(kept, feats, ok, strict=True):
        if good and len(rows[kind]) < wanted[kind]:
            rows[kind].append(row)
