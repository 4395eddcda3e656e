"""The class names and the paper's Table 1 sizes, kept in one place (``detector.classes``)."""

from __future__ import annotations

import numpy as np

from detector.classes import CLASSES, TABLE1, TARGET_CLASSES, SizeRange

# The paper's Table 1 (Matveev et al., Sensors 2020), metres: (width, height, depth)
PAPER_TABLE1 = {
    "pedestrian": ((0.3, 0.64), (1.15, 2.0), (0.3, 0.79)),
    "group": ((1.2, 3.0), (1.5, 2.0), (0.3, 0.79)),
    "cyclist": ((0.3, 0.64), (1.5, 1.9), (1.5, 1.7)),
    "vehicle": ((1.4, 1.8), (1.4, 2.0), (3.7, 4.6)),
}


def test_classes_and_table1_are_the_papers() -> None:
    assert CLASSES == ("noise", "pedestrian", "group", "cyclist", "vehicle")
    assert TARGET_CLASSES == CLASSES[1:] == tuple(TABLE1)
    for cls, (width_m, height_m, length_m) in PAPER_TABLE1.items():
        assert TABLE1[cls] == SizeRange(width_m, height_m, length_m), cls


def test_draw_is_uniform_in_the_ranges_width_height_length_in_that_order() -> None:
    size = TABLE1["vehicle"]
    drawn = size.draw(np.random.default_rng(5))
    rng = np.random.default_rng(5)
    expected = tuple(float(rng.uniform(*r)) for r in (size.width_m, size.height_m, size.length_m))
    assert drawn == expected
    for value, (lo, hi) in zip(drawn, (size.width_m, size.height_m, size.length_m), strict=True):
        assert lo <= value < hi
