"""Finding and running the real development clips (footage no simulator made) for the tests.

The clips do not ship with the repository; the tests find them in the folder named by
CITYSIM_REALCLIPS (default: realclips in the folder named "shared" beside the checkout)
and skip, saying so, where they are absent. CI sets the variable and fails without them.

There is no ground truth; the README of the clips lists when what is in view,
read off the frames by eye. The cameras are estimated (scenarios/cameras/realclip_*.yaml).
"""

import csv
import os
from pathlib import Path

import pytest

from detector.__main__ import detect_video

REPO = Path(__file__).resolve().parents[2]
CLIPS = Path(os.environ.get("CITYSIM_REALCLIPS", REPO.parent / "shared" / "realclips"))
CAMERAS = REPO / "scenarios" / "cameras"


def detections(tmp_path: Path, clip: str, camera: str) -> tuple[list[dict], dict]:
    video = CLIPS / clip
    if not video.exists():
        pytest.skip(f"{video} is missing: set CITYSIM_REALCLIPS to the folder holding the real clips")
    # no annotated video: encoding it at the clip's own size took a third of the test's time
    summary = detect_video(video, CAMERAS / camera, tmp_path / "out", progress=False, annotated=False)
    with open(tmp_path / "out" / "detections.csv", newline="") as fh:
        return list(csv.DictReader(fh)), summary


def target_frames(rows: list[dict], first: int, last: int) -> set[int]:
    """Frames ``first`` .. ``last`` where a region is a target (detections.csv's ``target`` column)."""
    return {int(r["frame"]) for r in rows if r["target"] == "1" and first <= int(r["frame"]) <= last}
