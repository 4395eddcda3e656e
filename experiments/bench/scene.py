"""Rendering cost per frame: a fixed suburban street, 320x240, 0/5/20 agents.

``make bench`` (``experiments.bench.figures.bench_render``) times these frames
interleaved with the detector; ``bench_render()`` here, printed by ``python -m
experiments.bench.scene``, times the renderer alone (median wall time, a quick
check while working on it). The scene is built here by
hand (two lanes, two sidewalks, a lamp chain, walls, trees, a parked car) so
the figure does not depend on any scenario file. Every frame has noise,
motion blur, lens distortion, lamp light and swaying crowns on - the default
the default ``EnvironmentSpec`` - and agents of every class moving through the view, some
with their lights on.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence

import numpy as np

from citysim.config.scenario import EnvironmentSpec
from citysim.render.camera import CameraRenderer
from citysim.world.agents import AgentState, MemberState
from citysim.world.street import LampSite, Lane, Sidewalk, StaticObject, Street
from detector.camera import CameraModel

BENCH_CAMERA = CameraModel(
    height_m=4.0,
    tilt_deg=20.0,
    focal_mm=0.73,
    sensor_w_mm=0.7,
    sensor_h_mm=0.52,
    width_px=320,
    height_px=240,
    k1=-0.25,
    k2=0.06,
)


def bench_street(
    camera: CameraModel = BENCH_CAMERA, n_lamps: int = 4, spacing_m: float = 30.0
) -> Street:
    """A two-lane street with sidewalks, lamps every ``spacing_m`` on the left side (y = 6.8 m)."""
    lamps = []
    for i in range(n_lamps):
        x = 10.0 + spacing_m * i
        cam = camera.placed(x_m=x, y_m=6.8, yaw_deg=-15.0 if i % 2 == 0 else 195.0)
        lamps.append(LampSite(i, x, 6.8, 6.0, cam, x - spacing_m / 2, x + spacing_m / 2))
    scenery = (
        StaticObject("wall", 60.0, 9.0, 120.0, 0.3, 2.0, 0.5),
        StaticObject("building", 30.0, -13.0, 16.0, 8.0, 7.0, 0.4),
        StaticObject("building", 65.0, -13.0, 20.0, 8.0, 9.0, 0.45),
        StaticObject("tree", 22.0, 7.5, 3.0, 3.0, 6.0, 0.5),
        StaticObject("tree", 40.0, -7.5, 3.5, 3.5, 7.0, 0.5),
        StaticObject("parked_car", 30.0, 3.0, 4.3, 1.8, 1.5, 0.55),
        StaticObject("hedge", 50.0, -7.2, 8.0, 0.8, 1.2, 0.35),
    )
    return Street(
        120.0,
        (Lane(-1.75, 3.5, -1), Lane(1.75, 3.5, 1)),
        (Sidewalk(-5.0, 3.0), Sidewalk(5.0, 3.0)),
        tuple(lamps),
        scenery,
    )


_CLASS_CYCLE = ("pedestrian", "vehicle", "cyclist", "group", "pedestrian", "animal")
_SIZES = {  # (length, width, height, speed m/s, y of the path)
    "pedestrian": (0.6, 0.5, 1.75, 1.4, 4.6),
    "group": (0.6, 1.6, 1.7, 1.2, -4.8),
    "cyclist": (1.7, 0.6, 1.8, 5.0, 1.2),
    "vehicle": (4.4, 1.8, 1.5, 13.0, -1.75),
    "animal": (0.8, 0.3, 0.5, 2.0, 3.5),
}


def bench_agents(n: int, t_s: float, rng_seed: int = 7) -> list[AgentState]:
    """``n`` agents of all classes spread 12-40 m along the street, moving at their speeds."""
    rng = np.random.default_rng(rng_seed)
    out = []
    for i in range(n):
        cls = _CLASS_CYCLE[i % len(_CLASS_CYCLE)]
        length, width, height, speed, y = _SIZES[cls]
        direction = 1.0 if rng.random() < 0.5 else -1.0
        # each agent shuttles through the view (x in 12..40 m), so all of them stay in the frame
        x = 12.0 + (rng.uniform(0.0, 28.0) + direction * speed * t_s) % 28.0
        members = ()
        if cls == "group":
            members = (
                MemberState(0.0, 0.5, 0.5, 1.75, 0.6, t_s * 6.0),
                MemberState(0.1, -0.5, 0.5, 1.6, 0.6, t_s * 6.0 + 2.0),
            )
        out.append(
            AgentState(
                i,
                cls,
                x,
                y + rng.uniform(-0.3, 0.3),
                0.0 if direction > 0 else math.pi,
                speed,
                length,
                width,
                height,
                gait_phase_rad=t_s * 6.0 + i,
                members=members,
                light_on=bool(i % 3 == 1),
            )
        )
    return out


#: The bench's night: clear, a light wind swaying the crowns, the default sensor.
BENCH_NIGHT = EnvironmentSpec(wind_mps=3.0)


def bench_render(
    n_objects_list: Sequence[int] = (0, 5, 20),
    frames: int = 150,
    environment: EnvironmentSpec | None = None,
) -> dict[int, float]:
    """Median wall time per rendered frame, ms, for each number of agents in view."""
    street = bench_street()
    camera = street.lamps[0].camera
    levels = [1.0, 1.0, 0.0, 0.0]
    out: dict[int, float] = {}
    for n in n_objects_list:
        renderer = CameraRenderer(
            camera, street, environment or BENCH_NIGHT, np.random.default_rng(0)
        )
        states = [bench_agents(n, k / camera.fps) for k in range(frames)]
        for k in range(min(10, frames)):  # warm caches (kernels, spot textures)
            renderer.render(k / camera.fps, states[k], levels)
        times = np.empty(frames)
        for k in range(frames):
            t0 = time.perf_counter()
            renderer.render(k / camera.fps, states[k], levels)
            times[k] = time.perf_counter() - t0
        out[int(n)] = float(np.median(times) * 1e3)
    return out


if __name__ == "__main__":
    for n, ms in bench_render().items():
        print(f"{n:3d} objects: {ms:.2f} ms/frame")
