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

import importlib
import sys
import time
import tracemalloc

import cv2
import numpy as np

cv2.setNumThreads(1)  # the paper's implementation is single-threaded, and so is a lamp's budget


def synthetic_sequence(width_px: int, height_px: int, n_frames: int = 300, n_objects: int = 5, seed: int = 0) -> list[np.ndarray]:
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


def opencv_floor_fps(frames: list[np.ndarray]) -> float:
    """OpenCV's own work for the paper's pipeline, nothing else: the floor we compare against."""
    clahe = cv2.createCLAHE(clipLimit=3.0, tileGridSize=(8, 8))
    mog2 = cv2.createBackgroundSubtractorMOG2(history=500, varThreshold=16, detectShadows=True)
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (3, 3))
    t0 = time.perf_counter()
    for f in frames:
        m = mog2.apply(clahe.apply(f))
        _, m = cv2.threshold(m, 170, 255, cv2.THRESH_BINARY)
        m = cv2.morphologyEx(m, cv2.MORPH_OPEN, kernel)
        m = cv2.dilate(m, kernel)
        cv2.findContours(m, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    return len(frames) / (time.perf_counter() - t0)


def detector_fps(frames: list[np.ndarray], width_px: int, height_px: int) -> float:
    from detector.camera import CameraModel
    from detector.classifier import default_model
    from detector.detector import Detector

    # the paper's Table 2 cameras at these resolutions: scene B (320x240) and scene A (424x240)
    if width_px == 320:
        cam = CameraModel(height_m=3.1, tilt_deg=22, focal_mm=0.73, sensor_w_mm=0.7, sensor_h_mm=0.52,
                          width_px=width_px, height_px=height_px)
    else:
        cam = CameraModel(height_m=3.0, tilt_deg=13, focal_mm=3.67, sensor_w_mm=4.8, sensor_h_mm=3.6,
                          width_px=width_px, height_px=height_px)
    det = Detector(cam, model=default_model())
    t0 = time.perf_counter()
    for f in frames:
        det.process(f)
    return len(frames) / (time.perf_counter() - t0)


def bench_detector() -> dict:
    print("== detector vs OpenCV floor (single thread) ==")
    out = {}
    for w, h in [(320, 240), (424, 240)]:
        frames = synthetic_sequence(w, h)
        best_floor = max(opencv_floor_fps(frames) for _ in range(3))
        tracemalloc.start()
        best_det = max(detector_fps(frames, w, h) for _ in range(3))
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        ratio = best_det / best_floor
        out[f"{w}x{h}"] = dict(detector_fps=best_det, floor_fps=best_floor, ratio=ratio)
        print(f"{w}x{h}: detector {best_det:7.1f} frames/s ({1000 / best_det:.2f} ms)   OpenCV floor "
              f"{best_floor:7.1f} frames/s ({1000 / best_floor:.2f} ms)   ratio {ratio:.2f}   "
              f"peak Python heap {peak / 1e6:.1f} MB")
    return out


SECTIONS = ["bench_detector", "bench_render", "bench_sim", "bench_sweep"]


def main() -> int:
    for name in SECTIONS:
        fn = globals().get(name)
        if fn is None:
            try:
                fn = getattr(importlib.import_module(f"experiments.bench_{name.removeprefix('bench_')}"), "main")
            except (ImportError, AttributeError) as exc:
                print(f"== {name}: not available ({exc}) ==")
                continue
        fn()
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
