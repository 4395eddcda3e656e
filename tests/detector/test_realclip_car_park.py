"""The detector on the real car-park clip by day: cars, a bicycle wheeled, walkers.

The clip does not ship with the repository (see ``tests.detector.realclips``); one clip per
file so the two run on different test workers.
"""

import numpy as np
import pytest

from tests.detector.realclips import detections, target_frames

pytestmark = pytest.mark.slow  # real footage: tens of seconds

#: Each car's frames and its part of the frame (box centres, the video's 768 x 432 px), read off
#: the frames by eye: the white car drives from the bottom left out through the left edge, the
#: grey-green car in from the bottom and out through the left edge; both stay left of x 330 px and
#: below y 60 px, where the walker (along the top) and the cyclist (right of x 500 px) are not.
CARS = {"white": (0, 47), "grey-green": (343, 395)}
CAR_PART_MAX_X_PX, CAR_PART_MIN_Y_PX = 330, 60


@pytest.fixture(scope="module")
def car_park(tmp_path_factory):
    rows, _ = detections(tmp_path_factory.mktemp("car_park"), "person-bicycle-car-detection.mp4",
                         "realclip_carpark.yaml")  # fmt: skip
    return rows


def test_car_park_by_day_quiet_stretch_stays_dark_and_walker_is_seen(car_park):
    rows = car_park
    # frames ~45-105: the white car has left and nobody has come yet: no target should light a lamp
    assert len(target_frames(rows, 50, 100)) <= 3
    # frames ~290-340: a pedestrian walks across alone
    walker = [r for r in rows if r["cls"] != "noise" and 295 <= int(r["frame"]) <= 335]
    assert len({int(r["frame"]) for r in walker}) > 0.5 * 41  # per frame, uncalibrated camera, no tracking
    assert np.mean([r["cls"] == "pedestrian" for r in walker]) > 0.6


def test_each_car_is_one_track_while_in_view(car_park):
    """A camera looking steeply down (``detector.tracks.footprint``): each car's pieces are one
    region and one track, and the ground it uncovers (``detector.ghosts``) is on no track.
    Before: the white car made 9 tracks in its part of the frame, the grey-green car 11."""
    for car, (first, last) in CARS.items():
        on_car = [r for r in car_park if first <= int(r["frame"]) <= last
                  and int(r["x"]) + int(r["w"]) / 2 < CAR_PART_MAX_X_PX
                  and int(r["y"]) + int(r["h"]) / 2 > CAR_PART_MIN_Y_PX]  # fmt: skip
        tracked = [r for r in on_car if r["track_id"] != ""]
        assert len({r["track_id"] for r in tracked}) == 1, car
        # the white car leaves through the frame's left edge from frame ~24 (a region touching the
        # border is not classified): tracked in 26 of its 48 frames; the grey-green car in 44 of 53
        assert len({r["frame"] for r in tracked}) >= 0.5 * (last - first + 1), car
