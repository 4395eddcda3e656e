"""`citysim run | render | plot` as a user meets them: outputs, and one clear error (exit 2) for bad input."""

import csv
import json
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from citysim.cli import main
from tests.citysim.streets import two_way_street

REPO = Path(__file__).resolve().parents[2]


def tiny(tmp_path: Path, **changes) -> Path:
    """Three lamps on a 100 m street with some traffic; written next to a copy of the scene-B camera."""
    data = {
        "name": "tiny",
        "seed": 3,
        "duration_s": 20.0,
        "street": two_way_street(100),
        "lamps": {"count": 3, "spacing_m": 30, "first_x_m": 20, "y_m": 6.2, "pole_height_m": 4.0,
                  "camera": {"file": "scene_b.yaml", "heading_deg": -10, "tilt_deg": 15}},
        "traffic": {"classes": {"pedestrian": {"rate_per_hour": 600}, "vehicle": {"rate_per_hour": 300}}},
        "controllers": ["always_on", "pir", "detector"],
    }
    for dotted, value in changes.items():
        node = data
        *head, last = dotted.split(".")
        for key in head:
            node = node.setdefault(key, {})
        node[last] = value
    (tmp_path / "scene_b.yaml").write_text((REPO / "scenarios" / "cameras" / "scene_b.yaml").read_text())
    path = tmp_path / "tiny.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "citysim", *args], capture_output=True, text=True, cwd=REPO)


def is_real_plot(path: Path) -> bool:
    img = cv2.imread(str(path))
    return img is not None and img.shape[0] > 100 and np.unique(img.reshape(-1, 3), axis=0).shape[0] > 20


def test_run_writes_summary_tables_and_plots(tmp_path):
    out = tmp_path / "run"
    assert main(["run", str(tiny(tmp_path)), "--out", str(out), "--no-progress", "--workers", "1"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["seed"] == 3 and summary["duration_s"] == 20.0
    assert set(summary["controllers"]) == {"always_on", "pir", "detector"}
    for name, c in summary["controllers"].items():
        for key in ("energy_kwh", "savings_vs_always_on", "lag_p50_s", "lag_p95_s", "lag_max_s", "dark_exposure_s",
                    "unlit_crossings", "switches", "detection"):
            assert key in c, (name, key)
    assert summary["controllers"]["always_on"]["savings_vs_always_on"] == pytest.approx(0.0, abs=1e-12)
    assert summary["controllers"]["detector"]["detection"]["frames"] > 0
    with open(out / "lamps.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0]) == ["controller", "t_s", "lamp", "level", "power_w"]
    assert len(rows) == 3 * 3 * 20  # three controllers, three lamps, one row per simulated second
    with open(out / "objects.csv") as fh:
        assert fh.readline().strip().split(",")[:4] == ["controller", "object_id", "cls", "lamp"]
    plots = sorted((out / "plots").glob("*.png"))
    assert len(plots) >= 3 and all(is_real_plot(p) for p in plots)
    assert not list(tmp_path.glob(".run.partial-*"))


def test_render_writes_video_truth_and_topdown(tmp_path):
    out = tmp_path / "cam"
    assert main(["render", str(tiny(tmp_path)), "--lamp", "1", "--duration", "4", "--out", str(out), "--detect",
                 "--no-progress"]) == 0
    cap = cv2.VideoCapture(str(out / "camera.mp4"))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 60
    with open(out / "truth.csv") as fh:
        assert fh.readline().strip() == "frame,t_s,object_id,cls,x,y,w,h,touches_border"
    assert is_real_plot(out / "topdown.png")


@pytest.mark.parametrize(
    ("change", "needles"),
    [
        ({"lamps.luminaire.rated_power_w": -60}, ["lamps.luminaire.rated_power_w", "greater than 0"]),
        ({"lamps.luminaire.hold_s": 0.01}, ["lamps.luminaire.hold_s", "one camera frame"]),
        ({"lamps.colour": "red"}, ["lamps.colour", "unknown field"]),
        ({"traffic.classes.vehicle.speed_kmh": {"min": -5, "max": 40}}, ["traffic.classes.vehicle.speed_kmh.min"]),
        ({"controllers": ["always_on", "magic"]}, ["controllers", "magic", "detector_network"]),
        ({"lamps.camera.tilt_deg": -40}, ["lamps.camera", "tilt_deg"]),
    ],
)
def test_bad_scenario_is_one_clear_error_and_exit_2(tmp_path, change, needles):
    out = tmp_path / "run"
    res = cli("run", str(tiny(tmp_path, **change)), "--out", str(out), "--no-progress")
    assert res.returncode == 2, res.stderr
    message = res.stderr.strip()
    assert message.count("\n") == 0 and "Traceback" not in message, message
    assert "tiny.yaml" in message or "controllers" in message
    for needle in needles:
        assert needle in message, message
    assert not out.exists()


def test_unknown_controller_on_the_command_line(tmp_path):
    res = cli("run", str(tiny(tmp_path)), "--out", str(tmp_path / "o"), "--controllers", "always_on,nope")
    assert res.returncode == 2 and "controllers: unknown 'nope'" in res.stderr
