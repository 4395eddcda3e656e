"""What a paper reproduction produced: per scene, per condition (night, day), and the whole run.

Its own module so that the run (``reproduce``), its report and its notes all read the same types
without importing each other.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from experiments.paper.metrics import (
    BandRate,
    BaselineRates,
    Confusions,
    PrecisionRecall,
    WindowCheck,
)
from experiments.paper.scenes import Budget, SceneRecords
from experiments.paper.tracks import TrackFigures


@dataclass(frozen=True)
class ConditionResult:
    """Night (scenes A-C) or day (scene D) pooled, as in the paper's Figs. 9-10."""

    name: str
    scenes: tuple[str, ...]
    records: SceneRecords
    confusions: dict[str, Confusions]  # by variant (paper_metrics.VARIANTS)
    precision_recall: dict[str, PrecisionRecall]
    baseline: dict[float, BaselineRates]
    window: WindowCheck
    by_distance: list[BandRate]
    #: per-object figures: each frame's own decision ('per frame'), the run's track decisions
    #: ('run') and each pooling's (``experiments.paper.tracks``)
    tracks: dict[str, TrackFigures]


@dataclass(frozen=True)
class SceneResult:
    key: str
    title: str
    time_of_day: str
    resolution: str
    range_m: float
    records: SceneRecords
    confusions: Confusions  # 'objects' variant

    @property
    def detector_fps_cpu(self) -> float | None:
        r = self.records
        return r.detector_frames / r.detector_cpu_s if r.detector_cpu_s > 0 else None

    @property
    def detector_fps_wall(self) -> float | None:
        r = self.records
        return r.detector_frames / r.detector_wall_s if r.detector_wall_s > 0 else None


@dataclass(frozen=True)
class Reproduction:
    scenes: dict[str, SceneResult]
    conditions: dict[str, ConditionResult]
    budget: Budget
    quick: bool
    cpu: str
    files: dict[str, Path]
    source: str  # the code's git commit (the numbers belong to it)
