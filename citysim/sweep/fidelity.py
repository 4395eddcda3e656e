"""Sweeps in fast mode: sensor models calibrated once per camera setup, and a full-fidelity check.

A sweep runs fast by default (``citysim.fast``). Its points are grouped by calibration key
(points that change only the traffic, the hold time or the controllers share one sensor
model; a point that moves or tilts the cameras needs its own), and each model is fetched from
the cache or calibrated in the client before any point is sent to Dask, so workers never
calibrate. ``check_points`` picks a sample of the points run this time, evenly spread, that are
re-run in full fidelity; ``check_report`` compares each with its fast run
(``citysim.sim.validation.compare_figures``) and DIR/fidelity_check.json keeps it.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

from citysim.config.scenario import Scenario
from citysim.sim.calibration import (
    DEFAULT_DURATION_S,
    DEFAULT_RUNS,
    calibration_key,
    sensor_model_for,
)
from citysim.sim.compare import needs_sensor_model, resolve_controllers
from citysim.sim.validation import compare_figures

CHECK_FILE = "fidelity_check.json"


def sensor_models(scenarios: Sequence[Scenario], cache_dir: Path | None, progress: bool) -> list:
    """One sensor model per scenario (None where no controller watches a camera), shared by key."""
    by_key: dict[str, object] = {}
    out = []
    for scenario in scenarios:
        if not needs_sensor_model(resolve_controllers(scenario, None)):
            out.append(None)
            continue
        key = calibration_key(scenario, DEFAULT_DURATION_S, DEFAULT_RUNS)
        if key not in by_key:
            by_key[key] = sensor_model_for(scenario, cache_dir, progress=progress)
        out.append(by_key[key])
    return out


def check_points(n_points: int, n_checks: int) -> list[int]:
    """Indices of ``n_checks`` of ``n_points`` points, evenly spread (first and last included)."""
    if n_checks <= 0 or n_points == 0:
        return []
    if n_checks >= n_points:
        return list(range(n_points))
    if n_checks == 1:
        return [0]
    return sorted({round(i * (n_points - 1) / (n_checks - 1)) for i in range(n_checks)})


def _tallied(points: dict) -> dict:
    """``points`` with the count of their agreement cells and of those that pass."""
    cells = [cell for rows in points.values() for row in rows.values() for cell in row.values()]
    return {"points": points, "cells": len(cells), "cells_pass": sum(bool(c["pass"]) for c in cells)}


def check_report(pairs: Sequence[tuple[str, dict, dict]]) -> dict:
    """Per checked point (point_id, full summary, fast summary): the figures' agreement."""
    return _tallied({pid: compare_figures([full], [fast]) for pid, full, fast in pairs})


def write_check(out_dir: Path, report: dict) -> Path:
    """Merge ``report`` into DIR/fidelity_check.json (points checked by earlier runs are kept)."""
    path = Path(out_dir) / CHECK_FILE
    points = {}
    if path.exists():
        try:
            points = json.loads(path.read_text()).get("points", {})
        except (OSError, json.JSONDecodeError):
            points = {}
    points.update(report["points"])
    merged = _tallied(points)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(merged, indent=2) + "\n")
    tmp.replace(path)
    return path
