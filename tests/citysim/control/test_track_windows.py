"""detector_confirmed's k of n runs per track: hits of different tracks never add up."""

from citysim.control.track_windows import TrackWindows


def test_two_of_six_of_one_track_confirms_it():
    windows = TrackWindows(2, 6)
    assert windows.update({1: True}) == set()
    assert windows.update({}) == set()  # a frame without the track counts as a miss
    assert windows.update({1: True}) == {1}
    for _ in range(3):
        assert windows.update({1: False}) == {1}  # both hits still among the last six frames
    assert windows.update({1: False}) == set()  # the first left the window: one hit of six


def test_hits_of_different_tracks_do_not_add_up():
    windows = TrackWindows(2, 6)
    # an insect here, a flicker there: one hit each, never two of one track
    for frame in range(30):
        assert windows.update({100 + frame: True, 7: frame % 7 == 0}) == set()
    # forgotten windows are dropped: only tracks with a hit in the last 6 frames are kept
    assert len(windows.bits) <= 7


def test_detections_without_a_track_share_one_window():
    windows = TrackWindows(2, 6)
    windows.update({None: True})
    assert windows.update({None: True}) == {None}
