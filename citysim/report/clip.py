"""`citysim render`: one lamp camera's view of a scenario, with its ground truth.

Runs the street's traffic (no controller: every lamp at its dim level, or
full with ``lamps_full``) and renders the chosen lamp's camera at its frame
rate. Writes camera.mp4 (truth boxes in white; with ``detect``, the real
detector's boxes in class colours beside them), truth.csv and topdown.png.
"""

from __future__ import annotations

import csv
from pathlib import Path

import cv2
import numpy as np
import simpy
from tqdm import tqdm

from citysim.config.scenario import Scenario
from citysim.render.camera import CameraRenderer
from citysim.report.topdown import plot_topdown
from citysim.sim.loop import RunError, render_params_of, seed_streams
from citysim.world.physics import World
from citysim.world.street import build_street
from citysim.world.traffic import start_traffic
from detector.draw import draw_boxes, draw_detections
from detector.outdir import staged_output

TRUTH_CSV_HEADER = ["frame", "t_s", "object_id", "cls", "x", "y", "w", "h", "touches_border"]


def render_clip(scenario: Scenario, lamp: int, duration_s: float, out_dir: Path, *, detect: bool = False,
                lamps_full: bool = False, progress: bool = True) -> dict:
    """Render lamp ``lamp``'s camera for ``duration_s`` simulated seconds into ``out_dir``."""
    rngs = seed_streams(scenario.seed)
    street = build_street(scenario)
    if not 0 <= lamp < len(street.lamps):
        raise RunError(f"--lamp: must be in 0..{len(street.lamps) - 1} for {scenario.name}, got {lamp}")
    if not duration_s > 0:
        raise RunError(f"--duration: must be > 0 s, got {duration_s}")
    world = World(street, rngs["world"])
    env = simpy.Environment()
    start_traffic(env, world, scenario, rngs["traffic"])
    camera = street.lamps[lamp].camera
    renderer = CameraRenderer(camera, street, render_params_of(scenario), rngs["render"].spawn(len(street.lamps))[lamp])
    level = 1.0 if lamps_full else scenario.lamps.luminaire.dim_level
    levels = np.full(len(street.lamps), level)
    detector = None
    if detect:
        from detector.classifier import default_model
        from detector.detector import Detector

        detector = Detector(camera, model=default_model())
    dt_s = 1.0 / scenario.physics_hz
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
                t_phys = 0.0
                for k in tqdm(range(n_frames), unit="frame", desc=f"render lamp {lamp}", disable=not progress):
                    t = k / fps
                    while t_phys + dt_s <= t + 1e-9:
                        env.run(until=t_phys + dt_s)
                        world.step(dt_s)
                        t_phys += dt_s
                    agents = world.states()
                    for a in agents:
                        tracks.setdefault(a.object_id, []).append((a.x_m, a.y_m))
                    frame = renderer.render(t, agents, levels)
                    for obj in frame.truth:
                        rows.writerow([k, f"{t:.3f}", obj.object_id, obj.cls, obj.x, obj.y, obj.w, obj.h, int(obj.touches_border)])
                    stats["truth_rows"] += len(frame.truth)
                    truth_img = cv2.cvtColor(frame.image, cv2.COLOR_GRAY2BGR)
                    draw_boxes(truth_img, [(o.x, o.y, o.w, o.h) for o in frame.truth], [f"{o.cls}#{o.object_id}" for o in frame.truth])
                    if detector is not None:
                        detections = detector.process(frame.image)
                        stats["frames_with_target_detected"] += detector.is_target(detections)
                        truth_img = np.hstack([truth_img, draw_detections(frame.image, detections)])
                    writer.write(truth_img)
        finally:
            writer.release()
        plot_topdown(street, [s.camera for s in street.lamps], {i: np.array(p) for i, p in tracks.items()}, stage / "topdown.png")
    return stats
