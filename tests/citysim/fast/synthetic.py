"""Synthetic calibration columns and sensor models for the fast-mode tests (no rendering)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from citysim.fast.model import KINDS, TRACK_FIELDS, SensorModel, fit_sensor_model, table_shape
from citysim.fast.records import DECISION_PREFIXES, FRAME_COLUMNS, ROW_COLUMNS

REPO = Path(__file__).resolve().parents[3]
CAMERA = REPO / "scenarios" / "cameras" / "scene_a.yaml"


def rows(n: int = 0, **columns) -> dict[str, np.ndarray]:
    """Candidate rows: every column of ``ROW_COLUMNS``, defaults for the ones not given."""
    defaults = {"camera": 0, "frame": np.arange(n), "object_id": 1, "kind": KINDS.index("pedestrian"),
                "forward_m": 12.0, "bearing_rad": 0.0, "speed_mps": 1.4, "light": 0.2, "young": False,
                **{f"{p}{c}": v for p in DECISION_PREFIXES
                   for c, v in (("hit", False), ("det_class", -1), ("hit_ahead_m", np.nan))}}  # fmt: skip
    out = {}
    for col in ROW_COLUMNS:
        value = columns.get(col, defaults[col])
        out[col] = np.broadcast_to(np.asarray(value), (n,)).copy()
    return out


def frames(n: int = 0, **columns) -> dict[str, np.ndarray]:
    """Judged-frame rows: every column of ``FRAME_COLUMNS``, defaults for the ones not given."""
    defaults = {"camera": 0, "frame": np.arange(n), "light": 0.2, "has_candidates": False, "regions": False,
                "near_kind": -1, "near_forward_m": np.nan, "area_fraction": 0.0, "age_bin": 2, "far_change_s": np.inf,
                **{f"{p}{c}": v for p in DECISION_PREFIXES
                   for c, v in (("fa", False), ("fa_distance_m", 15.0), ("fa_box", None), ("fa_class", 1))}}  # fmt: skip
    out = {}
    for col in FRAME_COLUMNS:
        if col.endswith("fa_box"):
            out[col] = np.tile(np.array([[100.0, 100.0, 20.0, 40.0]]), (n, 1)) if columns.get(col) is None \
                else np.asarray(columns[col], dtype=np.float64)  # fmt: skip
            continue
        value = columns.get(col, defaults[col])
        out[col] = np.broadcast_to(np.asarray(value), (n,)).copy()
    return out


def constant_model(p_hit: float, fa_start_p: float = 0.0, area_fraction: float = 0.0) -> SensorModel:
    """A model that detects every candidate with probability ``p_hit`` (no streaks), starts false
    alarms with ``fa_start_p`` per judged frame, and whose threshold segmenter always reports a
    region of ``area_fraction`` of the frame."""
    model = fit_sensor_model(rows(0), frames(1), camera_hours=1.0, key="synthetic")
    model.p_hit = np.full(table_shape(), p_hit).tolist()
    model.persistence = {k: 0.0 for k in KINDS}
    model.fa_start_p = [fa_start_p, fa_start_p]
    model.fa_length_frames = [5]
    model.fa_reports = [[15.0, 100.0, 100.0, 20.0, 40.0, 1.0]]
    conditions = [f"none/{b}" for b in ("dim", "lit")] + [f"{k}/{d}" for k in KINDS for d in range(12)]
    model.area_fraction = {c: [area_fraction] for c in conditions}
    model.track = {name: getattr(model, name) for name in TRACK_FIELDS}  # tracks decide alike
    model.plausible = dict(model.track)
    return model


def tiny_scenario(**more) -> dict:
    """Three lamps on a 90 m street with busy traffic: 20 simulated seconds see many passes."""
    from tests.citysim.streets import two_way_street

    base = {
        "name": "tiny_fast", "seed": 11, "duration_s": 20,
        "street": two_way_street(90, crossings_x_m=[45]),
        "lamps": {"count": 3, "spacing_m": 30, "first_x_m": 15, "y_m": 6.2, "pole_height_m": 5.5,
                  "camera": {"file": str(CAMERA), "tilt_deg": 15, "heading_deg": -8}},
        "traffic": {"classes": {"pedestrian": {"rate_per_hour": 600}, "vehicle": {"rate_per_hour": 200},
                                "cyclist": {"rate_per_hour": 100}}},
        "controllers": ["always_on", "detector_confirmed"],
    }  # fmt: skip
    base.update(more)
    return base
