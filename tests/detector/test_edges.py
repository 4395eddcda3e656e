"""Regions cut by the frame's edge (``detector.edges``, ``Detector(border_filter=False)``): which are
kept, on region lists of a 320 x 240 frame with a stand-in classifier."""

import numpy as np
import pytest

from detector.edges import cut_sides, keep_cut_regions, visible_part_fits
from detector.regions import Regions

CLASSES = ["noise", "pedestrian", "group", "cyclist", "vehicle"]
SHAPE = (240, 320)  # height, width px


def regions_of(boxes, cut_by_crop=None) -> Regions:
    return Regions(boxes_px=np.array(boxes, np.int32), areas_px=np.ones(len(boxes)), contours=[],
                   touches_border=np.ones(len(boxes), bool), foreground_fraction=0.0,
                   mask=np.zeros(SHAPE, np.uint8),
                   cut_by_crop=None if cut_by_crop is None else np.array(cut_by_crop, bool))


def row(width_m, height_m, distance_m=10.0):
    return [width_m, height_m, width_m * height_m * 0.7, distance_m, 20.0, 5.0]


def kept(boxes, rows, live=(), p_target=0.9, cls="pedestrian", cut_by_crop=None):
    """Which regions the rules keep: every row classified ``cls`` with P(target) ``p_target``."""
    edge = [True] * len(boxes)
    proba = [1.0 - p_target if c == "noise" else (p_target if c == cls else 0.0) for c in CLASSES]
    keep_cut_regions(regions_of(boxes, cut_by_crop), boxes, rows, edge, SHAPE, list(live),
                     classify=lambda rs: [proba for _ in rs], class_names=CLASSES, threshold=0.5)
    return [not e for e in edge]


def test_cut_sides_names_the_edges_a_box_reaches():
    assert cut_sides((0, 50, 10, 40), *SHAPE) == (True, False, False)
    assert cut_sides((300, 50, 20, 40), *SHAPE) == (True, False, False)
    assert cut_sides((100, 0, 10, 40), *SHAPE) == (False, True, False)
    assert cut_sides((100, 200, 10, 40), *SHAPE) == (False, False, True)
    assert cut_sides((1, 1, 10, 40), *SHAPE) == (False, False, False)


def test_a_side_cut_region_continuing_a_track_is_kept_whatever_it_looks_like():
    # classified noise on its own (P(target) 0.1): the track decides, so it is kept
    assert kept([(0, 80, 12, 60)], [row(0.2, 1.7)], live=[(2, 78, 20, 62)], p_target=0.1) == [True]


def test_a_side_cut_region_on_no_track_is_kept_when_its_visible_part_fits_a_class():
    # a walker half out of the left edge: 0.2 m of his width seen (a lower bound), 1.7 m tall
    assert kept([(0, 80, 6, 60)], [row(0.2, 1.7)]) == [True]
    # the same region classified noise is dropped
    assert kept([(0, 80, 6, 60)], [row(0.2, 1.7)], p_target=0.3) == [False]
    # its uncut height outside a pedestrian's (0.5 m: under 1.15 m less the tolerance) is dropped
    assert kept([(0, 80, 6, 20)], [row(0.2, 0.5)]) == [False]
    # a visible width already wider than any pedestrian's apparent width is dropped
    assert kept([(0, 80, 60, 60)], [row(2.0, 1.7)]) == [False]


def test_a_top_cut_region_needs_only_its_width_to_fit_and_its_height_below_the_largest():
    # cut by the top edge: 0.6 m of a walker's height seen is a lower bound, so it may be one
    assert kept([(100, 0, 10, 20)], [row(0.45, 0.6)]) == [True]
    # the same 0.6 m tall region not cut is no pedestrian (see above); cut, its width must still fit
    assert kept([(100, 0, 40, 20)], [row(1.5, 0.6)]) == [False]


def test_a_bottom_cut_region_is_kept_only_when_it_continues_a_track():
    box, r = (100, 200, 40, 40), row(1.6, 1.0, distance_m=4.0)
    assert kept([box], [r], cls="vehicle") == [False]  # fits a vehicle's width, but no foot row: out
    assert kept([box], [r], live=[(98, 190, 42, 45)], cls="vehicle") == [True]


def test_a_region_cut_by_the_band_or_without_a_ground_point_stays_out():
    live = [(0, 78, 20, 62)]
    assert kept([(0, 80, 6, 60)], [row(0.2, 1.7)], live=live, cut_by_crop=[True]) == [False]
    assert kept([(0, 80, 6, 60)], [None], live=live) == [False]


@pytest.mark.parametrize(("cls", "width_m", "height_m", "width_cut", "height_cut", "fits"), [
    ("vehicle", 0.6, 1.5, True, False, True),  # a car's front seen at the side edge
    ("vehicle", 0.6, 1.5, False, False, False),  # the same, uncut: too narrow for a car
    ("vehicle", 4.0, 0.6, False, True, True),  # a car's lower part under the top edge
    ("cyclist", 0.5, 3.5, False, False, False),  # taller than any cyclist
])
def test_visible_part_fits_by_cut_side(cls, width_m, height_m, width_cut, height_cut, fits):
    assert visible_part_fits(cls, width_m, height_m, width_cut, height_cut) is fits
