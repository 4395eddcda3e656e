"""Regions cut by the frame's edge on the real development clips, with the paper's border filter
and with ``--keep-edge-regions``: the figures of docs/design/detector-real-footage.md.

The clips do not ship with the repository (``CITYSIM_REALCLIPS`` names their folder, as for the
tests). Each run is ``python -m detector``'s ``detect_video`` (CLI defaults, no annotated video);
what is counted follows tests/detector/test_realclip_car_park.py and test_realclip_night_walk.py::

    CITYSIM_REALCLIPS=/work/shared/realclips python -m experiments.edge_regions

Design: docs/design/detector-real-footage.md (Regions at the frame's edge)
"""

from __future__ import annotations

import csv
import os
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
CLIPS = Path(os.environ.get("CITYSIM_REALCLIPS", REPO.parent / "shared" / "realclips"))
CAMERAS = REPO / "scenarios" / "cameras"
#: the car park's cars: frames and part of the frame (tests/detector/test_realclip_car_park.py)
CARS = {"white": (0, 47), "grey-green": (343, 395)}
CAR_PART_MAX_X_PX, CAR_PART_MIN_Y_PX = 330, 60


def run(clip: str, camera: str, keep_edge: bool, out_dir: Path) -> list[dict]:
    """detections.csv's rows of one run."""
    from detector.__main__ import detect_video

    detect_video(CLIPS / clip, CAMERAS / camera, out_dir, progress=False, annotated=False,
                 border_filter=not keep_edge)
    with open(out_dir / "detections.csv", newline="") as fh:
        return list(csv.DictReader(fh))


def car_park_figures(rows: list[dict]) -> dict:
    """Per car: frames its region is on a track, frames a target, frames a vehicle target, number of
    tracks; target frames and target tracks in the quiet stretch (frames 45-105)."""
    out = {}
    for car, (first, last) in CARS.items():
        on_car = [r for r in rows if first <= int(r["frame"]) <= last and r["track_id"] != ""
                  and int(r["x"]) + int(r["w"]) / 2 < CAR_PART_MAX_X_PX
                  and int(r["y"]) + int(r["h"]) / 2 > CAR_PART_MIN_Y_PX]  # fmt: skip
        out[car] = {"tracked": len({r["frame"] for r in on_car}),
                    "target": len({r["frame"] for r in on_car if r["target"] == "1"}),
                    "vehicle": len({r["frame"] for r in on_car if r["target_cls"] == "vehicle"}),
                    "tracks": len({r["track_id"] for r in on_car}),
                    "classes": sorted({r["target_cls"] for r in on_car if r["target"] == "1"})}
    quiet = [r for r in rows if 45 <= int(r["frame"]) <= 105 and r["target"] == "1"]
    out["quiet 45-105"] = {"target frames": len({r["frame"] for r in quiet}),
                           "target tracks": len({r["track_id"] for r in quiet})}
    return out


def night_walk_figures(rows: list[dict]) -> dict:
    """The walker's target frames in 200-520 (of 321) and the classes ever a target."""
    frames = {int(r["frame"]) for r in rows if r["target"] == "1" and 200 <= int(r["frame"]) <= 520}
    return {"walker target frames of 321": len(frames),
            "target classes": sorted({r["target_cls"] for r in rows if r["target"] == "1"})}


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        for keep_edge in (False, True):
            name = "--keep-edge-regions" if keep_edge else "border filter"
            rows = run("person-bicycle-car-detection.mp4", "realclip_carpark.yaml", keep_edge, Path(tmp) / f"c{keep_edge}")
            print(f"car park, {name}: {car_park_figures(rows)}", flush=True)
            rows = run("night_walk.mp4", "realclip_night_walk.yaml", keep_edge, Path(tmp) / f"n{keep_edge}")
            print(f"night_walk, {name}: {night_walk_figures(rows)}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
