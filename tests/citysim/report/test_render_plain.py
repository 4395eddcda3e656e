"""`citysim render --plain`: the camera's frames with nothing drawn on them, the truth in truth.csv."""

from types import SimpleNamespace

import cv2
import numpy as np

from citysim.cli import main
from citysim.report.clip import _clip_frame
from tests.citysim.test_cli import tiny


def _frames(path) -> list[np.ndarray]:
    cap = cv2.VideoCapture(str(path))
    frames = []
    while True:
        ok, frame = cap.read()
        if not ok:
            return frames
        frames.append(frame)


def test_a_plain_frame_is_the_camera_image_untouched():
    image = np.random.default_rng(0).integers(0, 200, (240, 320), dtype=np.uint8)
    truth = [SimpleNamespace(x=50, y=60, w=30, h=80, cls="pedestrian", object_id=4)]
    frame = SimpleNamespace(image=image, truth=truth)
    plain = _clip_frame(frame, None, {}, plain=True)
    assert np.array_equal(plain, cv2.cvtColor(image, cv2.COLOR_GRAY2BGR))
    drawn = _clip_frame(frame, None, {})
    assert (drawn != plain).any()  # the truth box is drawn without --plain
    assert (drawn[60, 50] == 255).all()  # its white corner


def test_render_plain_keeps_the_truth_and_draws_nothing(tmp_path):
    outs = {kind: tmp_path / kind for kind in ("boxes", "plain")}
    scenario = str(tiny(tmp_path))
    for kind, out in outs.items():
        extra = ["--plain"] if kind == "plain" else []
        assert main(["render", scenario, "--lamp", "1", "--start", "12", "--duration", "3", "--out", str(out), "--no-progress",
                     *extra]) == 0
    assert (outs["plain"] / "truth.csv").read_text() == (outs["boxes"] / "truth.csv").read_text()
    boxes, plain = (_frames(out / "camera.mp4") for out in outs.values())
    assert len(plain) == len(boxes) == 45
    # where a truth box is drawn, the plain video holds the scene, not a white outline
    rows = (outs["plain"] / "truth.csv").read_text().splitlines()[1:]
    assert rows, "the clip should hold someone"
    differs = 0
    for row in rows:
        k, _, _, _, x, y, w, h, _ = row.split(",")
        k, x, y = int(k), int(x), int(y)
        differs += int(boxes[k][y, x].mean()) - int(plain[k][y, x].mean()) > 40
    assert differs > 0.5 * len(rows)
