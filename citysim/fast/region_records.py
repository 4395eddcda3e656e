"""Calibration records of the threshold baselines: the largest foreground region of every judged frame.

The paper's naive baselines (``citysim.control.camera.ForegroundThreshold``) light a lamp when a
foreground region covers a share of the frame; fast mode draws that share from samples recorded
under the same condition (``citysim.fast.model.threshold_conditions``). The samples come from
*region nights*: full-fidelity runs of a threshold baseline itself, at the scenario's own
traffic, whose segmenters ``RegionSensors`` wraps so ``RegionRecorder`` writes one row per judged
frame (the columns ``citysim.fast.model.fit_area_fractions`` and ``fit_area_persistence`` read),
not the detector's busier calibration nights.

Design: docs/design/fast-mode-sensor-model.md
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from citysim.fast.model import background_age_bin
from citysim.fast.records import StreetWatch

#: The columns of a region night's frame rows (what the area fits read).
REGION_COLUMNS = ("camera", "frame", "light", "near_kind", "near_forward_m", "area_fraction", "age_bin",
                  "far_change_s")  # fmt: skip


class RecordingSegmenter:
    """A real ``detector.segment.Segmenter`` that keeps its last frame's largest region's share."""

    def __init__(self, segmenter):
        self.inner = segmenter
        self.fresh = False  # a frame was segmented since the recorder last looked
        self.last_rate: float | None = None
        self.last_area_fraction = 0.0

    def __getattr__(self, name):  # automatic_learning_rate, ...
        return getattr(self.inner, name)

    def reset(self) -> None:
        self.inner.reset()

    def apply(self, image: np.ndarray, learning_rate: float | None = None):
        regions = self.inner.apply(image, learning_rate)
        n_px = image.shape[0] * image.shape[1]
        self.last_area_fraction = float(regions.areas_px.max()) / n_px if len(regions.areas_px) else 0.0
        self.last_rate = learning_rate
        self.fresh = True
        return regions


class RegionSensors:
    """``ControlContext.sensors`` of a region night: the threshold baseline's own segmenters, recorded."""

    def __init__(self):
        self.segmenters_made: list[RecordingSegmenter] = []

    def segmenters(self, ctx) -> list[RecordingSegmenter]:
        from detector.segment import Segmenter, SegmenterParams

        fps = 1.0 / ctx.frame_period_s
        self.segmenters_made = [RecordingSegmenter(Segmenter(SegmenterParams(), fps=fps)) for _ in ctx.camera_lamps]
        return self.segmenters_made

    def detectors(self, ctx, threshold: float):
        raise ValueError("a region night records a threshold baseline, not a detector controller")


class RegionRecorder(StreetWatch):
    """Collector of a region night: one row per judged frame, its condition and largest region's share.

    A threshold baseline's ``on_frame`` returns no detections, judged or not (a frame is skipped
    while the light in view changes): a frame was judged when its camera's segmenter ran on it.
    """

    def __init__(self, geometry, sensors: RegionSensors, fps: float):
        super().__init__(geometry, fps)
        self.sensors = sensors
        self.frames: dict[str, list] = {c: [] for c in REGION_COLUMNS}

    def on_frame(self, lamp_index: int, t_s: float, truth: Sequence, detections: Sequence | None) -> None:
        segmenter = self.sensors.segmenters_made[lamp_index]
        if not segmenter.fresh:
            return  # not judged (the light in view was changing)
        segmenter.fresh = False
        _, near_kind, near_forward_m = self.in_view(lamp_index)
        values = {"camera": lamp_index, "frame": int(round(t_s * self.fps)), "light": float(self.levels[self.geometry.camera_lamps[lamp_index]]),
                  "near_kind": near_kind, "near_forward_m": near_forward_m,
                  "area_fraction": segmenter.last_area_fraction, "age_bin": background_age_bin(segmenter.last_rate),
                  "far_change_s": self.changes.far_change_age_s(lamp_index, t_s)}  # fmt: skip
        for col in REGION_COLUMNS:
            self.frames[col].append(values[col])

    def region_columns(self) -> dict[str, np.ndarray]:
        """The frame rows as arrays (a region night has no candidate rows)."""
        return {c: np.asarray(v) for c, v in self.frames.items()}
