"""Fitting the sensor model on tiny synthetic calibration sets with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from citysim.fast.model import (
    KINDS,
    PRIOR_FRAMES,
    SensorModel,
    background_age_bin,
    cell_of,
    fit_sensor_model,
    nearest_in_view,
    threshold_conditions,
)
from tests.citysim.fast.synthetic import frames, rows

PED, CAR = KINDS.index("pedestrian"), KINDS.index("vehicle")


def _cell(model: SensorModel, kind: int, forward_m: float, light: float = 0.2, speed_mps: float = 1.4) -> float:
    return float(model.p_hit_array()[cell_of([kind], [forward_m], [0.0], [light], [False], [speed_mps])][0])


def test_hit_rates_are_the_counts_shrunk_toward_the_coarser_cell():
    # 400 pedestrian sightings at 9.5 m, 300 of them detected; 400 at 21.5 m, 40 detected
    near = rows(400, forward_m=9.5, hit=np.arange(400) < 300, det_class=1)
    far = rows(400, forward_m=21.5, hit=np.arange(400) < 40, det_class=1, object_id=2)
    both = {k: np.concatenate([near[k], far[k]]) for k in near}
    model = fit_sensor_model(both, frames(10), camera_hours=1.0)
    # every level of the hierarchy holds the same 400 rows, so each shrinks toward a parent that is
    # already near 0.75 (resp. 0.10): the cell is within 4 / 404 of the raw rate
    assert _cell(model, PED, 9.5) == pytest.approx(0.75, abs=PRIOR_FRAMES / 400)
    assert _cell(model, PED, 21.5) == pytest.approx(0.10, abs=PRIOR_FRAMES / 400)
    # a distance bin never seen falls back to the kind's pooled rate (340 of 800)
    assert _cell(model, PED, 3.0) == pytest.approx(340 / 800, abs=0.01)
    # a target kind never seen (vehicles) takes the pooled rate of all targets
    assert _cell(model, CAR, 9.5) == pytest.approx(340 / 800, abs=0.01)


def test_streaks_of_misses_give_a_persistence_near_the_chain_that_made_them():
    rng = np.random.default_rng(3)
    p, rho, n = 0.5, 0.6, 6000
    hit = np.zeros(n, dtype=bool)
    hit[0] = True
    for i in range(1, n):
        q = p + rho * (1 - p) if hit[i - 1] else p * (1 - rho)
        hit[i] = rng.random() < q
    model = fit_sensor_model(rows(n, hit=hit, det_class=np.where(hit, 1, -1)), frames(10), camera_hours=1.0)
    # 6000 frames: the lag-1 correlation's standard error is about 1 / sqrt(6000) = 0.013
    assert model.persistence["pedestrian"] == pytest.approx(rho, abs=0.06)
    assert model.persistence["vehicle"] == 0.0  # never seen: independent draws


def test_false_alarm_episodes_are_counted_per_judged_frame():
    # 1000 judged frames of one camera, dim: an episode of 3 frames starts every 100 frames
    fa = (np.arange(1000) % 100) < 3
    model = fit_sensor_model(rows(0), frames(1000, fa=fa, fa_distance_m=14.0), camera_hours=0.5)
    assert model.fa_length_frames == [3] * 10
    # 10 starts among the frames not already in an episode (1000 - 10 x 2 continuing frames)
    assert model.fa_start_p[0] == pytest.approx(10 / 980)
    assert model.fa_start_p[1] == 0.0  # no lit frames seen
    assert model.fa_per_camera_hour == pytest.approx(20.0)
    assert {r[0] for r in model.fa_reports} == {14.0}


def test_detected_classes_and_threshold_areas_come_from_their_frames():
    hit = np.arange(100) < 50
    det = np.where(np.arange(100) < 40, 4, 3)  # vehicles reported as 'vehicle' 40 times, 'cyclist' 10
    car_rows = rows(100, kind=CAR, hit=hit, det_class=np.where(hit, det, -1), speed_mps=11.0)
    area = frames(4, near_kind=[-1, -1, CAR, CAR], near_forward_m=[np.nan, np.nan, 9.0, 9.0],
                  area_fraction=[0.0, 0.001, 0.08, 0.06], age_bin=[0, 2, 2, 2])
    model = fit_sensor_model(car_rows, area, camera_hours=1.0)
    classes = model.class_given_hit["vehicle"]
    assert classes[4] == pytest.approx(40.5 / 50.5) and classes[3] == pytest.approx(10 / 50.5)
    assert model.area_fraction["none/dim"] == [0.0, 0.001]
    # a just-rebuilt background's frames are kept apart too (looked up first in fast mode)
    assert model.area_fraction["none/dim/age0"] == [0.0] and model.area_fraction["none/dim/age2"] == [0.001]
    assert model.area_fraction["vehicle/2/dim"] == [0.08, 0.06] == model.area_fraction["vehicle/2/dim/age2"]
    assert model.area_fraction["vehicle/2"] == [0.08, 0.06]  # a candidate's key without the light too
    assert threshold_conditions(CAR, 9.0, True, 2) == ("vehicle/2/lit/age2", "vehicle/2/lit", "vehicle/2")
    assert threshold_conditions(-1, np.nan, False, 0) == ("none/dim/age0", "none/dim")
    # nothing in view 3 s after a far lamp changed level: that bin's samples first, then nothing in view's
    assert threshold_conditions(-1, np.nan, False, 2, far_change_age_s=3.0) == ("none/far0/dim/age2", "none/far0/dim",
                                                                                 "none/dim/age2", "none/dim")
    assert threshold_conditions(-1, np.nan, False, 2, far_change_age_s=12.0)[0] == "none/far1/dim/age2"
    assert threshold_conditions(-1, np.nan, False, 2, far_change_age_s=30.0) == ("none/dim/age2", "none/dim")
    far = frames(4, area_fraction=[0.0, 0.0, 0.02, 0.03], far_change_s=[np.inf, 45.0, 1.0, 2.0])
    far_model = fit_sensor_model(rows(0), far, camera_hours=1.0)
    assert far_model.area_fraction["none/dim"] == [0.0, 0.0] and far_model.area_fraction["none/far0/dim"] == [0.02, 0.03]
    # with nothing in view, only the frames every camera is judged count (idle cameras: every 15th)
    idle = frames(30, area_fraction=np.where(np.arange(30) % 15 == 0, 0.0, 0.08))
    assert fit_sensor_model(rows(0), idle, camera_hours=1.0, idle_frame_stride=15).area_fraction["none/dim"] == [0.0, 0.0]
    assert background_age_bin(1.0) == 0 and background_age_bin(1 / 32) == 1 and background_age_bin(1 / 500) == 2


def test_big_foreground_regions_last_as_long_as_calibration_saw_them():
    # episodes of 20 frames over 5 % of the frame, then 180 frames of nothing, on two cameras:
    # P(over next | over now) = 19/20 and P(over) = 0.1, so keep = (0.95 - 0.1) / 0.9 = 0.944
    n, episode = 4000, (np.arange(4000) % 200) < 20
    camera = np.repeat([0, 1], n // 2)
    frame = np.tile(np.arange(n // 2), 2)
    area = frames(n, camera=camera, frame=frame, area_fraction=np.where(episode, 0.08, 0.0))
    assert fit_sensor_model(rows(0), area, camera_hours=1.0).area_persistence == pytest.approx(0.944, abs=0.002)
    # the same shares in independent frames: nothing to keep
    shuffled = frames(n, camera=camera, frame=frame,
                      area_fraction=np.random.default_rng(5).permutation(np.where(episode, 0.08, 0.0)))
    assert fit_sensor_model(rows(0), shuffled, camera_hours=1.0).area_persistence == pytest.approx(0.0, abs=0.03)
    # frames that are not consecutive (an idle camera judged every 15th) are no pair
    strided = frames(n, camera=camera, frame=frame * 15, area_fraction=np.where(episode, 0.08, 0.0))
    assert fit_sensor_model(rows(0), strided, camera_hours=1.0).area_persistence == 0.0


def test_a_frame_with_only_a_beam_in_view_is_the_beams_condition():
    beam = KINDS.index("beam")
    assert nearest_in_view(np.array([PED, CAR]), np.array([14.0, 9.0]), np.array([3.0])) == (CAR, 9.0)
    assert nearest_in_view(np.array([]), np.array([]), np.array([12.0, 7.0])) == (beam, 7.0)
    kind, forward_m = nearest_in_view(np.array([]), np.array([]), np.array([]))
    assert kind == -1 and np.isnan(forward_m)


def test_each_decision_set_has_its_own_hit_and_false_alarm_tables():
    # frame decisions: an insect is a target in 1 judged frame of 10 and a walker in 3 of 4; its
    # track decisions (plausibility) call the insect a target in 1 frame of 100, the walker in 1 of
    # 2; the frames of plausible tracks the insect in 1 of 50, the walker in 5 of 8
    n = 400
    walker = rows(n, forward_m=9.5, hit=np.arange(n) % 4 != 0, det_class=1, track_hit=np.arange(n) % 2 == 0,
                  track_det_class=1, plausible_hit=np.arange(n) % 8 < 5, plausible_det_class=1)
    fa, track_fa, plausible_fa = (np.arange(1000) % m == 0 for m in (10, 100, 50))
    model = fit_sensor_model(walker, frames(1000, fa=fa, track_fa=track_fa, track_fa_distance_m=7.0,
                                            plausible_fa=plausible_fa), camera_hours=1.0)
    tracks, plausible = model.for_decisions("track"), model.for_decisions("plausible")
    assert model.for_decisions("frame") is model
    assert _cell(model, PED, 9.5) == pytest.approx(0.75, abs=PRIOR_FRAMES / n)
    assert _cell(tracks, PED, 9.5) == pytest.approx(0.50, abs=PRIOR_FRAMES / n)
    assert _cell(plausible, PED, 9.5) == pytest.approx(0.625, abs=PRIOR_FRAMES / n)
    assert (model.fa_per_camera_hour, tracks.fa_per_camera_hour, plausible.fa_per_camera_hour) == (100, 10, 20)
    assert {r[0] for r in tracks.fa_reports} == {7.0}
    # what they share is kept; a model fitted without a set's columns says to recalibrate
    assert tracks.area_fraction == model.area_fraction and tracks.track is None and plausible.plausible is None
    frame_only = {k: v for k, v in walker.items() if not k.startswith(("track_", "plausible_"))}
    with pytest.raises(ValueError, match="recalibrate"):
        fit_sensor_model(frame_only, frames(10), camera_hours=1.0).for_decisions("plausible")


def test_a_saved_model_loads_equal(tmp_path):
    model = fit_sensor_model(rows(50, hit=np.arange(50) % 2 == 0, det_class=1), frames(20), camera_hours=1.0, key="k")
    model.save(tmp_path / "m.json")
    assert SensorModel.load(tmp_path / "m.json") == model


def test_no_judged_frames_is_an_error_naming_calibration():
    with pytest.raises(ValueError, match="calibration: no judged camera frames"):
        fit_sensor_model(rows(0), frames(0), camera_hours=1.0)


def test_region_sizes_come_from_the_frames_given_for_them_and_false_alarms_from_all():
    # calibration gives its region nights' frames (only the columns a region night records) for
    # the threshold baselines' region sizes, and its detector nights' frames for the rest
    from citysim.fast.region_records import REGION_COLUMNS

    busy = frames(4, area_fraction=[0.0, 0.01, 0.0, 0.01])
    quiet = frames(4, area_fraction=[0.2, 0.3, 0.2, 0.3], fa=[True, False, False, False])
    both = {col: np.concatenate([busy[col], quiet[col]]) for col in busy}
    region_night = {col: busy[col] for col in REGION_COLUMNS}
    model = fit_sensor_model(rows(0), both, camera_hours=1.0, area_frames=region_night)
    assert model.area_fraction["none/dim"] == [0.0, 0.01, 0.0, 0.01]
    assert model.fa_start_p[0] > 0  # the quiet night's false alarm still counts
    assert fit_sensor_model(rows(0), both, camera_hours=1.0).area_fraction["none/dim"] == list(both["area_fraction"])
