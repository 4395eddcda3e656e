"""The real detector on the simulator's frames: a clear night on scenarios/suburban_night.yaml.

Prints the per-frame figure (pytest -s shows it) and holds it to the issue's bar: the detector finds
at least 90% of the fully visible pedestrians within 25 m of the camera.
"""

from pathlib import Path

import numpy as np
import simpy

from citysim.config.scenario import load_scenario, override
from citysim.metrics.confusion import iou_matrix
from citysim.render.camera import CameraRenderer
from citysim.sim.loop import render_params_of, seed_streams
from citysim.world.physics import World
from citysim.world.street import build_street
from citysim.world.traffic import start_traffic
from detector.classifier import default_model
from detector.detector import Detector

REPO = Path(__file__).resolve().parents[2]


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
    rngs = seed_streams(scenario.seed)
    street = build_street(scenario)
    lamp = 0  # the first lamp's camera looks into the walkers coming from the far end and those leaving
    camera = street.lamps[lamp].camera
    world = World(street, rngs["world"])
    env = simpy.Environment()
    start_traffic(env, world, scenario, rngs["traffic"])
    renderer = CameraRenderer(camera, street, render_params_of(scenario), rngs["render"])
    detector = Detector(camera, model=default_model())
    levels = np.full(len(street.lamps), scenario.lamps.luminaire.dim_level)
    dt = 1.0 / scenario.physics_hz
    steps_per_frame = round(scenario.physics_hz / camera.fps)
    seen = found = 0
    for k in range(int(scenario.duration_s * camera.fps)):
        for _ in range(steps_per_frame):
            env.run(until=env.now + dt)
            world.step(dt)
        frame = renderer.render(k / camera.fps, world.states(), levels, frame_index=k)
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
