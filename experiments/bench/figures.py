"""`make bench`: speed and memory figures, never pass/fail.

Each section prints its own figures beside the floor it is compared with,
measured in the same run on the same frames:

* detector: frames/s single-threaded, cropped to the band where a target within
  range can appear (``detector.roi``) and on the full frame, with tracks and without,
  vs OpenCV's own full-frame floor (CLAHE + MOG2 + opening + contours), on sequences
  drawn through each of the paper's Table 2 cameras, scene B's lens at 480x360 beside
  320x240, and the suburban lamp camera;
* renderer: ms per frame with 0, 5 and 20 objects, beside the detector's ms/frame;
* simulation: simulated seconds per wall second per controller replaying the recorded traffic
  (as in a comparison), and of the traffic recorder, which runs once for all; peak memory;
* traffic: CPU seconds of recording the world alone (the compiled step) at 22:00 and 02:00;
* sweeps: a 16-point sweep on 2 Dask workers vs 1;
* whole night: every controller of suburban_night through one comparison on 2 workers, the
  first 10 minutes at full fidelity scaled to the night (``--night``: the whole night, measured;
  long), and fast mode from a sample of each hour of the night and as one whole-night run;
* year: ``citysim year`` of suburban_night in fast mode, every controller;
* city: a three-street city's year on 1 and 2 Dask workers (wall, CPU, per-worker peak memory).

Each whole-night and year figure is printed beside the figure measured before.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import cv2
import numpy as np

cv2.setNumThreads(1)  # the paper's implementation is single-threaded, and so is a lamp's budget


REPO = Path(__file__).resolve().parents[2]
# what walks and drives through the bench's frames: (width m, height m, brightness DN), cycled
_BENCH_OBJECTS = ((0.5, 1.75, 170), (1.8, 1.5, 200), (0.6, 1.8, 160), (1.6, 1.7, 150), (0.5, 1.6, 180))


def bench_cameras() -> dict:
    """The paper's Table 2 cameras (scenes A, B and C/D), scene B's lens at 480x360 beside its
    320x240 (the same 4:3 view at the next camera mode: the paper's 320x240 floor and a lamp
    camera a size up), and the suburban scenario's lamp camera."""
    from citysim.config.scenario import load_scenario
    from detector.camera import CameraModel

    scene_a = dict(height_m=3.0, tilt_deg=13, focal_mm=3.67, sensor_w_mm=4.8, sensor_h_mm=3.6)
    scene_b = dict(height_m=3.1, tilt_deg=22, focal_mm=0.73, sensor_w_mm=0.7, sensor_h_mm=0.52)
    return {
        "scene A": CameraModel(**scene_a, width_px=424, height_px=240, name="scene_a"),
        "scene B": CameraModel(**scene_b, width_px=320, height_px=240, name="scene_b"),
        "scene B 480x360": CameraModel(**scene_b, width_px=480, height_px=360, name="scene_b_480"),
        "scene C/D": CameraModel.from_yaml(REPO / "scenarios" / "cameras" / "scene_cd.yaml"),
        "suburban lamp": load_scenario(REPO / "scenarios" / "suburban_night.yaml").lamps.camera_model,
    }


def camera_sequence(camera, n_frames: int = 300, n_objects: int = 5, seed: int = 0) -> list[np.ndarray]:
    """Dark noisy frames (brighter toward the bottom, as under an IR emitter) with bright upright
    ellipses of people's and cars' sizes crossing the view at forward distances of 4-35 m (some
    beyond the 25 m range), drawn through ``camera`` (distortion included)."""
    rng = np.random.default_rng(seed)
    h_px, w_px = camera.height_px, camera.width_px
    ramp = np.linspace(25.0, 55.0, h_px)[:, None]
    base = (ramp + rng.normal(0, 4, (h_px, w_px))).clip(0, 255).astype(np.uint8)
    distance_m = rng.uniform(4.0, 35.0, n_objects)
    half_view_m = distance_m * math.tan(math.radians(camera.horizontal_fov_deg) / 2) * 1.2
    lateral_m = rng.uniform(-1.0, 1.0, n_objects) * half_view_m
    speed_mps = rng.choice((-1.0, 1.0), n_objects) * rng.uniform(1.0, 4.0, n_objects)
    heading = camera.heading_unit
    left = np.array([-heading[1], heading[0]])
    frames = []
    for i in range(n_frames):
        img = base.copy()
        t_s = i / camera.fps
        for k in range(n_objects):
            width_m, height_m, level = _BENCH_OBJECTS[k % len(_BENCH_OBJECTS)]
            lat = (lateral_m[k] + speed_mps[k] * t_s + half_view_m[k]) % (2 * half_view_m[k])
            foot = camera.position_m[:2] + distance_m[k] * heading + (lat - half_view_m[k]) * left
            side = width_m / 2 * left
            pts = np.array([[*(foot - side), 0.0], [*(foot + side), 0.0], [*foot, height_m]])
            uv = camera.project(pts)
            if not np.all(np.isfinite(uv)):
                continue
            u_c, v_bottom = (uv[0] + uv[1]) / 2
            half_w, half_h = abs(uv[1, 0] - uv[0, 0]) / 2, (v_bottom - uv[2, 1]) / 2
            if half_w < 0.5 or half_h < 0.5 or not (-w_px < u_c < 2 * w_px):
                continue
            centre = (int(round(u_c)), int(round(v_bottom - half_h)))
            cv2.ellipse(img, centre, (int(round(half_w)), int(round(half_h))), 0, 0, 360, level, -1)
        frames.append(cv2.add(img, rng.normal(0, 3, (h_px, w_px)).astype(np.int8), dtype=cv2.CV_8U))
    return frames


class OpenCVFloor:
    """OpenCV's own work for the paper's pipeline, nothing else: the floor we compare against."""

    def __init__(self):
        self.clahe = cv2.createCLAHE(clipLimit=3.0, tileGridSize=(8, 8))
        self.mog2 = cv2.createBackgroundSubtractorMOG2(
            history=500, varThreshold=16, detectShadows=True
        )
        self.kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (3, 3))

    def process(self, frame: np.ndarray) -> None:
        m = self.mog2.apply(self.clahe.apply(frame))
        cv2.threshold(m, 170, 255, cv2.THRESH_BINARY, dst=m)
        cv2.morphologyEx(m, cv2.MORPH_OPEN, self.kernel, dst=m)
        cv2.dilate(m, self.kernel, dst=m)
        cv2.findContours(m, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)


def interleaved_cpu_ms(frames: list[np.ndarray], pipelines: dict) -> dict[str, float]:
    """CPU ms per frame of each pipeline, timed frame by frame in one loop.

    Interleaving and process CPU time (not wall time) keep the comparison fair on a shared,
    loaded machine: all pipelines meet the same cache state and the same interruptions; the
    order turns every frame, so none is always the one that brings the frame into the cache.
    """
    totals = dict.fromkeys(pipelines, 0.0)
    order = list(pipelines.items())
    for i, frame in enumerate(frames):
        k = i % len(order)
        for name, fn in order[k:] + order[:k]:
            t0 = time.process_time()
            fn(frame)
            totals[name] += time.process_time() - t0
    return {name: 1000.0 * total / len(frames) for name, total in totals.items()}


def peak_memory_mb(fn, frames) -> float:
    tracemalloc.start()
    for f in frames:
        fn(f)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak / 1e6


def bench_detector(n_frames: int = 300) -> dict:
    """Frames/s of the detector on the full frame and cropped to its range, with tracks (the
    default) and without (the paper's per-frame path), beside OpenCV's full-frame floor, per
    camera; the share of the frame's pixels each segments (MOG2, morphology, contours) and whose
    CLAHE histograms it takes (``detector.clahe``: the tiles the crop needs)."""
    from detector.detector import Detector
    from detector.general_model import default_model

    print(
        "== detector vs OpenCV floor (single thread, CPU time, interleaved frame by frame; "
        "crop: the band where a target within 25 m can appear) =="
    )
    model = default_model()
    out = {}
    for name, camera in bench_cameras().items():
        frames = camera_sequence(camera, n_frames)
        detectors = {
            "full frame, tracks": Detector(camera, model=model, crop_to_range=False),
            "crop, tracks": Detector(camera, model=model),
            "full frame, no tracks": Detector(camera, model=model, crop_to_range=False, tracking=False),
            "crop, no tracks": Detector(camera, model=model, tracking=False),
        }
        pipelines = {key: det.process for key, det in detectors.items()}
        ms = interleaved_cpu_ms(frames, {**pipelines, "floor": OpenCVFloor().process})
        mem = peak_memory_mb(Detector(camera, model=model).process, frames[:100])
        crop = detectors["crop, tracks"].crop
        print(
            f"{name} ({camera.width_px}x{camera.height_px}, crop rows {crop.top_px}-"
            f"{crop.bottom_px - 1}): OpenCV floor {1000 / ms['floor']:6.1f} frames/s; "
            f"detector peak Python heap {mem:.2f} MB"
        )
        out[name] = {"floor_ms": ms["floor"], "peak_mb": mem}
        for key, det in detectors.items():
            ratio = ms["floor"] / ms[key]
            histogrammed = det.segmenter.clahe_histogram_share
            out[name][key] = dict(
                ms=ms[key], segmented=det.crop.share, histogrammed=histogrammed, ratio=ratio
            )
            print(
                f"    {key:<22} {1000 / ms[key]:6.1f} frames/s  {det.crop.share:4.0%} of pixels "
                f"segmented, {histogrammed:4.0%} histogrammed for CLAHE  {ratio:.2f}x floor"
            )
    return out


def bench_render() -> dict:
    """Render ms per 320x240 frame with 0, 5 and 20 agents in view, beside the detector's ms on those frames."""
    from citysim.render.camera import CameraRenderer
    from detector.detector import Detector
    from detector.general_model import default_model
    from experiments.bench.scene import BENCH_NIGHT, bench_agents, bench_street

    print("== renderer vs detector (320x240, CPU ms per frame, interleaved) ==")
    street = bench_street()
    camera = street.lamps[0].camera
    levels = [1.0, 1.0, 0.0, 0.0]
    out = {}
    for n in (0, 5, 20):
        # an untimed pass first: numba compiles a kernel the first time a path needs it
        # (e.g. an agent behind a tree), which must not land inside the timed frames
        warm = CameraRenderer(camera, street, BENCH_NIGHT, np.random.default_rng(1))
        for k in range(160):
            warm.render(k / camera.fps, bench_agents(n, k / camera.fps), levels)
        del warm
        renderer = CameraRenderer(camera, street, BENCH_NIGHT, np.random.default_rng(0))
        detector = Detector(camera, model=default_model())
        render_s = detect_s = 0.0
        frames = 150
        for k in range(frames + 10):
            agents = bench_agents(n, k / camera.fps)
            t0 = time.process_time()
            image = renderer.render(k / camera.fps, agents, levels).image
            t1 = time.process_time()
            detector.process(image)
            t2 = time.process_time()
            if k >= 10:  # the first frames build MOG2's model and the still view's cache
                render_s += t1 - t0
                detect_s += t2 - t1
        out[n] = dict(render_ms=1000 * render_s / frames, detect_ms=1000 * detect_s / frames)
        print(
            f"{n:2d} agents: render {out[n]['render_ms']:.2f} ms   detect {out[n]['detect_ms']:.2f} ms   "
            f"render/detect {out[n]['render_ms'] / out[n]['detect_ms']:.2f}"
        )
    return out


_SIM_CHILD = """
import json, resource, sys, time, cv2
cv2.setNumThreads(1)
from citysim.config.scenario import ControllerSpec, load_scenario, override
from citysim.sim.loop import run_controller
scenario = override(load_scenario(sys.argv[1]), {"duration_s": float(sys.argv[3])})
t0 = time.perf_counter()
run_controller(scenario, ControllerSpec(name=sys.argv[2]), traffic=sys.argv[4])
wall_s = time.perf_counter() - t0
try:  # this process's own peak: ru_maxrss would also count the parent's memory at the fork
    with open("/proc/self/status") as f:
        peak_mb = next(int(line.split()[1]) for line in f if line.startswith("VmHWM")) / 1024
except OSError:
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps({"wall_s": wall_s, "max_rss_mb": peak_mb}))
"""


def bench_sim(
    scenario_path: str = "scenarios/suburban_night.yaml", durations_s=(60.0, 180.0)
) -> dict:
    """Simulated seconds per wall second per controller replaying the traffic (recorded once
    here, timed), and peak memory at two run lengths (flat = streaming)."""
    import json
    import subprocess

    from citysim.config.scenario import load_scenario, override
    from citysim.control.registry import CONTROLLERS
    from citysim.sim.replay import record_traffic

    print(f"== simulation: {scenario_path}, per controller (each in a fresh process, replaying the traffic) ==")
    out = {}
    tmp = tempfile.TemporaryDirectory(prefix="bench-traffic-")
    traffic = {}
    for duration_s in durations_s:
        traffic[duration_s] = Path(tmp.name) / f"{duration_s:.0f}"
        t0 = time.perf_counter()
        record_traffic(override(load_scenario(scenario_path), {"duration_s": duration_s}), traffic[duration_s])
        record_wall_s = time.perf_counter() - t0
    out["traffic recorder"] = dict(sim_s_per_wall_s=durations_s[-1] / record_wall_s)
    print(f"{'traffic recorder':<20} {durations_s[-1] / record_wall_s:8.1f} sim s / wall s    (once for all controllers)")
    for name in CONTROLLERS:
        figures = []
        for duration_s in durations_s:
            res = subprocess.run(
                [sys.executable, "-c", _SIM_CHILD, scenario_path, name, str(duration_s), str(traffic[duration_s])],
                capture_output=True,
                text=True,
                check=True,
            )
            figures.append(json.loads(res.stdout.strip().splitlines()[-1]))
        speed = durations_s[-1] / figures[-1]["wall_s"]
        out[name] = dict(sim_s_per_wall_s=speed, max_rss_mb=[f["max_rss_mb"] for f in figures])
        rss = "  ".join(
            f"{d:.0f} s: {f['max_rss_mb']:.0f} MB"
            for d, f in zip(durations_s, figures, strict=True)
        )
        print(f"{name:<20} {speed:8.1f} sim s / wall s    peak RSS {rss}")
    tmp.cleanup()
    return out


def bench_sweep() -> dict:
    from experiments.bench.sweep_scaling import bench_sweep_scaling

    return bench_sweep_scaling()


def bench_night_sample() -> dict:
    from experiments.bench.night import bench_night_full_hours

    return bench_night_full_hours()


def bench_shared_frames() -> dict:
    from experiments.bench.night import bench_shared_frames as shared

    return shared()


def bench_night_fast() -> dict:
    from experiments.bench.night import bench_night_fast as fast

    return fast()


def bench_night_fast_whole() -> dict:
    from experiments.bench.night import bench_night_fast_whole as whole

    return whole()


def bench_traffic() -> dict:
    from experiments.bench.world import bench_world

    return bench_world()


def bench_curved_street() -> dict:
    from experiments.bench.curved import bench_curved

    return bench_curved()


def bench_year_fast() -> dict:
    from experiments.bench.year import bench_year

    return bench_year()


def bench_city() -> dict:
    from experiments.bench.city import bench_city as city

    return city()


SECTIONS = (bench_detector, bench_render, bench_sim, bench_traffic, bench_sweep, bench_night_sample, bench_shared_frames,
            bench_night_fast, bench_night_fast_whole, bench_year_fast, bench_city)

#: the straight against the curved street (issue 33), after the other sections
SECTIONS += (bench_curved_street,)


def main(argv: list[str] | None = None) -> int:
    from experiments.bench.night import WHOLE_NIGHT_S, bench_night

    parser = argparse.ArgumentParser(prog="python -m experiments.bench", description=__doc__.split("\n")[0])
    parser.add_argument("--night", action="store_true",
                        help="only the whole-night section, over the whole night (28,800 sim s; long)")  # fmt: skip
    parser.add_argument("--night-s", type=float, default=None, metavar="SECONDS",
                        help="with --night: simulate only the first SECONDS of the night (0 < SECONDS <= 28800)")
    parser.add_argument("--only", choices=[s.__name__ for s in SECTIONS], action="append",
                        help="run only this section (repeatable); default: every section")
    args = parser.parse_args(argv)
    if args.night_s is not None and not (args.night and 0 < args.night_s <= WHOLE_NIGHT_S):
        parser.error(f"--night-s: needs --night and a value in (0, {WHOLE_NIGHT_S:.0f}], got {args.night_s}")
    if args.night:
        bench_night(args.night_s or WHOLE_NIGHT_S)
        return 0
    for section in SECTIONS:
        if args.only and section.__name__ not in args.only:
            continue
        section()
        print()
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
