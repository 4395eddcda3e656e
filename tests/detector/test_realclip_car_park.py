"""The detector on the real car-park clip by day: cars, a bicycle wheeled, walkers.

The clip does not ship with the repository (see ``tests.detector.realclips``); one clip per
file so the two run on different test workers.
"""

import numpy as np
import pytest

from tests.detector.realclips import detections, target_frames

pytestmark = pytest.mark.slow  # real footage: tens of seconds


def test_car_park_by_day_quiet_stretch_stays_dark_and_walker_is_seen(tmp_path):
    rows, _ = detections(tmp_path, "person-bicycle-car-detection.mp4", "realclip_carpark.yaml")
    # frames ~45-105: the white car has left and nobody has come yet: no target should light a lamp
    assert len(target_frames(rows, 50, 100)) <= 3
    # frames ~290-340: a pedestrian walks across alone
    walker = [r for r in rows if r["cls"] != "noise" and 295 <= int(r["frame"]) <= 335]
    assert len({int(r["frame"]) for r in walker}) > 0.5 * 41  # per frame, uncalibrated camera, no tracking
    assert np.mean([r["cls"] == "pedestrian" for r in walker]) > 0.6
