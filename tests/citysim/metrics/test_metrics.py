"""Streaming metrics: zone lag and dark exposure against hand computations,
detection confusion on hand-made frames, energy summary against always-on."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

from citysim.config.street import LuminaireSpec
from citysim.control.lamps import Lamp
from citysim.metrics.confusion import CONFUSION_CLASSES, DetectionConfusion
from citysim.metrics.energy import energy_summary
from citysim.metrics.quantiles import QuantileSketch
from citysim.metrics.zones import ZoneTracker
from citysim.world.agents import AgentState
from citysim.world.street import LampSite, Lane, Sidewalk, Street
from detector.camera import CameraModel

DT_S = 1 / 30  # physics step
CAMERA = CameraModel(
    height_m=5.0,
    tilt_deg=20.0,
    focal_mm=3.6,
    sensor_w_mm=4.8,
    sensor_h_mm=3.6,
    width_px=320,
    height_px=240,
)


def _street(zones_m: list[tuple[float, float]]) -> Street:
    lamps = tuple(
        LampSite(i, (a + b) / 2, -4.0, 6.0, CAMERA.placed(x_m=(a + b) / 2, y_m=-4.0), a, b)
        for i, (a, b) in enumerate(zones_m)
    )
    return Street(100.0, (Lane(0.0, 3.5, 1),), (Sidewalk(-3.0, 2.0),), lamps)


def _agent(
    object_id: int, cls: str, x_m: float, speed_mps: float, heading_rad: float = 0.0
) -> AgentState:
    return AgentState(object_id, cls, x_m, 0.0, heading_rad, speed_mps, 0.5, 0.5, 1.7)


def _drive(tracker: ZoneTracker, lamps: list[Lamp], events, paths, t_end_s: float) -> list[dict]:
    """Step the tracker at DT_S. events: (t_s, lamp, level); paths: object -> f(t) -> AgentState | None."""
    pending = sorted(events)
    for k in range(int(round(t_end_s / DT_S)) + 1):
        t_s = k * DT_S
        while pending and pending[0][0] <= t_s:
            t_event, j, level = pending.pop(0)
            lamps[j].set_target(t_event, level)  # a controller acts at its own instant
        agents = [a for a in (path(t_s) for path in paths) if a is not None]
        tracker.update(t_s, agents, np.array([lamp.level_at(t_s) for lamp in lamps]))
    tracker.finish(t_end_s)
    return list(tracker.rows())


def test_pedestrian_past_one_lamp_entry_lag_and_dark_exposure_match_hand_computation():
    street = _street([(10.0, 20.0), (20.0, 30.0)])
    spec = LuminaireSpec(dim_level=0.2, ramp_up_s=0.3, fade_s=1.0)
    lamps = [Lamp(i, spec, True, 0.2) for i in range(2)]
    speed = 1.4
    tracker = ZoneTracker(street)
    rows = _drive(
        tracker,
        lamps,
        [(8.0, 0, 1.0), (12.0, 0, 0.2)],  # lit at 8.0 (full at 8.24), dimmed again at 12.0
        [lambda t: _agent(1, "pedestrian", speed * t, speed)],
        25.0,
    )
    assert [r["lamp"] for r in rows] == [0, 1]
    first, second = rows
    t_in0, t_out0, t_out1 = 10 / speed, 20 / speed, 30 / speed
    assert first["t_enter_s"] == pytest.approx(t_in0, abs=DT_S)
    assert first["t_exit_s"] == pytest.approx(t_out0, abs=DT_S)
    assert first["lag_s"] == pytest.approx(8.24 - t_in0, abs=DT_S)
    # dark before full light, and again from the dimming until the exit
    assert first["dark_s"] == pytest.approx((8.24 - t_in0) + (t_out0 - 12.0), abs=DT_S)
    assert first["lit"] and not first["lit_on_entry"] and first["completed"]
    # lamp 1 never lit: the lag is the whole time inside and the crossing is unlit
    assert not second["lit"]
    assert second["lag_s"] == pytest.approx(t_out1 - t_out0, abs=DT_S)
    assert second["dark_s"] == pytest.approx(t_out1 - t_out0, abs=DT_S)

    s = tracker.summary()
    ped = s["by_class"]["pedestrian"]
    assert ped["objects"] == 1 and ped["visits"] == 2 and ped["unlit_crossings"] == 1
    assert ped["dark_exposure_total_s"] == pytest.approx(
        first["dark_s"] + second["dark_s"], rel=1e-9
    )
    assert ped["lag_max_s"] == pytest.approx(second["lag_s"], rel=1e-9)
    assert s["overall"]["unlit_crossings"] == 1
    assert (
        s["by_class"]["vehicle"]["objects"] == 0 and s["by_class"]["vehicle"]["lag_p50_s"] is None
    )


def test_a_lower_required_level_is_reached_earlier_on_the_ramp():
    street = _street([(10.0, 20.0)])
    lamps = [Lamp(0, LuminaireSpec(ramp_up_s=0.3), True, 0.2)]
    tracker = ZoneTracker(street, required_level={"pedestrian": 0.5})
    rows = _drive(
        tracker, lamps, [(8.0, 0, 1.0)], [lambda t: _agent(1, "pedestrian", 1.4 * t, 1.4)], 16.0
    )
    # 0.2 -> 0.5 takes 0.3 * 0.3 = 0.09 s
    assert rows[0]["lag_s"] == pytest.approx(8.09 - 10 / 1.4, abs=DT_S)


def test_a_vehicle_with_lookahead_enters_early_in_both_directions():
    street = _street([(10.0, 20.0), (20.0, 30.0)])
    lamps = [Lamp(i, LuminaireSpec(ramp_up_s=0.0), True, 0.2) for i in range(2)]
    v = 60 / 3.6
    paths = [
        lambda t: _agent(1, "vehicle", -50.0 + v * t, v),  # toward +x
        lambda t: _agent(2, "vehicle", 80.0 - v * t, v, math.pi),  # toward -x
    ]
    tracker = ZoneTracker(street, lookahead_s={"vehicle": 2.0})
    rows = _drive(tracker, lamps, [(2.0, 0, 1.0)], paths, 3.0)
    east = {r["lamp"]: r for r in rows if r["object_id"] == 1}
    west = {r["lamp"]: r for r in rows if r["object_id"] == 2}
    # the front of the need span (x + 2 s * v) reaches 10 m at 1.6 s; the centre only at 3.6 s
    assert east[0]["t_enter_s"] == pytest.approx((10 - 2 * v + 50) / v, abs=DT_S)
    assert east[0]["lag_s"] == pytest.approx(2.0 - 1.6, abs=DT_S)
    assert not east[0]["completed"]  # still inside when the run ended
    # heading -x: x - 2 s * v drops below 30 m at 1.0 s
    assert west[1]["t_enter_s"] == pytest.approx((80 - 30 - 2 * v) / v, abs=DT_S)

    plain = ZoneTracker(street, lookahead_s={})
    lamps = [Lamp(i, LuminaireSpec(ramp_up_s=0.0), True, 0.2) for i in range(2)]
    rows = _drive(plain, lamps, [(2.0, 0, 1.0)], paths[:1], 4.0)
    assert rows[0]["t_enter_s"] == pytest.approx(60 / v, abs=DT_S)
    assert rows[0]["lag_s"] == 0.0 and rows[0]["lit_on_entry"]


def test_overlapping_needs_in_two_dark_zones_count_once_toward_dark_exposure():
    street = _street([(10.0, 20.0), (20.0, 30.0)])
    lamps = [Lamp(i, LuminaireSpec(), True, 0.2) for i in range(2)]
    v = 60 / 3.6
    tracker = ZoneTracker(street, lookahead_s={"vehicle": 2.0})
    rows = _drive(tracker, lamps, [], [lambda t: _agent(1, "vehicle", -50.0 + v * t, v)], 6.0)
    # zone 0 needed from 1.6 s to 4.2 s, zone 1 from 2.2 s to 4.8 s
    assert [r["dark_s"] for r in rows] == pytest.approx([2.6, 2.6], abs=DT_S)
    total = tracker.summary()["by_class"]["vehicle"]["dark_exposure_total_s"]
    assert total == pytest.approx(4.8 - 1.6, abs=DT_S)


def test_rows_drain_and_summary_quantiles_follow_the_rows():
    street = _street([(0.0, 10.0)])
    lamps = [Lamp(0, LuminaireSpec(ramp_up_s=0.0), True, 0.2)]
    tracker = ZoneTracker(street)
    speeds = np.linspace(0.8, 2.0, 25)
    paths = [
        lambda t, k=k, s=s: _agent(k, "pedestrian", -5.0 - k + s * t, s)
        for k, s in enumerate(speeds)
    ]
    rows = _drive(tracker, lamps, [(12.0, 0, 1.0)], paths, 40.0)
    assert len(rows) == 25 and list(tracker.rows()) == []  # drained
    lags = np.array([r["lag_s"] for r in rows])
    s = tracker.summary()["overall"]
    assert s["visits"] == 25 and s["objects"] == 25
    for q, key in ((0.5, "lag_p50_s"), (0.95, "lag_p95_s")):
        assert s[key] == pytest.approx(np.quantile(lags, q, method="lower"), rel=0.006)
    assert s["lag_max_s"] == lags.max()


def test_an_object_that_vanishes_closes_its_visit_where_it_was_last_seen():
    street = _street([(0.0, 10.0)])
    tracker = ZoneTracker(street)
    tracker.update(
        0.0, [_agent(1, "pedestrian", 5.0, 1.0), _agent(9, "animal", 5.0, 1.0)], np.array([1.0])
    )
    tracker.update(0.5, [_agent(1, "pedestrian", 5.5, 1.0)], np.array([1.0]))
    tracker.update(1.0, [], np.array([1.0]))
    rows = list(tracker.rows())
    assert len(rows) == 1  # animals are not tracked
    assert rows[0]["t_enter_s"] == 0.0 and rows[0]["t_exit_s"] == 0.5 and rows[0]["lit_on_entry"]


def test_zone_tracker_errors_name_the_field():
    street = _street([(0.0, 10.0), (10.0, 20.0)])
    tracker = ZoneTracker(street)
    with pytest.raises(ValueError, match="levels"):
        tracker.update(0.0, [], np.array([1.0]))
    tracker.update(1.0, [], np.array([1.0, 1.0]))
    with pytest.raises(ValueError, match="t_s: must increase"):
        tracker.update(1.0, [], np.array([1.0, 1.0]))
    with pytest.raises(ValueError, match=r"required_level\.pedestrian"):
        ZoneTracker(street, required_level={"pedestrian": 2.0})
    with pytest.raises(ValueError, match=r"lookahead_s\.vehicle"):
        ZoneTracker(street, lookahead_s={"vehicle": -1.0})
    with pytest.raises(ValueError, match=r"lamps\[0\]: zone_end_m"):
        ZoneTracker(_street([(5.0, 5.0)]))


def test_quantile_sketch_is_within_half_a_percent_of_exact_quantiles():
    rng = np.random.default_rng(2)
    values = np.concatenate(
        [np.zeros(300), rng.exponential(2.0, 5000), rng.uniform(1e-4, 1e-3, 200)]
    )
    rng.shuffle(values)
    sketch = QuantileSketch()
    for v in values:
        sketch.add(float(v))
    for q in (0.05, 0.5, 0.9, 0.95, 0.99):
        assert sketch.quantile(q) == pytest.approx(
            np.quantile(values, q, method="lower"), rel=0.005, abs=1e-12
        )
    assert sketch.max == values.max() and sketch.count == values.size
    assert len(sketch._bins) < 2500  # memory bounded by the value range, not the count


# ---------------------------------------------------------------------- confusion
@dataclass(frozen=True)
class Truth:  # stand-in for citysim.render.camera.TruthObject
    object_id: int
    cls: str
    x: int
    y: int
    w: int
    h: int
    touches_border: bool = False
    fully_visible: bool = True
    distance_m: float = 10.0


@dataclass(frozen=True)
class Det:  # stand-in for detector.detector.Detection
    box_px: tuple[int, int, int, int]
    cls: str
    p_target: float


def _index(cls):
    return CONFUSION_CLASSES.index(cls)


def test_confusion_counts_a_hit_a_miss_a_false_positive_and_an_animal_rejected():
    truth = [
        Truth(1, "pedestrian", 10, 10, 20, 40),
        Truth(2, "cyclist", 100, 50, 30, 40),  # not detected: a miss
        Truth(3, "animal", 200, 150, 30, 20),
        Truth(
            4, "vehicle", 300, 100, 20, 60, touches_border=True, fully_visible=False
        ),  # cut: not a miss
    ]
    dets = [
        Det((12, 12, 20, 40), "pedestrian", 0.9),
        Det((250, 10, 20, 20), "vehicle", 0.8),  # matches nothing: a false positive
        Det((201, 150, 30, 20), "noise", 0.1),  # the animal, correctly noise
    ]
    conf = DetectionConfusion()
    conf.add(truth, dets, lamp_index=0, t_s=0.0)
    conf.finish()
    s = conf.summary()
    assert (s["tp"], s["fn"], s["fp"], s["tn"]) == (1, 1, 1, 1)
    c = np.array(s["confusion_5"])
    assert c.sum() == 4
    assert c[_index("pedestrian"), _index("pedestrian")] == 1
    assert c[_index("cyclist"), _index("noise")] == 1
    assert c[_index("noise"), _index("vehicle")] == 1
    assert c[_index("noise"), _index("noise")] == 1
    assert s["tpr"] == 0.5 and s["precision"] == 0.5
    assert s["fpr"] == 0.5  # one of two noise regions called a target
    assert s["fp_per_frame"] == 1.0 and s["fp_per_region"] == pytest.approx(1 / 3)
    # passes: pedestrian detected, cyclist missed, the cut-off vehicle never fully seen
    assert s["object_passes"] == 2 and s["miss_rate"] == 0.5
    assert s["miss_rate_by_class"]["cyclist"] == 1.0
    assert s["miss_rate_by_class"]["pedestrian"] == 0.0
    assert s["miss_rate_by_class"]["vehicle"] is None


def test_per_object_miss_rate_over_frames_and_passes():
    conf = DetectionConfusion(pass_gap_s=1.0)
    ped = Truth(7, "pedestrian", 50, 50, 20, 50)
    # three frames: missed twice, then detected once -> the pass is not missed
    for t_s, dets in ((0.0, []), (0.1, []), (0.2, [Det((51, 50, 20, 50), "group", 0.7)])):
        conf.add([ped], dets, lamp_index=2, t_s=t_s)
    # it walks out of view and comes back 5 s later: a new pass, never detected
    for t_s in (5.2, 5.3):
        conf.add([ped], [], lamp_index=2, t_s=t_s)
    # another lamp sees a vehicle it detects only below the threshold
    conf.add(
        [Truth(8, "vehicle", 0, 100, 80, 40)],
        [Det((0, 100, 80, 40), "vehicle", 0.4)],
        lamp_index=3,
        t_s=0.0,
    )
    conf.finish()
    s = conf.summary()
    assert s["object_passes"] == 3 and s["missed_passes"] == 2
    assert s["miss_rate"] == pytest.approx(2 / 3)
    assert s["tp"] == 1 and s["fn"] == 5 and s["fp"] == 0
    c = np.array(s["confusion_5"])
    assert c[_index("pedestrian"), _index("group")] == 1  # a target, but the wrong target class
    assert c[_index("vehicle"), _index("vehicle")] == 1  # right class, yet not a target by p_target


def test_greedy_matching_gives_each_detection_to_its_best_truth():
    conf = DetectionConfusion()
    truth = [Truth(1, "pedestrian", 0, 0, 20, 40), Truth(2, "cyclist", 12, 0, 20, 40)]
    conf.add(truth, [Det((11, 0, 20, 40), "cyclist", 0.9)], lamp_index=0, t_s=0.0)
    c = np.array(conf.summary()["confusion_5"])
    assert c[_index("cyclist"), _index("cyclist")] == 1
    assert c[_index("pedestrian"), _index("noise")] == 1


def test_unknown_detection_class_names_the_field():
    with pytest.raises(ValueError, match=r"detections\.cls"):
        DetectionConfusion().add([], [Det((0, 0, 5, 5), "dog", 0.9)], lamp_index=0, t_s=0.0)
    with pytest.raises(ValueError, match=r"DetectionConfusion\.iou_threshold"):
        DetectionConfusion(iou_threshold=1.3)


# ---------------------------------------------------------------------- energy
def test_energy_summary_against_always_on():
    spec = LuminaireSpec(
        rated_power_w=60.0, dim_level=0.2, standby_power_w=0.5, sensing_power_w=5.0
    )
    base = [Lamp(i, spec, senses=False, initial_level=1.0) for i in range(3)]
    smart = [Lamp(i, spec, senses=True, initial_level=0.2) for i in range(3)]
    smart[1].set_target(40.0, 1.0)
    smart[1].set_target(50.0, 0.2)
    for lamp in base + smart:
        lamp.advance(100.0)
    always_j = energy_summary(base, 1.0)["energy_j"]
    assert always_j == 3 * 60.0 * 100.0
    s = energy_summary(smart, always_j)
    expected_j = sum(lamp.energy_j for lamp in smart)
    assert s["energy_kwh"] == pytest.approx(expected_j / 3.6e6)
    assert s["savings_vs_always_on"] == pytest.approx(1 - expected_j / always_j)
    assert s["switches"] == 2
    assert s["sensing_energy_kwh"] == pytest.approx(3 * 5.0 * 100 / 3.6e6)
    assert s["on_time_s"] == pytest.approx(smart[1].on_time_s)
    smart[0].advance(120.0)
    with pytest.raises(ValueError, match="same t_s"):
        energy_summary(smart, always_j)
    with pytest.raises(ValueError, match="always_on_energy_j"):
        energy_summary(base, 0.0)


def test_tracker_state_stays_bounded_as_objects_come_and_go():
    street = _street([(0.0, 10.0), (10.0, 20.0), (20.0, 30.0)])
    tracker = ZoneTracker(street)
    levels = np.array([1.0, 0.2, 1.0])
    largest = 0
    for k in range(3100):
        t_s = k * DT_S
        # a new pedestrian every second (100 of them), each living 3 s: at most 3 alive at once
        alive = [n for n in range(int(t_s) - 2, int(t_s) + 1) if 0 <= n < 100]
        agents = [_agent(n, "pedestrian", 10.0 * (t_s - n), 10.0) for n in alive]
        tracker.update(t_s, agents, levels)
        largest = max(largest, len(tracker._tracks), len(tracker._done))
        if k % 30 == 0:
            for _ in tracker.rows():
                pass
    tracker.finish(t_s)
    assert largest <= 3 * 3
    s = tracker.summary()["overall"]
    assert s["objects"] == 100 and s["visits"] == 100 * 3
    assert s["unlit_crossings"] == 100  # every pedestrian crosses the dim middle zone


@pytest.mark.parametrize("seed", range(20))
def test_matching_on_plain_floats_pairs_as_the_iou_matrix_does(seed):
    # small integer boxes on a small grid: many equal IoUs (ties), empty overlaps and zero-area boxes
    from citysim.metrics.confusion import greedy_match, iou_matrix, match_boxes

    rng = np.random.default_rng(seed)
    for _ in range(200):
        a = [tuple(int(v) for v in row) for row in rng.integers(0, 6, size=(int(rng.integers(1, 5)), 4))]
        b = [tuple(int(v) for v in row) for row in rng.integers(0, 6, size=(int(rng.integers(1, 5)), 4))]
        for threshold in (0.0, 0.3, 0.5):
            assert match_boxes(a, b, threshold) == greedy_match(iou_matrix(a, b), threshold)


class _EveryFrameMatched(DetectionConfusion):
    """The slow path: every frame matched (no shortcut for empty frames) and every frame's passes
    scanned for ended ones."""

    def add(self, truth, detections, lamp_index, t_s):
        self._add_matched(truth, detections, lamp_index, t_s)

    def _end_passes(self, lamp_index, t_s):
        passes = self._passes.get(lamp_index, {})
        for object_id in [i for i, p in passes.items() if t_s - p.last_seen_s > self.pass_gap_s]:
            self._end_pass(passes.pop(object_id))


@pytest.mark.parametrize("seed", range(5))
def test_the_shortcuts_count_as_matching_every_frame_does(seed):
    # road users coming and going in the views of 3 cameras, now and then detected, at 15 fps
    rng = np.random.default_rng(seed)
    fast, slow = DetectionConfusion(), _EveryFrameMatched()
    classes = ["pedestrian", "cyclist", "vehicle", "group", "dog"]
    for frame in range(3000):
        t_s = frame / 15
        for lamp in range(3):
            in_view = [i for i in range(8) if rng.random() < 0.15]
            truth = [Truth(i, classes[i % 5], 10 * i, 0, 20, 40, fully_visible=bool(rng.random() < 0.7)) for i in in_view]
            dets = [Det((10 * i + int(rng.integers(-3, 4)), 0, 20, 40), "pedestrian", float(rng.random()))
                    for i in in_view if rng.random() < 0.3]  # fmt: skip
            for conf in (fast, slow):
                conf.add(truth, dets, lamp, t_s)
    for conf in (fast, slow):
        conf.finish()
    assert fast.summary() == slow.summary() and fast.summary()["object_passes"] > 50
