"""The detector on the real car-park clip by day: cars, a bicycle wheeled, a walker, a cyclist.

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


def track_targets(rows, first, last, in_part=lambda r: True) -> dict[str, set[int]]:
    """Per target track (its id), the frames in ``first``-``last`` it was a target in (its pooled
    class not noise), of the detections ``in_part``."""
    out: dict[str, set[int]] = {}
    for r in rows:
        if r["target_cls"] != "noise" and first <= int(r["frame"]) <= last and in_part(r):
            out.setdefault(r["track_id"], set()).add(int(r["frame"]))
    return out


def test_car_park_by_day_quiet_stretch_stays_dark_and_walker_is_seen(car_park):
    rows = car_park
    # frames ~45-105: the white car has left and nobody has come yet: no target should light a lamp
    assert len(target_frames(rows, 50, 100)) <= 3
    assert track_targets(rows, 45, 105) == {}
    # still regions (ghosts on the painted lines, ``detector.ghosts``) are never targets
    assert not [r for r in rows if r["track_id"] == "" and r["target_cls"] != "noise"]
    # frames ~290-340: a pedestrian walks across alone, tracked (a still region on a painted line,
    # classified pedestrian in 10 of these frames, no longer counts): his track is a pedestrian
    # target in 24 of the 41 frames (0b837fd: 0, 'classified noise'; only his legs are segmented in
    # half of them), and his whole-body frames are classified pedestrian
    walker = track_targets(rows, 295, 335)
    assert len(walker) == 1, walker
    ((track_id, frames),) = walker.items()
    assert len(frames) > 0.5 * 41
    assert {r["target_cls"] for r in rows if r["track_id"] == track_id and r["target_cls"] != "noise"} == {"pedestrian"}
    tracked = [r for r in rows if r["track_id"] == track_id and r["frame_cls"] != "noise"]
    assert len(tracked) >= 15 and np.mean([r["frame_cls"] == "pedestrian" for r in tracked]) > 0.6


def test_cyclist_and_bicycle_wheeled_are_targets(car_park):
    """Along the top of the view, far up (legs and wheels alone segmented in many frames): the person
    wheeling a bicycle (frames ~110-170) and the cyclist (~350-420, right of x 500 px) are each a
    target track (0b837fd: 'classified noise' / 'size unsteady' and 'jumping'); of the classifier's
    likeliest class, 'pedestrian' (their least footprints fit a walker, a cyclist and a group)."""
    wheeled = track_targets(car_park, 110, 170)
    cyclist = track_targets(car_park, 350, 420, lambda r: int(r["x"]) + int(r["w"]) / 2 > 500)
    for who, targets, at_least in (("wheeled", wheeled, 20), ("cyclist", cyclist, 12)):
        assert len(targets) == 1, who
        assert len(next(iter(targets.values()))) >= at_least, who


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


def test_each_car_is_one_vehicle_target_while_in_view(car_park):
    """A steep camera judges a track by its footprint (``detector.tracks.steep``): each car's one
    track is a vehicle target in most of its tracked frames (0b837fd: never a target, 'size outside
    Table 1'; the classifier takes the joined car for a group). The white car: a vehicle in 20 of
    its 26 tracked frames (a target from its 5th, 'group' then 'vehicle' once its footprint's upper
    quartile reaches a vehicle's); the grey-green car in 30 of 44 (it enters in pieces: 'group'
    7 frames before)."""
    for car, (first, last) in CARS.items():
        on_car = [r for r in car_park if first <= int(r["frame"]) <= last and r["track_id"] != ""
                  and int(r["x"]) + int(r["w"]) / 2 < CAR_PART_MAX_X_PX
                  and int(r["y"]) + int(r["h"]) / 2 > CAR_PART_MIN_Y_PX]  # fmt: skip
        tracked = {int(r["frame"]) for r in on_car}
        vehicle = {int(r["frame"]) for r in on_car if r["target_cls"] == "vehicle"}
        assert len({r["track_id"] for r in on_car if r["target_cls"] == "vehicle"}) == 1, car
        assert len(vehicle) >= 0.6 * len(tracked), car
        # and never a target of another class after it was a vehicle
        assert not [r for r in on_car if int(r["frame"]) > min(vehicle) and r["target_cls"] not in ("vehicle", "noise")]
