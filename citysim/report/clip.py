"""`citysim render`: one lamp camera's view of a scenario, with its ground truth.

Runs the street's traffic (no controller: every lamp at its dim level, or
full with ``lamps_full``) and renders the chosen lamp's camera at its frame
rate. Writes camera.mp4 (truth boxes in white; with ``detect``, the real
detector's boxes in class colours beside them), truth.csv and topdown.png. ``plain``:
camera.mp4 holds the camera's frames as they are, nothing drawn (the truth stays in
truth.csv), to be fed to ``python -m detector`` and its calibration like real footage.
"""

from __future__ import annotations

import csv
from pathlib import Path

import cv2
import numpy as np
from tqdm import tqdm

from citysim.config.scenario import Scenario
from citysim.report.topdown import plot_topdown
from citysim.sim.loop import RunError
from citysim.sim.night import build_night
from detector.draw import draw_boxes, draw_detections
from detector.outdir import staged_output

TRUTH_CSV_HEADER = ["frame", "t_s", "object_id", "cls", "x", "y", "w", "h", "touches_border"]


#: Which of a pole's cameras ``render_clip`` films: its own (looking the lamps' heading) or the
#: backward one (``lamps.camera.back_heading_deg``).
CAMERA_SIDES = ("forward", "backward")


def render_clip(scenario: Scenario, lamp: int, duration_s: float, out_dir: Path, *, start_s: float = 0.0,
                detect: bool = False, lamps_full: bool = False, progress: bool = True,
                camera_side: str = "forward", plain: bool = False) -> dict:
    """Render lamp ``lamp``'s camera (``camera_side``: its forward or backward one) from ``start_s``
    for ``duration_s`` simulated seconds into ``out_dir``.

    The traffic runs from the start of the night; frames are taken from ``start_s`` on. With
    ``detect`` the video shows the truth (left) beside the detector's boxes (right), each half
    captioned. ``plain``: no truth boxes and no captions drawn (with ``detect``, the plain frame
    beside the detector's boxes).
    """
    check_clip(scenario, lamp, duration_s, start_s, camera_side)  # before the night is built: a mistake costs nothing
    night = build_night(scenario)
    night.start_physics()
    # Street.cameras: the poles' own cameras in lamp order, then the backward ones
    renderer = night.renderer(lamp if camera_side == "forward" else night.n_lamps + lamp)
    camera = renderer.camera
    level = 1.0 if lamps_full else scenario.lamps.luminaire.dim_level
    levels = np.full(night.n_lamps, level)
    detector = None
    if detect:
        from detector.detector import Detector
        from detector.general_model import default_model

        detector = Detector(camera, model=default_model())
    fps = camera.fps
    n_frames = int(duration_s * fps)
    tracks: dict[int, list[tuple[float, float]]] = {}
    stats = {"frames": n_frames, "truth_rows": 0, "frames_with_target_detected": 0}
    size = (camera.width_px * (2 if detect else 1), camera.height_px)
    with staged_output(out_dir) as stage:
        writer = cv2.VideoWriter(str(stage / "camera.mp4"), cv2.VideoWriter_fourcc(*"mp4v"), fps, size)
        try:
            with open(stage / "truth.csv", "w", newline="") as fh:
                rows = csv.writer(fh)
                rows.writerow(TRUTH_CSV_HEADER)
                for k in tqdm(range(n_frames), unit="frame", desc=f"render lamp {lamp} {camera_side}", disable=not progress):
                    t = start_s + k / fps
                    night.run_until(t + 1e-6)  # the physics tick at t included
                    agents = night.street.in_world(night.agents)
                    for a in agents:
                        tracks.setdefault(a.object_id, []).append((a.x_m, a.y_m))
                    frame = renderer.render(t, agents, levels)
                    for obj in frame.truth:
                        rows.writerow([k, f"{t:.3f}", obj.object_id, obj.cls, obj.x, obj.y, obj.w, obj.h, int(obj.touches_border)])
                    stats["truth_rows"] += len(frame.truth)
                    writer.write(_clip_frame(frame, detector, stats, plain))
        finally:
            writer.release()
        plot_topdown(night.street, [s.camera for s in night.street.cameras], {i: np.array(p) for i, p in tracks.items()},
                     stage / "topdown.png")
    return stats


def check_clip(scenario: Scenario, lamp: int, duration_s: float, start_s: float, camera_side: str = "forward") -> None:
    """The clip's arguments against the scenario, before anything is built or rendered."""
    n_lamps = len(scenario.lamps.positions_x_m)
    if not 0 <= lamp < n_lamps:
        raise RunError(f"--lamp: must be in 0..{n_lamps - 1} for {scenario.name}, got {lamp}")
    if camera_side not in CAMERA_SIDES:
        raise RunError(f"--camera: must be one of {', '.join(CAMERA_SIDES)}, got {camera_side!r}")
    if camera_side == "backward" and scenario.lamps.cameras_per_pole < 2:
        raise RunError(f"--camera: {scenario.name} has no backward cameras (set lamps.camera.back_heading_deg, "
                       "as scenarios/suburban_night_two_way.yaml does)")
    if not duration_s > 0:
        raise RunError(f"--duration: must be > 0 s, got {duration_s}")
    if not 0 <= start_s < scenario.duration_s:
        raise RunError(f"--start: must be >= 0 and < {scenario.duration_s:g} s (the scenario's night), got {start_s:g}")


def _clip_frame(frame, detector, stats: dict, plain: bool = False) -> np.ndarray:
    """The video frame: truth boxes (``plain``: none), and with a detector its boxes beside them,
    each half captioned (``plain``: not)."""
    truth_img = cv2.cvtColor(frame.image, cv2.COLOR_GRAY2BGR)
    if not plain:
        draw_boxes(truth_img, [(o.x, o.y, o.w, o.h) for o in frame.truth], [f"{o.cls}#{o.object_id}" for o in frame.truth])
    if detector is None:
        return truth_img
    detections = detector.process(frame.image)
    stats["frames_with_target_detected"] += detector.is_target(detections)
    detected_img = draw_detections(frame.image, detections)
    if not plain:
        _caption(truth_img, "truth")
        _caption(detected_img, "detector")
    return np.hstack([truth_img, detected_img])


def _caption(img: np.ndarray, text: str) -> None:
    """A caption in the bottom-left corner, dark-outlined so it reads on any background."""
    org = (4, img.shape[0] - 6)
    cv2.putText(img, text, org, cv2.FONT_HERSHEY_SIMPLEX, 0.45, (0, 0, 0), 3, cv2.LINE_AA)
    cv2.putText(img, text, org, cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 255), 1, cv2.LINE_AA)
