"""`python -m detector` and `citysim detect` share one parser; clear words for a folder, an empty
file or no camera file; Ctrl-C and SIGTERM end a run with one line and nothing half-written."""

import signal
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from detector.camera import CameraModel
from tests.detector.test_cli import SCENE_B, assert_clean_failure, run_cli, write_walker_video

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def walker(tmp_path_factory):
    folder = tmp_path_factory.mktemp("shared")
    (folder / "cam.yaml").write_text(yaml.safe_dump(SCENE_B))
    write_walker_video(folder / "walker.mp4", CameraModel(**SCENE_B), 10.0, n_frames=40)
    return folder


def _options(parser) -> dict[str, tuple]:
    return {a.dest: (tuple(a.option_strings), a.default, a.required) for a in parser._actions if a.dest != "help"}


def test_citysim_detect_takes_every_option_of_the_detector_cli():
    import argparse

    from citysim.cli import build_parser
    from detector.__main__ import _detect_parser

    commands = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)).choices
    mine, theirs = _options(commands["detect"]), _options(_detect_parser())
    assert mine == theirs
    assert {"no_video", "full_frame", "keep_edge_regions", "model", "max_width"} <= set(mine)


def test_citysim_detect_runs_with_no_video(walker, tmp_path, capsys):
    from citysim.cli import main

    out = tmp_path / "out"
    code = main(["detect", str(walker / "walker.mp4"), "--camera", str(walker / "cam.yaml"), "--out", str(out),
                 "--no-video", "--no-progress"])
    assert code == 0, capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == ["detections.csv", "summary.json", "tracks.csv"]


def test_a_folder_given_as_the_video_is_called_a_folder(walker, tmp_path):
    out = tmp_path / "out"
    res = run_cli(str(tmp_path), "--camera", str(walker / "cam.yaml"), "--out", str(out))
    assert_clean_failure(res, out, str(tmp_path), "is a folder, not a video")


def test_an_empty_video_file_is_called_empty(walker, tmp_path):
    empty = tmp_path / "empty.mp4"
    empty.touch()
    out = tmp_path / "out"
    res = run_cli(str(empty), "--camera", str(walker / "cam.yaml"), "--out", str(out))
    assert_clean_failure(res, out, "empty.mp4", "empty (0 bytes)")


def test_without_a_camera_file_it_says_how_to_get_one(walker, tmp_path):
    out = tmp_path / "out"
    res = run_cli(str(walker / "walker.mp4"), "--out", str(out))
    assert_clean_failure(res, out, "--camera", "python -m detector calibrate", "--hfov-deg")


@pytest.mark.slow
@pytest.mark.parametrize(("sig", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_an_interrupted_run_says_so_in_one_line_and_leaves_nothing(tmp_path, sig, code):
    """A real process gets a real signal while it works through a long video."""
    video = tmp_path / "long.avi"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 15.0, (320, 240))
    rng = np.random.default_rng(0)
    frames = [rng.integers(0, 255, (240, 320, 3), dtype=np.uint8) for _ in range(8)]
    for k in range(3000):  # noise: every frame full of regions, minutes of work
        writer.write(frames[k % 8])
    writer.release()
    (tmp_path / "cam.yaml").write_text(yaml.safe_dump(SCENE_B))
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "detector", str(video), "--camera", str(tmp_path / "cam.yaml"),
                             "--out", str(out), "--no-progress"], stderr=subprocess.PIPE, text=True)
    # wait until it is writing (its staging folder exists), then interrupt it
    for _ in range(600):
        if list(tmp_path.glob(".out.partial-*")) or proc.poll() is not None:
            break
        time.sleep(0.1)
    assert proc.poll() is None, "the run ended before it could be interrupted"
    time.sleep(0.5)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == code, err
    assert "Traceback" not in err, err
    assert err.strip().splitlines()[-1] == f"interrupted: {out} left as it was", err
    assert not out.exists() and not list(tmp_path.glob(".out.partial-*"))
