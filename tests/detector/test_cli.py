"""`python -m detector VIDEO --camera CAM --out DIR` on videos made here, and its user errors."""

import csv
import math
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from detector.__main__ import CSV_HEADER, main
from detector.camera import CameraModel
from detector.train.shapes import pedestrian_shape, silhouette_mask

SCENE_B = dict(height_m=3.1, tilt_deg=22.0, focal_mm=0.73, sensor_w_mm=0.7, sensor_h_mm=0.52, width_px=320,
               height_px=240, fps=15.0)
FORWARD_M = 10.0


def write_walker_video(path: Path, camera: CameraModel, forward_m: float, n_frames: int = 90) -> None:
    """A 1.75 m walker crossing the view at a fixed forward distance, on a dark noisy ground."""
    rng = np.random.default_rng(3)
    base = np.full((camera.height_px, camera.width_px), 40, np.uint8)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), camera.fps, (camera.width_px, camera.height_px))
    assert writer.isOpened()
    speed_mps, step_m = 1.4, 0.7
    for k in range(n_frames):
        lateral_m = 3.0 - speed_mps * k / camera.fps  # walks from left (+y) to right
        phase = 2 * math.pi * (speed_mps * k / camera.fps) / (2 * step_m)
        frame = base.copy()
        shape = pedestrian_shape(forward_m, lateral_m, -math.pi / 2, 0.5, 1.75, step_m, phase)
        sil = silhouette_mask(camera, shape)
        if sil is not None:
            x0, y0 = sil.offset_px
            h, w = sil.mask.shape
            frame[y0 : y0 + h, x0 : x0 + w][sil.mask > 0] = 190
        noisy = np.clip(frame + rng.normal(0, 2.5, frame.shape), 0, 255).astype(np.uint8)
        writer.write(cv2.cvtColor(noisy, cv2.COLOR_GRAY2BGR))
    writer.release()


@pytest.fixture(scope="module")
def scene_b_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cli")
    camera = CameraModel(**SCENE_B)
    (folder / "cam.yaml").write_text(yaml.safe_dump(SCENE_B))
    write_walker_video(folder / "walker.mp4", camera, FORWARD_M)
    return folder


def read_rows(path: Path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_cli_detects_a_walker_at_its_distance_as_a_pedestrian(scene_b_files):
    out = scene_b_files / "out"
    assert main([str(scene_b_files / "walker.mp4"), "--camera", str(scene_b_files / "cam.yaml"), "--out", str(out),
                 "--no-progress"]) == 0
    with open(out / "detections.csv") as fh:
        assert fh.readline().strip().split(",") == CSV_HEADER
    rows = read_rows(out / "detections.csv")
    targets = [r for r in rows if r["cls"] != "noise"]
    frames_with_target = {int(r["frame"]) for r in targets}
    # the walker is whole in view for most of the clip; MOG2 needs a few frames to learn the ground
    in_view = 0
    camera = CameraModel(**SCENE_B)
    for k in range(90):
        shape = pedestrian_shape(FORWARD_M, 3.0 - 1.4 * k / 15, -math.pi / 2, 0.5, 1.75, 0.7, 0.0)
        sil = silhouette_mask(camera, shape)
        in_view += sil is not None and not sil.touches_border and k >= 5
    assert len(frames_with_target) >= 0.8 * in_view, (len(frames_with_target), in_view)
    distance = np.array([float(r["distance_m"]) for r in targets])
    assert np.median(np.abs(distance - FORWARD_M) / FORWARD_M) < 0.10
    assert np.mean(np.abs(distance - FORWARD_M) / FORWARD_M < 0.10) > 0.8
    classes = [r["cls"] for r in targets]
    assert classes.count("pedestrian") / len(classes) > 0.7, classes
    cap = cv2.VideoCapture(str(out / "annotated.mp4"))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 90


def run_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "detector", *args], capture_output=True, text=True)


def assert_clean_failure(res: subprocess.CompletedProcess, out: Path, *needles: str) -> None:
    assert res.returncode == 2, res.stderr
    line = res.stderr.strip()
    assert "Traceback" not in line and line.count("\n") == 0, line
    for needle in needles:
        assert needle in line, line
    assert not out.exists()
    assert not list(out.parent.glob(f".{out.name}.partial-*"))


def test_missing_video_is_one_clear_error_and_writes_nothing(scene_b_files, tmp_path):
    out = tmp_path / "out"
    res = run_cli(str(tmp_path / "nope.mp4"), "--camera", str(scene_b_files / "cam.yaml"), "--out", str(out))
    assert_clean_failure(res, out, "nope.mp4", "not found")


def test_corrupt_video_is_one_clear_error(scene_b_files, tmp_path):
    bad = tmp_path / "corrupt.mp4"
    bad.write_bytes(np.random.default_rng(0).integers(0, 256, 20000, dtype=np.uint8).tobytes())
    out = tmp_path / "out"
    res = run_cli(str(bad), "--camera", str(scene_b_files / "cam.yaml"), "--out", str(out))
    assert_clean_failure(res, out, "corrupt.mp4")


def test_camera_file_with_a_wrong_field_names_it(scene_b_files, tmp_path):
    cam = tmp_path / "typo.yaml"
    cam.write_text(yaml.safe_dump({**{k: v for k, v in SCENE_B.items() if k != "tilt_deg"}, "tilt": 22}))
    out = tmp_path / "out"
    res = run_cli(str(scene_b_files / "walker.mp4"), "--camera", str(cam), "--out", str(out))
    assert_clean_failure(res, out, "typo.yaml", "tilt: unknown field", "tilt_deg")


def test_camera_that_cannot_see_the_ground_is_refused(scene_b_files, tmp_path):
    cam = tmp_path / "sky.yaml"
    cam.write_text(yaml.safe_dump({**SCENE_B, "tilt_deg": -25.0}))
    out = tmp_path / "out"
    res = run_cli(str(scene_b_files / "walker.mp4"), "--camera", str(cam), "--out", str(out))
    assert_clean_failure(res, out, "sky.yaml", "cannot see the ground", "tilt_deg")


def test_camera_for_another_aspect_ratio_is_refused(scene_b_files, tmp_path):
    cam = tmp_path / "wide.yaml"
    cam.write_text(yaml.safe_dump({**SCENE_B, "width_px": 424}))
    out = tmp_path / "out"
    res = run_cli(str(scene_b_files / "walker.mp4"), "--camera", str(cam), "--out", str(out))
    assert_clean_failure(res, out, "wide.yaml", "aspect ratio")
