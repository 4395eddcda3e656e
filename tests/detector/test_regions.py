"""The arrays a frame's few regions make from their lists (``detector.regions``) are those of
the straightforward ``Regions``."""

from __future__ import annotations

import numpy as np

from detector.segment import Regions
from tests.detector.test_segment import Scene, warmed_up


def test_regions_of_few_contours_make_their_arrays_from_the_lists_once():
    """The few-contour path keeps the lists and makes each array on first use: the same values
    and dtypes as a Regions built from arrays, one array object per field, lists untouched."""
    scene = Scene(4)
    seg = warmed_up(scene)
    regions = seg.apply(scene.frame([(40, 60, 20, 40), (150, 100, 25, 50), (-10, 180, 30, 40)]))
    assert isinstance(regions, Regions) and len(regions) == 3 == len(regions.contours)
    boxes, areas, unusable = (list(values) for values in regions.lists)
    eager = Regions(
        np.array(boxes, np.int32), np.array(areas), regions.contours, regions.touches_border.copy(),
        regions.foreground_fraction, regions.mask, regions.cut_by_crop.copy(), lists=regions.lists,
    )  # fmt: skip
    for name in ("boxes_px", "areas_px", "touches_border", "cut_by_crop"):
        got, want = getattr(regions, name), getattr(eager, name)
        assert got.dtype == want.dtype and np.array_equal(got, want) and getattr(regions, name) is got
    assert regions.unusable.tolist() == unusable and sorted(unusable) == [False, False, True]
    assert regions.lists == (boxes, areas, unusable) and regions.extents.shape == (3,)
