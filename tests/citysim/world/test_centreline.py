"""The centreline's s,d <-> x,y conversions, against hand-computed points on a 90-degree bend."""

import math

import numpy as np
import pytest

from citysim.world.centreline import BLEND_M, Centreline

#: 100 m east, then 100 m north: a left bend at s = 100 m; blends of 30 m either side of it
BEND = Centreline(((0.0, 0.0), (100.0, 0.0), (100.0, 100.0)))


@pytest.mark.parametrize(
    ("s_m", "d_m", "xy_m"),
    [
        (50.0, 4.0, (50.0, 4.0)),  # square to the first segment, far from the bend
        (70.0, 4.0, (70.0, 4.0)),  # where the blend starts (100 - BLEND_M)
        # half-way through the blend the cross-section is (0, 1)/2 + (-1, 1)/2 = (-0.5, 1)
        (85.0, 4.0, (85.0 - 2.0, 4.0)),
        (100.0, 4.0, (96.0, 4.0)),  # on the bisector inside the bend: d / cos 45 deg from the vertex
        (100.0, -4.0, (104.0, -4.0)),  # ... and outside it
        (150.0, 4.0, (96.0, 50.0)),  # square to the second segment (d to the left of north is west)
        (-10.0, 2.0, (-10.0, 2.0)),  # before the start: straight on along the first segment
        (210.0, 1.0, (99.0, 110.0)),  # beyond the end, straight on along the last
    ],
)
def test_hand_computed_points_on_a_bend(s_m, d_m, xy_m):
    assert BLEND_M == 30.0
    assert BEND.to_xy(s_m, d_m) == pytest.approx(xy_m, abs=1e-12)
    assert BEND.to_sd(*xy_m) == pytest.approx((s_m, d_m), abs=1e-9)


def test_heading_is_the_segments_direction():
    assert BEND.heading_rad(50.0) == 0.0
    assert BEND.heading_rad(150.0) == pytest.approx(math.pi / 2)
    assert BEND.heading_rad(np.array([10.0, 99.9, 100.1])) == pytest.approx([0.0, 0.0, math.pi / 2])
    assert BEND.length_m == pytest.approx(200.0)


@pytest.mark.parametrize(
    "points",
    [
        ((0.0, 0.0), (100.0, 0.0), (100.0, 100.0)),
        ((0.0, 0.0), (50.0, 10.0), (90.0, -5.0), (120.0, 30.0), (121.0, 31.0)),
        ((10.0, 5.0), (-40.0, 60.0)),
    ],
)
def test_round_trips_to_the_nanometre(points):
    line = Centreline(points)
    rng = np.random.default_rng(0)
    s_m = rng.uniform(-20.0, line.length_m + 20.0, 5000)
    d_m = rng.uniform(-12.0, 12.0, 5000)
    x_m, y_m = line.to_xy(s_m, d_m)
    s2, d2 = line.to_sd(x_m, y_m)
    assert np.abs(s2 - s_m).max() < 1e-9 and np.abs(d2 - d_m).max() < 1e-9
    # the distance from a point's own segment line is its d (the cross-sections are mitred)
    k = np.clip(np.searchsorted(np.cumsum([0.0] + [math.dist(a, b) for a, b in zip(points[:-1], points[1:], strict=True)]),
                                s_m, side="right") - 1, 0, len(points) - 2)  # fmt: skip
    p0, p1 = np.array(points)[k], np.array(points)[k + 1]
    u = (p1 - p0) / np.linalg.norm(p1 - p0, axis=1)[:, None]
    assert np.allclose(-(x_m - p0[:, 0]) * u[:, 1] + (y_m - p0[:, 1]) * u[:, 0], d_m, atol=1e-9)


def test_the_map_is_continuous_round_the_bend():
    s_m = np.linspace(60.0, 140.0, 8001)  # 1 cm steps
    for d_m in (-6.0, 0.0, 6.0):
        x_m, y_m = BEND.to_xy(s_m, np.full_like(s_m, d_m))
        steps = np.hypot(np.diff(x_m), np.diff(y_m))
        # a step of 1 cm of s moves at most (1 + |d| / blend) cm in the world
        assert steps.max() <= 0.01 * (1.0 + abs(d_m) / BLEND_M) + 1e-9


def test_the_straight_street_is_the_identity_and_returns_its_inputs():
    line = Centreline.straight(390.0)
    assert line.is_straight_x
    s_m, d_m = np.array([1.0, 2.0]), np.array([-3.0, 4.0])
    x_m, y_m = line.to_xy(s_m, d_m)
    assert x_m is s_m and y_m is d_m
    assert line.to_sd(5.0, 6.0) == (5.0, 6.0)
    assert line.heading_rad(5.0) == 0.0
    assert not BEND.is_straight_x


def test_a_centreline_needs_two_distinct_points():
    with pytest.raises(ValueError, match=">= 2 points"):
        Centreline(((0.0, 0.0),))
    with pytest.raises(ValueError, match="must differ"):
        Centreline(((0.0, 0.0), (0.0, 0.0)))


def test_one_point_in_floats_converts_as_the_arrays_do():
    line = Centreline(((0.0, 0.0), (50.0, 10.0), (90.0, -5.0), (120.0, 30.0)))
    rng = np.random.default_rng(1)
    s_m, d_m = rng.uniform(-10.0, line.length_m + 10.0, 300), rng.uniform(-8.0, 8.0, 300)
    x_m, y_m = line.to_xy(s_m, d_m)
    one = np.array([line.to_xy(float(s), float(d)) for s, d in zip(s_m, d_m, strict=True)])
    assert np.array_equal(one, np.column_stack([x_m, y_m]))
    back = np.array([line.to_sd(float(x), float(y)) for x, y in zip(x_m, y_m, strict=True)])
    assert np.array_equal(back, np.column_stack(line.to_sd(x_m, y_m)))
    assert isinstance(line.heading_rad(60.0), float)
    assert line.heading_rad(60.0) == pytest.approx(float(line.heading_rad(np.array([60.0]))[0]))
