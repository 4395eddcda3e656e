"""The e-scooter's 3D shape and how the real renderer draws it: a box of the model's size,
where the camera model says, and its bike lamp when lit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from citysim.render.beams import BEAMS, beam_of
from citysim.render.models import agent_shape, e_scooter_shape
from citysim.world.agents import AgentState
from tests.citysim.render.test_camera import CAM_X, CAM_Y, PINHOLE, box_iou, changed_box, renderer

SIZES = ((0.4, 1.6, 1.0), (0.5, 1.8, 1.1), (0.6, 2.0, 1.2))  # width, height, length, m


def scooter(x_m: float, y_m: float = 1.75, heading_rad: float = math.pi, **kw) -> AgentState:
    args = dict(speed_mps=5.5, length_m=1.1, width_m=0.5, height_m=1.8)
    args.update(kw)
    return AgentState(1, "e_scooter", x_m, y_m, heading_rad, **args)


@pytest.mark.parametrize("width_m, height_m, length_m", SIZES)
def test_shape_extents_are_the_drawn_sizes(width_m, height_m, length_m) -> None:
    shape = e_scooter_shape(width_m, height_m, length_m)
    assert shape.extents_m(0.0) == pytest.approx((length_m, width_m, height_m))
    assert shape.corners_m[..., 2].min() == pytest.approx(0.0)  # stands on the ground
    kinds = shape.part_kind
    assert kinds.count("wheel") == 2 and kinds.count("leg") == 2 and kinds.count("arm") == 2
    assert {"frame", "handlebar", "torso", "head"} <= set(kinds)


def test_rider_stands_on_the_deck_and_holds_the_handlebar() -> None:
    shape = e_scooter_shape(0.5, 1.8, 1.1)
    parts = dict(enumerate(shape.part_kind))
    legs = [shape.corners_m[i] for i, k in parts.items() if k == "leg"]
    bar = next(shape.corners_m[i] for i, k in parts.items() if k == "handlebar")
    arms = [shape.corners_m[i] for i, k in parts.items() if k == "arm"]
    deck_top = max(shape.corners_m[i][:, 2].max() for i, k in parts.items() if k == "frame"
                   and shape.corners_m[i][:, 2].max() < 0.5)  # fmt: skip
    for leg in legs:
        assert leg[:, 2].min() == pytest.approx(deck_top)  # feet on the deck
    assert abs(legs[0][:, 1].mean() - legs[1][:, 1].mean()) < 0.2  # legs together
    for arm in arms:  # hands at the handlebar, shoulders behind and above it
        hand = arm[arm[:, 2].argmin()]
        assert hand[0] == pytest.approx(bar[:, 0].mean(), abs=0.05)
        assert arm[:, 0].min() < hand[0] and arm[:, 2].max() > bar[:, 2].max()


def test_renderer_draws_a_truth_box_of_plausible_size() -> None:
    d_m = 14.0
    agent = scooter(d_m)
    r = renderer()
    empty = r.render(0.0, [], [0.0, 0.0]).image
    frame = r.render(0.0, [agent], [0.0, 0.0])
    (truth,) = frame.truth
    assert truth.cls == "e_scooter" and truth.fully_visible and not truth.touches_border
    assert box_iou((truth.x, truth.y, truth.w, truth.h), changed_box(empty, frame.image)) >= 0.9
    cam = PINHOLE.placed(x_m=CAM_X, y_m=CAM_Y)
    uv = cam.project(agent_shape(agent).corners_m.reshape(-1, 3), distort=False)
    assert truth.y == pytest.approx(uv[:, 1].min(), abs=1.0)
    # the lowest points are the wheels' bottom vertices, which cover no pixel centre of their own
    assert truth.y + truth.h - 1 == pytest.approx(uv[:, 1].max(), abs=1.5)
    # plausible: as tall as a 1.8 m figure standing there, narrower than tall
    v_head, v_feet = cam.project(
        np.array([[d_m, agent.y_m, agent.height_m], [d_m, agent.y_m, 0.0]]), distort=False
    )[:, 1]
    assert truth.h == pytest.approx(v_feet - v_head, rel=0.1)
    assert 0.2 < truth.w / truth.h < 0.8


def test_a_lit_e_scooter_carries_a_bike_lamp() -> None:
    assert beam_of("e_scooter") is BEAMS["bike_lamp"] is beam_of("cyclist")
    r = renderer()
    dark = r.render(0.0, [scooter(12.0)], [0.0, 0.0]).image.astype(int)
    lit = r.render(0.0, [scooter(12.0, light_on=True)], [0.0, 0.0]).image.astype(int)
    assert (lit - dark).max() > 50  # its lamp glares at the camera it rides toward
