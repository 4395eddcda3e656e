"""The street tracker: one track per road user across cameras, ghosts fade, lost walkers are carried."""

from __future__ import annotations

import numpy as np
import pytest

from citysim.control.fused import DEFAULT_ZONE_PROBABILITY
from citysim.control.fusion import existence, kalman
from citysim.control.fusion.births import P_BIRTH_ENTRY, P_BIRTH_INSIDE
from citysim.control.fusion.measurement import measure, pixel_covariance_m2
from citysim.control.fusion.zones import zone_probabilities
from tests.citysim.control.fusion_walks import FPS, Rig

WALK_MPS = 1.4
SIDEWALK_D_M = -4.3


def walk(rig: Rig, s0_m: float, s1_m: float, seed: int = 1, gone_after_m: float | None = None) -> list[int]:
    """A walker along the right sidewalk from ``s0_m`` to ``s1_m`` at 1.4 m/s (vanishing at
    ``gone_after_m`` if given, the frames going on); the street tracks its measurements fed."""
    rng = np.random.default_rng(seed)
    fed = []
    for k in range(int((s1_m - s0_m) / WALK_MPS * FPS)):
        s_m = s0_m + WALK_MPS * k / FPS
        where = None if gone_after_m is not None and s_m > gone_after_m else (s_m, SIDEWALK_D_M)
        fed += rig.step(k / FPS, where, rng)
    return fed


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_walker_crossing_from_one_cameras_view_to_the_next_keeps_one_street_track(seed):
    rig = Rig(two_way=True)  # views overlap (x 20-40 m: lamp 0's forward and lamp 1's backward camera)
    fed = walk(rig, 22.0, 66.0, seed)
    cameras_fed = {key[0] for t in rig.tracker.tracks for key in t.keys}
    assert len(set(fed)) == 1, f"the walker fed street tracks {sorted(set(fed))}"
    assert len(cameras_fed) >= 3  # lamp 0's forward, lamp 1's backward and forward (and lamp 2's backward)
    [track] = rig.tracker.tracks
    assert track.existence > 0.9
    assert track.mean[2] == pytest.approx(WALK_MPS, abs=0.4)  # its speed along the street, m/s


def test_a_ghost_seen_once_in_the_middle_of_a_view_lights_no_zone_beyond_its_own():
    rig = Rig()
    ghost = rig.detection(0, 31.0, SIDEWALK_D_M, track_id=7)  # lamp 0's camera sees x 21-40 m: 31 m is 5 m or more from either edge
    rig.tracker.observe(0, 0.0, [measure(rig.frame, rig.rays[0], 0, ghost, "pedestrian")])
    [track] = rig.tracker.tracks
    assert track.existence == pytest.approx(P_BIRTH_INSIDE)
    starts = np.array([s.zone_start_m for s in rig.street.lamps])
    ends = np.array([s.zone_end_m for s in rig.street.lamps])
    p, _ = zone_probabilities(rig.tracker.tracks, lambda cls: 2.0, starts, ends)
    own = int(np.flatnonzero((starts <= 31.0) & (ends > 31.0))[0])
    others = [j for j in range(len(p)) if j != own]
    assert max(p[others]) < 0.5 * DEFAULT_ZONE_PROBABILITY
    assert p[own] <= P_BIRTH_INSIDE + 1e-9
    # the camera keeps looking and sees nothing there: the ghost is dropped within half a second
    for k in range(1, 8):
        rig.tracker.observe(0, k / FPS, [])
    assert rig.tracker.tracks == []


def test_a_walker_lost_in_a_blind_stretch_is_carried_into_the_next_view_and_dropped_when_seen_empty():
    rig = Rig()  # forward cameras only: x 40-51 m (under lamp 1's pole) is seen by no camera
    assert not rig.views.seen_sd(46.0, SIDEWALK_D_M).any()
    rng = np.random.default_rng(4)
    t_s, track_id = 0.0, None
    for k in range(int((40.0 - 24.0) / WALK_MPS * FPS)):  # seen by lamp 0's camera from 24 m to 40 m
        t_s = k / FPS
        rig.step(t_s, (24.0 + WALK_MPS * t_s, SIDEWALK_D_M), rng)
    [track] = rig.tracker.tracks
    track_id, p_lost = track.id, track.existence
    # in the blind stretch: nobody sees it, it is carried at its speed, its existence untouched by lamp 1's camera
    t_blind_s = t_s + 6.0 / WALK_MPS
    for k in range(1, int(6.0 / WALK_MPS * FPS) + 1):
        rig.step(t_s + k / FPS, None, rng)
    [track] = rig.tracker.tracks
    assert track.id == track_id
    assert track.s_m == pytest.approx(24.0 + WALK_MPS * t_blind_s, abs=1.5)
    assert track.existence > 0.5 * p_lost
    # it walks on into lamp 1's camera's view... but it vanished: that camera sees the place empty
    enters_m = next(s for s in np.arange(46.0, 70.0, 0.1) if rig.views.seen_sd(s, SIDEWALK_D_M)[1])
    for k in range(1, int(30.0 / WALK_MPS * FPS)):
        rig.step(t_blind_s + k / FPS, None, rng)
        if not rig.tracker.tracks:
            break
    assert rig.tracker.tracks == []
    dropped_at_m = 24.0 + WALK_MPS * (t_blind_s + k / FPS)
    assert enters_m <= dropped_at_m <= enters_m + 10.0  # within 10 m (7 s at its pace) of entering the view


def test_a_walker_carried_across_a_blind_stretch_is_picked_up_by_the_next_camera_as_the_same_track():
    rig = Rig()
    fed = walk(rig, 24.0, 62.0, seed=5)
    assert len(set(fed)) == 1


def test_newcomers_are_likely_at_a_view_edge_next_to_a_blind_stretch_and_unlikely_mid_view():
    births = Rig().tracker.births
    assert births.prior(23.0) == P_BIRTH_ENTRY  # 2 m into lamp 0's view, after the street's unseen start
    assert births.prior(52.0) == P_BIRTH_ENTRY  # just past the blind stretch under lamp 1's pole
    assert births.prior(31.0) == P_BIRTH_INSIDE


def test_the_range_error_grows_with_distance_and_the_lateral_error_too():
    rig = Rig()
    rays = rig.rays[0]
    cam = rig.street.cameras[0].camera
    u = (cam.width_px - 1) / 2.0
    near, far = pixel_covariance_m2(rays, u, cam.height_px - 10.0), pixel_covariance_m2(rays, u, cam.height_px * 0.45)
    # the camera looks along +x: x is range, y lateral
    assert far[0, 0] > 4.0 * near[0, 0]
    assert far[1, 1] > near[1, 1]


def test_existence_falls_by_each_miss_in_view_and_not_out_of_it():
    p = 0.9
    assert existence.after_miss(p, 0.0) == p
    once = existence.after_miss(p, 1.0)
    assert once < p and existence.after_miss(once, 1.0) < once
    assert existence.after_hit(0.5) == pytest.approx(existence.HIT_LIKELIHOOD_RATIO / (1 + existence.HIT_LIKELIHOOD_RATIO))


def test_kalman_prediction_in_two_steps_equals_one():
    mean, cov = np.array([10.0, 1.0, 1.4, 0.0]), np.diag([0.5, 0.3, 1.0, 0.5])
    one = kalman.predict(mean, cov, 1.0, "pedestrian")
    two = kalman.predict(*kalman.predict(mean, cov, 0.4, "pedestrian"), 0.6, "pedestrian")
    np.testing.assert_allclose(one[0], two[0], atol=1e-12)
    np.testing.assert_allclose(one[1], two[1], atol=1e-12)
