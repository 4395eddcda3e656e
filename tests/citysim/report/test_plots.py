"""Planner plots and the HTML report: real PNGs with the data in them, one self-contained page.

The run folder comes from a real ``run_comparison`` of a tiny scenario (``run_copy`` of
conftest.py); the camera height x tilt heatmaps are checked on a results table written through
``ResultsFile`` with figures that vary over the grid in a known way.
"""

from __future__ import annotations

import base64
import json
import re
from pathlib import Path

import cv2
import numpy as np
import pytest

from citysim.report.common import CONTROLLER_COLORS, axis_label, clock_label
from citysim.report.html import best_settings, write_report
from citysim.report.run_plots import PlotError, plot_run
from citysim.report.sweep_plots import plot_sweep
from citysim.sweep.results import ResultsFile, flatten_summary
from citysim.sweep.spec import point_id


def rgb(path: Path) -> np.ndarray:
    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    assert image is not None, f"{path} is not a readable image"
    return image[:, :, ::-1]


def color_mask(image: np.ndarray, hex_color: str, tol: int = 12) -> np.ndarray:
    target = np.array([int(hex_color[i : i + 2], 16) for i in (1, 3, 5)])
    return np.abs(image.astype(int) - target).max(axis=2) <= tol


def pixels_of(image: np.ndarray, hex_color: str, tol: int = 12) -> int:
    return int(color_mask(image, hex_color, tol).sum())


def longest_vertical_run(mask: np.ndarray) -> int:
    best = 0
    for column in mask.T:
        edges = np.flatnonzero(np.diff(np.r_[0, column.astype(np.int8), 0]))
        if len(edges):
            best = max(best, int((edges[1::2] - edges[::2]).max()))
    return best


def assert_real_plot(path: Path) -> np.ndarray:
    image = rgb(path)
    gray = image.mean(axis=2)
    assert image.shape[0] > 200 and image.shape[1] > 300
    assert (gray < 200).mean() > 0.02, f"{path.name} is nearly blank"
    assert len(np.unique(gray)) > 20
    return image


def test_plot_run_draws_energy_levels_and_lag(run_copy):
    run_dir = run_copy
    summary = json.loads((run_dir / "summary.json").read_text())
    assert summary["controllers"]["pir"]["savings_vs_always_on"] > 0
    paths = plot_run(run_dir)
    assert [p.name for p in paths] == [
        "frontier.png",
        "energy.png",
        "oracle_gap.png",  # pir's line: the fixture's run holds the oracle
        "energy_per_hour.png",
        "lamp_levels.png",
        "lag_cdf.png",
        "coverage.png",  # drawn by `citysim run` (here the fixture) from the scenario, and kept
    ]
    for p in paths:
        assert p.parent == run_dir / "plots"
        assert_real_plot(p)
    # the controllers' own colours are where their data are drawn
    energy, levels = rgb(paths[1]), rgb(paths[4])
    assert pixels_of(rgb(paths[2]), CONTROLLER_COLORS["pir"]) > 100
    for name in ("always_on", "pir"):
        assert pixels_of(energy, CONTROLLER_COLORS[name]) > 2000
        assert pixels_of(levels, CONTROLLER_COLORS[name]) > 100
    # the solid (luminaire) part of pir's bar is lower than always_on's in proportion:
    # compare the longest vertical run of each colour (text antialiasing makes only short runs)
    heights = {
        n: longest_vertical_run(color_mask(energy, CONTROLLER_COLORS[n]))
        for n in ("always_on", "pir")
    }
    pir, reference = summary["controllers"]["pir"], summary["controllers"]["always_on"]
    expected = pir["energy_split_kwh"]["luminaire"] / reference["energy_kwh"]
    assert heights["pir"] / heights["always_on"] == pytest.approx(expected, abs=0.03)


def test_run_report_embeds_every_plot(run_copy):
    run_dir = run_copy
    report = write_report(run_dir)
    html = report.read_text()
    uris = re.findall(r'<img alt="([^"]+)" src="data:image/png;base64,([^"]+)"', html)
    on_disk = sorted(p.name for p in (run_dir / "plots").glob("*.png"))
    assert sorted(n for n, _ in uris) == on_disk and len(on_disk) == 7
    for name, data in uris:
        decoded = cv2.imdecode(np.frombuffer(base64.b64decode(data), np.uint8), cv2.IMREAD_COLOR)
        assert decoded is not None
        assert np.array_equal(decoded[:, :, ::-1], rgb(run_dir / "plots" / name))
    assert "Figures per controller" in html and "tiny_plots" in html
    assert 'src="plots/' not in html  # nothing linked from outside the page


def test_plot_run_needs_a_run_folder(tmp_path):
    with pytest.raises(PlotError, match="no summary.json"):
        plot_run(tmp_path)
    with pytest.raises(PlotError, match="neither a run folder"):
        write_report(tmp_path)


HEIGHTS_M = (2.0, 6.0, 10.0)
TILTS_DEG = (0.0, 40.0, 80.0)


def synthetic_sweep(folder: Path, with_detection: bool, savings_slope: float) -> Path:
    """A height x tilt sweep table: savings grow with tilt, misses with height, lag with both."""
    axes = ["lamps.camera.height_m", "lamps.camera.tilt_deg"]
    folder.mkdir(parents=True)
    (folder / "sweep.json").write_text(json.dumps({
        "name": "height_tilt", "scenario": "synthetic", "axes": {axes[0]: HEIGHTS_M, axes[1]: TILTS_DEG},
        "controllers": ["always_on", "detector"], "seeds": [1, 2], "duration_s": 5400.0, "start_hour": 22.0,
        "points": 18,
    }))  # fmt: skip
    results = ResultsFile(folder / "results.csv", axes)
    for h in HEIGHTS_M:
        for t in TILTS_DEG:
            for seed in (1, 2):
                ident = {axes[0]: h, axes[1]: t, "seed": seed}
                pid = point_id({axes[0]: h, axes[1]: t}, seed)
                det = (
                    {"tpr": 1 - h / 20, "fpr": t / 400, "miss_rate": h / 20}
                    if with_detection
                    else {}
                )
                figures = {
                    "always_on": {"energy_kwh": 1.0, "savings_vs_always_on": 0.0, "lag_p95_s": 0.0,
                                  "unlit_crossings": 0, "energy_per_hour_kwh": [0.66, 0.34], "detection": {}},
                    "detector": {"energy_kwh": 0.5, "savings_vs_always_on": 0.2 + savings_slope * t / 80,
                                 "lag_p95_s": 0.1 * h + t / 100, "unlit_crossings": int(h > 8),
                                 "energy_per_hour_kwh": [0.3, 0.2], "detection": det},
                }  # fmt: skip
                results.append([
                    {"point_id": pid, **ident, "controller": c, "status": "ok", "error": "",
                     **flatten_summary(f, reserved={"controller"})}
                    for c, f in figures.items()
                ])  # fmt: skip
    return folder


def test_heatmaps_over_height_and_tilt(tmp_path):
    folder = synthetic_sweep(tmp_path / "a", with_detection=True, savings_slope=0.6)
    paths = {p.name: p for p in plot_sweep(folder)}
    expected = {
        f"heatmap_{k}.png"
        for k in ("savings", "false_negative_rate", "false_positive_rate", "lag_p95")
    }
    assert expected <= set(paths)
    assert {
        "vs_lamps_camera_height_m.png",
        "vs_lamps_camera_tilt_deg.png",
        "energy_per_hour.png",
    } <= set(paths)
    for p in paths.values():
        assert_real_plot(p)
    assert "lag_cdf.png skipped" in (folder / "plots" / "notes.txt").read_text()
    # same grid, flat savings: the savings heatmap must look different (it shows the data)
    flat = synthetic_sweep(tmp_path / "b", with_detection=False, savings_slope=0.0)
    flat_paths = {p.name: p for p in plot_sweep(flat)}
    assert "heatmap_false_negative_rate.png" not in flat_paths
    assert not np.array_equal(
        rgb(paths["heatmap_savings.png"]), rgb(flat_paths["heatmap_savings.png"])
    )
    assert "false negative rate" in (flat / "plots" / "notes.txt").read_text()


def test_best_settings_respects_unlit_crossings(tmp_path):
    folder = synthetic_sweep(tmp_path / "a", with_detection=True, savings_slope=0.6)
    from citysim.report.sweep_plots import SweepTable

    table = SweepTable.load(folder)
    best = {b["goal"]: b for b in best_settings(table.ok, table.axes)}
    safest = best["highest savings, no never-full crossing"]
    # savings peak at tilt 80 whatever the height; heights above 8 m have unlit crossings
    assert safest["setting"]["lamps.camera.tilt_deg"] == "80.0"
    assert float(safest["setting"]["lamps.camera.height_m"]) <= 8
    assert safest["savings"] == pytest.approx(0.8)
    fastest = best["lowest lag p95"]
    assert fastest["setting"] == {"lamps.camera.height_m": "2.0", "lamps.camera.tilt_deg": "0.0"}
    html = write_report(folder).read_text()
    assert "camera tilt below horizon (deg) = 80.0" in html


def test_labels_carry_units():
    assert axis_label("lamps.camera.height_m") == "camera height (m)"
    assert axis_label("network.latency_ms") == "network latency (ms)"
    assert axis_label("traffic.classes.vehicle.rate_per_hour") == "vehicle rate (per hour)"
    assert clock_label(22.0, 3) == "01:00"
    assert clock_label(21.5, 0) == "21:30"


def test_best_settings_falls_back_to_fewest_unlit_crossings():
    rows = [
        {"controller": "detector", "status": "ok", "lamps.camera.tilt_deg": tilt, "seed": seed,
         "savings_vs_always_on": str(savings), "lag_p95_s": "1.0", "unlit_crossings": str(unlit)}
        for tilt, seed, savings, unlit in [("20", "1", 0.3, 1), ("20", "2", 0.3, 2),
                                           ("40", "1", 0.5, 1), ("40", "2", 0.6, 1),
                                           ("60", "1", 0.9, 3), ("60", "2", 0.9, 0)]
    ]  # fmt: skip
    best = best_settings(rows, ["lamps.camera.tilt_deg"])[0]
    # the worst seed decides: 40 deg has at most 1 unlit crossing, 20 and 60 deg have more
    assert best["goal"] == "highest savings, fewest never-full crossings (1; none has 0)"
    assert best["setting"] == {"lamps.camera.tilt_deg": "40"}
    assert best["savings"] == pytest.approx(0.55) and best["seeds"] == 2
