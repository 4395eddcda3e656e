"""`make bench`: speed and memory figures, never pass/fail.

Each section prints its own figures beside the floor it is compared with,
measured in the same run on the same frames:

* detector: frames/s single-threaded vs OpenCV's own floor (CLAHE + MOG2 +
  opening + contours) on 320x240 and 424x240 sequences with moving objects;
* renderer: ms per frame with 0, 5 and 20 objects, beside the detector's ms/frame;
* simulation: simulated seconds per wall second per controller, peak memory;
* sweeps: a 16-point sweep on 2 Dask workers vs 1.
"""

from __future__ import annotations

import sys
import time
import tracemalloc

import cv2
import numpy as np

cv2.setNumThreads(1)  # the paper's implementation is single-threaded, and so is a lamp's budget


def synthetic_sequence(
    width_px: int, height_px: int, n_frames: int = 300, n_objects: int = 5, seed: int = 0
) -> list[np.ndarray]:
    """Dark noisy frames with bright upright blobs moving across at different depths."""
    rng = np.random.default_rng(seed)
    base = rng.normal(35, 6, (height_px, width_px)).clip(0, 255).astype(np.uint8)
    starts = rng.uniform(0, width_px, n_objects)
    rows = rng.uniform(0.45, 0.9, n_objects) * height_px
    speeds = rng.uniform(-3, 3, n_objects)
    frames = []
    for i in range(n_frames):
        img = base.copy()
        noise = rng.normal(0, 3, base.shape)
        for k in range(n_objects):
            x = int((starts[k] + speeds[k] * i) % width_px)
            scale = rows[k] / height_px
            w, h = int(6 + 14 * scale), int(15 + 50 * scale)
            y1 = int(rows[k])
            cv2.ellipse(img, (x, y1 - h // 2), (w // 2, h // 2), 0, 0, 360, 170, -1)
        frames.append(np.clip(img + noise, 0, 255).astype(np.uint8))
    return frames


def paper_camera(width_px: int, height_px: int):
    """The paper's Table 2 cameras at these resolutions: scene B (320x240) and scene A (424x240)."""
    from detector.camera import CameraModel

    if width_px == 320:
        return CameraModel(
            height_m=3.1,
            tilt_deg=22,
            focal_mm=0.73,
            sensor_w_mm=0.7,
            sensor_h_mm=0.52,
            width_px=width_px,
            height_px=height_px,
        )
    return CameraModel(
        height_m=3.0,
        tilt_deg=13,
        focal_mm=3.67,
        sensor_w_mm=4.8,
        sensor_h_mm=3.6,
        width_px=width_px,
        height_px=height_px,
    )


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
    loaded machine: both pipelines meet the same cache state and the same interruptions.
    """
    totals = dict.fromkeys(pipelines, 0.0)
    for frame in frames:
        for name, fn in pipelines.items():
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


def bench_detector() -> dict:
    from detector.detector import Detector
    from detector.general_model import default_model

    print("== detector vs OpenCV floor (single thread, CPU time, interleaved frame by frame) ==")
    model = default_model()
    out = {}
    for w, h in [(320, 240), (424, 240)]:
        frames = synthetic_sequence(w, h)
        det, floor = Detector(paper_camera(w, h), model=model), OpenCVFloor()
        ms = interleaved_cpu_ms(frames, {"detector": det.process, "floor": floor.process})
        mem = peak_memory_mb(Detector(paper_camera(w, h), model=model).process, frames[:100])
        ratio = ms["floor"] / ms["detector"]
        out[f"{w}x{h}"] = dict(
            detector_ms=ms["detector"], floor_ms=ms["floor"], fps_ratio=ratio, peak_mb=mem
        )
        print(
            f"{w}x{h}: detector {1000 / ms['detector']:7.1f} frames/s ({ms['detector']:.2f} ms)   OpenCV floor "
            f"{1000 / ms['floor']:7.1f} frames/s ({ms['floor']:.2f} ms)   detector/floor fps ratio {ratio:.2f}   "
            f"peak Python heap {mem:.2f} MB"
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
run_controller(scenario, ControllerSpec(name=sys.argv[2]))
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
    """Simulated seconds per wall second per controller, and peak memory at two run lengths (flat = streaming)."""
    import json
    import subprocess

    from citysim.control.registry import CONTROLLERS

    print(f"== simulation: {scenario_path}, per controller (each in a fresh process) ==")
    out = {}
    for name in CONTROLLERS:
        figures = []
        for duration_s in durations_s:
            res = subprocess.run(
                [sys.executable, "-c", _SIM_CHILD, scenario_path, name, str(duration_s)],
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
    return out


def bench_sweep() -> dict:
    from experiments.bench.sweep_scaling import bench_sweep_scaling

    return bench_sweep_scaling()


SECTIONS = (bench_detector, bench_render, bench_sim, bench_sweep)


def main() -> int:
    for section in SECTIONS:
        section()
        print()
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
