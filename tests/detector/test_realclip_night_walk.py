"""The detector on the real night_walk clip: one person crossing before two lamp-lit garages, no cars.

The clip does not ship with the repository (see ``tests.detector.realclips``); one clip per
file so the two run on different test workers.
"""

from collections import Counter

import numpy as np
import pytest

from tests.detector.realclips import detections, target_frames

pytestmark = pytest.mark.slow  # real footage: tens of seconds


def test_night_walk_person_is_found_and_measured_as_a_person(tmp_path):
    rows, summary = detections(tmp_path, "night_walk.mp4", "realclip_night_walk.yaml")
    assert summary["frames"] == 565
    # one person crosses, in view about frames 180-564 (before his hand covers the lens at the end)
    walking = target_frames(rows, 200, 520)
    # the answer (the target column) holds him in at least 90 % of these frames, all of them within range
    assert len(walking) >= 0.9 * (520 - 200 + 1), len(walking)
    assert {r["target_cls"] for r in rows if r["target"] == "1"} == {"pedestrian"}  # no cyclist, no car
    assert summary["frames_with_target"] == len({r["frame"] for r in rows if r["target"] == "1"})
    heights = np.array([float(r["height_m"]) for r in rows if r["frame_cls"] != "noise" and 200 <= int(r["frame"]) <= 520])
    assert 1.4 < np.median(heights) < 2.1, np.median(heights)  # a person, measured through the estimated camera
    assert not any(r["frame_cls"] == "vehicle" for r in rows), "there are no cars in this clip"
    # with tracks: he is one target track, not a new one whenever his body breaks into pieces
    # (his legs alone, a speck by his feet, a reflection joined below them)
    tracked: dict[int, set[str]] = {}
    for r in rows:
        if r["target_cls"] not in ("noise", "") and 200 <= int(r["frame"]) <= 520:
            tracked.setdefault(int(r["frame"]), set()).add(r["track_id"])
    assert len(tracked) > 0.55 * (520 - 200 + 1), len(tracked)
    ids = Counter(t for ids in tracked.values() for t in ids)
    walker, frames_as_walker = ids.most_common(1)[0]
    assert frames_as_walker > 0.9 * len(tracked), ids  # before: three tracks took turns (0.81)
    assert not any(r["target_cls"] == "vehicle" for r in rows)
