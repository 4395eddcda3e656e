"""How training samples are drawn: the cameras (Table 2 lenses, the general model's range of
heights and tilts) and the limits a region must pass, the same as the detector's segmenter."""

from __future__ import annotations

from dataclasses import dataclass, field

from detector.classes import GENERAL_CAMERA_HEIGHT_M, GENERAL_MIN_VIEW_RANGE_M, GENERAL_TILT_DEG
from detector.segment import SegmenterParams
from detector.train.samplers import FEATURE_NOISE, NOISE_SAMPLERS

# the segmenter's own defaults, so training regions are cleaned and filtered like the detector's
_SEGMENTER = SegmenterParams()

@dataclass(frozen=True)
class Intrinsics:
    """A camera's lens and sensor: focal length and sensor size, mm; image size, px."""

    focal_mm: float
    sensor_w_mm: float
    sensor_h_mm: float
    width_px: int
    height_px: int


#: The paper's Table 2 cameras (Logitech C920, Microsoft HD-3000, Gadinan IP cam).
TABLE2_INTRINSICS = (
    Intrinsics(3.67, 4.8, 3.6, 424, 240),
    Intrinsics(0.73, 0.7, 0.52, 320, 240),
    Intrinsics(3.6, 3.45, 1.94, 424, 240),
)


@dataclass(frozen=True)
class TrainingConfig:
    """How samples are drawn. The morphology and region limits default to
    ``detector.segment.SegmenterParams``'s (imported, so they cannot drift) so
    training regions look like the regions the detector extracts."""

    camera_height_m: tuple[float, float] = GENERAL_CAMERA_HEIGHT_M
    tilt_deg: tuple[float, float] = GENERAL_TILT_DEG
    intrinsics: tuple[Intrinsics, ...] = TABLE2_INTRINSICS
    min_view_range_m: float = GENERAL_MIN_VIEW_RANGE_M
    min_distance_m: float = 1.0
    max_distance_m: float = 50.0
    exposure_ms: tuple[float, float] = (0.0, 40.0)
    jitter_px: int = 1
    open_kernel_px: int = _SEGMENTER.open_kernel_px
    dilate_iterations: int = _SEGMENTER.dilate_iterations
    min_area_fraction: float = _SEGMENTER.min_area_fraction
    min_extent: float = _SEGMENTER.min_extent
    attempts_per_camera: int = 4
    noise_ratio: float = 3.0
    noise_weights: dict[str, float] = field(
        default_factory=lambda: {
            "too_small": 0.2,
            "too_flat": 0.1,
            "too_tall_thin": 0.1,
            "too_large": 0.1,
            "animal": 0.15,
            "ground_spot": 0.15,
            "insect": 0.1,
            "foliage": 0.05,
        }
    )

    def __post_init__(self) -> None:
        for name in ("camera_height_m", "tilt_deg", "exposure_ms"):
            lo, hi = getattr(self, name)
            if not lo <= hi:
                raise ValueError(
                    f"TrainingConfig.{name} must be (min, max) with min <= max, got {(lo, hi)}"
                )
        if not 0 < self.min_distance_m < self.max_distance_m:
            raise ValueError(
                "TrainingConfig.min_distance_m / max_distance_m must satisfy 0 < min < max, "
                f"got {self.min_distance_m}, {self.max_distance_m}"
            )
        valid_kinds = set(NOISE_SAMPLERS) | set(FEATURE_NOISE)
        unknown = set(self.noise_weights) - valid_kinds
        if (
            unknown
            or any(w < 0 for w in self.noise_weights.values())
            or sum(self.noise_weights.values()) <= 0
        ):
            raise ValueError(
                f"TrainingConfig.noise_weights must map kinds in {sorted(valid_kinds)} to weights >= 0 "
                f"(not all 0), got {self.noise_weights}"
            )
        if not self.noise_ratio > 0:
            raise ValueError(f"TrainingConfig.noise_ratio must be > 0, got {self.noise_ratio}")


#: The general model's training configuration (frozen: one shared instance is safe).
DEFAULT_CONFIG = TrainingConfig()
