"""Self-calibration on rendered streets: the table of docs/design/detector-real-footage.md.

Each camera (height m, tilt deg) is scene B's lens (320x240) on the first of three poles beside
a 120 m two-way street, looking along it (heading -10 deg), pedestrians only at 2000 per hour,
lamps full; 60 s are rendered plain (``citysim render --plain``: frames from 40 s on, so the
sidewalks have filled) and fed to ``python -m detector calibrate``'s steps
(``detector.selfcal``). The truth boxes of the same clip (``truth.csv``, pedestrians clear of
the frame's edge) are fed to the same solver, to tell the solver's bias from the segmentation's.
Clips are kept in ``--clips`` (rendered once; about 1-3 min each on one core)::

    python -m experiments.selfcal_cameras                       # the six cameras of the table
    python -m experiments.selfcal_cameras --camera 7 20 --camera 3 30

Design: docs/design/detector-real-footage.md (Self-calibration from walkers)
"""

from __future__ import annotations

import argparse
import csv
import math
import tempfile
from pathlib import Path

import numpy as np
import yaml

REPO = Path(__file__).resolve().parents[1]
#: (height m, tilt deg) of the table's cameras
CAMERAS = ((3.0, 30.0), (4.0, 10.0), (5.0, 15.0), (6.0, 25.0), (7.0, 20.0), (8.0, 5.0))
CLIP_S = 60.0
START_S = 40.0
#: scene B's lens: focal 0.73 mm on a 0.7 mm wide sensor
HFOV_DEG = math.degrees(2 * math.atan(0.35 / 0.73))
SEED = 5
#: the pole whose camera is rendered (the middle one: 60 m of street ahead)
LAMP = 1


def scenario(height_m: float, tilt_deg: float, seed: int = SEED) -> dict:
    """The walkers' street with scene B's camera on the first pole at ``height_m`` m, ``tilt_deg`` deg
    below the horizon (the camera file ``scene_b.yaml`` must sit beside the scenario file)."""
    street = {"length_m": 120, "lanes": [{"y_center_m": -1.6, "width_m": 3.2, "direction": 1},
                                         {"y_center_m": 1.6, "width_m": 3.2, "direction": -1}],
              "sidewalks": [{"y_center_m": -4.3, "width_m": 2.2}, {"y_center_m": 4.3, "width_m": 2.2}]}
    return {"name": "walkers", "seed": seed, "duration_s": START_S + CLIP_S + 5.0, "street": street,
            "lamps": {"count": 3, "spacing_m": 40, "first_x_m": 20, "y_m": 6.2, "pole_height_m": height_m,
                      "camera": {"file": "scene_b.yaml", "heading_deg": -10, "tilt_deg": tilt_deg}},
            "traffic": {"classes": {"pedestrian": {"rate_per_hour": 2000}}}, "controllers": ["always_on"]}


def render(height_m: float, tilt_deg: float, out_dir: Path, lamp: int = LAMP, clip_s: float = CLIP_S) -> Path:
    """Render pole ``lamp``'s plain clip into ``out_dir`` (camera.mp4, truth.csv); returns ``out_dir``."""
    from citysim.config.scenario import load_scenario
    from citysim.report.clip import render_clip

    out_dir.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "scene_b.yaml").write_text((REPO / "scenarios" / "cameras" / "scene_b.yaml").read_text())
        (Path(tmp) / "s.yaml").write_text(yaml.safe_dump(scenario(height_m, tilt_deg)))
        render_clip(load_scenario(Path(tmp) / "s.yaml"), lamp, clip_s, out_dir, start_s=START_S, progress=False,
                    plain=True, lamps_full=True)
    return out_dir


def truth_tracks(truth_csv: Path, min_sightings: int = 8) -> list[np.ndarray]:
    """The pedestrians' truth boxes clear of the frame's edge and upright as ``detector.selfcal.walkers``
    keeps them, as image tracks (frame, centre column, top edge row, bottom edge row, width;
    pixel-centre convention, as ``detector.selfcal.walkers``)."""
    from detector.selfcal.walkers import MIN_ASPECT, MIN_HEIGHT_PX

    by_id: dict[str, list] = {}
    with open(truth_csv) as fh:
        for r in csv.DictReader(fh):
            x, y, w, h = (int(float(r[k])) for k in "xywh")
            if r["cls"] != "pedestrian" or r["touches_border"] == "1" or h < MIN_HEIGHT_PX or h < MIN_ASPECT * w:
                continue
            by_id.setdefault(r["object_id"], []).append((int(r["frame"]), x + (w - 1) / 2, y - 0.5, y + h - 0.5, w))
    return [np.array(s) for s in by_id.values() if len(s) >= min_sightings]


def measure(clip_dir: Path) -> dict:
    """Calibrate from the clip's video and from its truth boxes; the estimates (or the error text)."""
    import cv2

    from detector.selfcal.solve import CalibrationError, calibrate
    from detector.selfcal.walkers import upright_tracks

    cap = cv2.VideoCapture(str(clip_dir / "camera.mp4"))
    w, h, fps = int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT)), cap.get(cv2.CAP_PROP_FPS)

    def frames():
        ok, img = cap.read()
        while ok:
            yield cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
            ok, img = cap.read()

    f_px = (w / 2) / math.tan(math.radians(HFOV_DEG) / 2)
    out = {}
    for name, tracks in (("video", upright_tracks(frames(), fps)), ("truth", truth_tracks(clip_dir / "truth.csv"))):
        try:
            out[name] = calibrate(tracks, w, h, f_px, f_px, fps)
        except CalibrationError as exc:
            out[name] = str(exc)
    cap.release()
    return out


def _cell(cal, height_m: float, tilt_deg: float) -> str:
    if isinstance(cal, str):
        return f"failed: {cal}"
    return (f"{cal.walkers} | {cal.height_m:.2f} +- {cal.height_sd_m:.2f} ({100 * (cal.height_m / height_m - 1):+.1f} %) | "
            f"{cal.tilt_deg:.1f} +- {cal.tilt_sd_deg:.1f} ({cal.tilt_deg - tilt_deg:+.1f})")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m experiments.selfcal_cameras", description=__doc__.splitlines()[0])
    p.add_argument("--camera", nargs=2, type=float, action="append", metavar=("HEIGHT_M", "TILT_DEG"),
                   help="a camera to measure (repeatable; default: the table's six)")
    p.add_argument("--lamp", type=int, default=LAMP, choices=(0, 1, 2), help="the pole whose camera is rendered")
    p.add_argument("--clips", type=Path, default=Path(tempfile.gettempdir()) / "citysim-selfcal-clips",
                   help="folder the rendered clips are kept in (reused when present)")
    args = p.parse_args(argv)
    print("| camera | walkers | height m (error) | tilt deg (error) | truth boxes: walkers | height m | tilt deg |")
    print("|---|---|---|---|---|---|---|")
    for height_m, tilt_deg in args.camera or CAMERAS:
        clip = args.clips / f"h{height_m:g}_t{tilt_deg:g}_s{SEED}_lamp{args.lamp}"
        if not (clip / "truth.csv").exists():
            render(height_m, tilt_deg, clip, args.lamp)
        res = measure(clip)
        print(f"| {height_m:g} m, {tilt_deg:g} deg, pole {args.lamp} | {_cell(res['video'], height_m, tilt_deg)} | "
              f"{_cell(res['truth'], height_m, tilt_deg)} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
