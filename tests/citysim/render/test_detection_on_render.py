"""The real detector on the simulator's frames: a clear night on scenarios/suburban_night.yaml.

Prints the per-frame figure (pytest -s shows it) and holds it to the issue's bar: the detector finds
at least 90% of the fully visible pedestrians within 25 m of the camera.
"""

from pathlib import Path

import numpy as np
import pytest

from citysim.config.scenario import load_scenario, override
from citysim.metrics.confusion import iou_matrix
from citysim.sim.night import build_night
from detector.detector import Detector
from detector.general_model import default_model

pytestmark = pytest.mark.slow  # real simulation or footage: tens of seconds

REPO = Path(__file__).resolve().parents[3]


def test_detector_finds_fully_visible_pedestrians_within_25_m():
    scenario = override(
        load_scenario(REPO / "scenarios" / "suburban_night.yaml"),
        {
            "duration_s": 60.0,
            "environment.insects_per_min": 0.0,  # a clear night: what is measured is the pedestrians
            "traffic.classes.pedestrian.rate_per_hour": 900.0,
            "traffic.classes.pedestrian.crossing_fraction": 0.0,
            "traffic.classes.pedestrian.flashlight_fraction": 0.0,
            "traffic.scripted": [{"cls": "pedestrian", "t_s": 0.0, "speed_kmh": 5.0, "direction": -1, "path": k % 2}
                                 for k in range(2)],
        },
    )
    night = build_night(scenario)  # the same night a run builds: its camera streams, its traffic
    lamp = 0  # the first lamp's camera looks into the walkers coming from the far end and those leaving
    night.start_physics()
    renderer = night.renderer(lamp)
    camera = renderer.camera
    detector = Detector(camera, model=default_model())
    levels = np.full(night.n_lamps, scenario.lamps.luminaire.dim_level)
    seen = found = 0
    for k in range(int(scenario.duration_s * camera.fps)):
        night.run_until(k / camera.fps + 1e-6)
        frame = renderer.render(k / camera.fps, night.agents, levels, frame_index=k)
        detections = detector.process(frame.image)
        if k < camera.fps:  # the background model learns the street in the first second
            continue
        walkers = [t for t in frame.truth if t.cls == "pedestrian" and t.fully_visible and t.distance_m <= 25.0]
        if not walkers:
            continue
        truth_boxes = np.array([[t.x, t.y, t.w, t.h] for t in walkers], float)
        target_boxes = np.array([d.box_px for d in detections if d.p_target >= detector.target_threshold], float)
        seen += len(walkers)
        if len(target_boxes):
            found += int((iou_matrix(truth_boxes, target_boxes.reshape(-1, 4)).max(axis=1) >= 0.3).sum())
    rate = found / seen
    print(f"\nsuburban_night lamp {lamp}: detector found {found} of {seen} fully visible pedestrians "
          f"within 25 m ({rate:.1%}), per frame")
    assert seen >= 100
    assert rate >= 0.90
