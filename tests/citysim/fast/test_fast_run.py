"""Fast mode runs: the sensor model drives the camera controllers, deterministically per seed."""

from __future__ import annotations

import numpy as np
import pytest

from citysim.config.scenario import ControllerSpec, scenario_from_mapping
from citysim.fast.model import BEAM, KINDS
from citysim.sim.loop import RunError, run_controller
from tests.citysim.fast.synthetic import constant_model, tiny_scenario


@pytest.fixture(scope="module")
def scenario():
    return scenario_from_mapping(tiny_scenario())


def fast(scenario, name: str, model, **spec) -> dict:
    return run_controller(scenario, ControllerSpec(name=name, **spec), fidelity="fast", sensor_model=model)


def triggers(summary: dict) -> int:
    return sum(t["triggers"] for t in summary["lamp_triggers"])


def test_same_seed_same_summary_and_another_seed_another(scenario):
    model = constant_model(0.6, fa_start_p=0.01)
    first = fast(scenario, "detector_located", model)
    again = fast(scenario, "detector_located", model)
    assert first == again
    other = fast(scenario.model_copy(update={"seed": scenario.seed + 1}), "detector_located", model)
    assert other != first


@pytest.mark.parametrize("name", ["detector", "detector_confirmed", "detector_network", "detector_located"])
def test_detector_controllers_light_only_when_the_model_detects(scenario, name):
    # detector_located keeps an end lamp whose approach no camera watches at full by design
    # (light_blind_ends): off here, so every trigger must come from the model
    spec = {"light_blind_ends": False} if name == "detector_located" else {}
    blind = fast(scenario, name, constant_model(0.0), **spec)
    sharp = fast(scenario, name, constant_model(1.0), **spec)
    assert triggers(blind) == 0 and blind["detection"]["tp"] == 0
    assert triggers(sharp) > 0
    # a perfect sensor leaves far fewer people walking into a dim zone than a blind one
    assert sharp["lit_on_entry_rate"] > blind["lit_on_entry_rate"]


def test_false_alarms_light_lamps_with_nobody_there(scenario):
    empty = scenario_from_mapping(tiny_scenario(traffic={"classes": {}}))
    quiet = fast(empty, "detector_confirmed", constant_model(1.0, fa_start_p=0.0))
    noisy = fast(empty, "detector_confirmed", constant_model(1.0, fa_start_p=0.05))
    assert triggers(quiet) == 0 and quiet["false_on_time_s"] == 0.0
    assert triggers(noisy) > 0 and noisy["false_on_time_s"] > 0.0


def test_each_controller_draws_the_false_alarms_of_the_decisions_it_counts(scenario):
    # frame decisions raise false alarms, track decisions none (insects make no plausible target
    # track), the frames of plausible tracks (detector_confirmed per track) fewer
    empty = scenario_from_mapping(tiny_scenario(traffic={"classes": {}}))
    model = constant_model(1.0, fa_start_p=0.05)
    model.track = {**model.track, "fa_start_p": [0.0, 0.0]}
    model.plausible = {**model.plausible, "fa_start_p": [0.0, 0.0]}
    assert fast(empty, "detector", model)["false_on_time_s"] > 0.0
    assert fast(empty, "detector_confirmed", model, tracking=False)["false_on_time_s"] > 0.0
    for name in ("detector_confirmed", "detector_network", "detector_tracked", "detector_located"):
        spec = {"light_blind_ends": False} if name == "detector_located" else {}
        assert fast(empty, name, model, **spec)["false_on_time_s"] == 0.0, name
    # a scenario may turn tracks on for the paper's detector: then it draws the track decisions
    assert fast(empty, "detector", model, tracking=True)["false_on_time_s"] == 0.0
    # detector_confirmed per track draws the plausible tables, not the track ones
    model.plausible = {**model.plausible, "fa_start_p": [0.05, 0.05]}
    assert fast(empty, "detector_confirmed", model)["false_on_time_s"] > 0.0
    assert fast(empty, "detector_tracked", model)["false_on_time_s"] == 0.0


def test_threshold_baselines_trigger_on_the_drawn_region_share(scenario):
    # every judged frame reports a region of 1 % of the frame: above 0.5 %, below 5 %
    model = constant_model(0.0, area_fraction=0.01)
    assert triggers(fast(scenario, "threshold_05", model)) > 0
    assert triggers(fast(scenario, "threshold_5", model)) == 0


def test_light_controllers_are_identical_in_both_fidelities(scenario):
    model = constant_model(0.5)
    for name in ("always_on", "pir", "oracle"):
        full = run_controller(scenario, ControllerSpec(name=name))
        assert fast(scenario, name, model) == full


def test_fast_mode_renders_nothing(scenario, monkeypatch):
    from citysim.sim import night

    def no_rendering(*args, **kwargs):
        raise AssertionError("fast mode rendered a frame")

    monkeypatch.setattr(night.Night, "renderer", no_rendering)
    summary = fast(scenario, "detector_confirmed", constant_model(0.7))
    assert triggers(summary) > 0


def test_fast_without_a_model_and_an_unknown_fidelity_are_errors(scenario):
    with pytest.raises(RunError, match="'fast' needs a calibrated sensor model"):
        run_controller(scenario, ControllerSpec(name="detector"), fidelity="fast")
    with pytest.raises(RunError, match="fidelity: unknown 'quick'; valid: full, fast"):
        run_controller(scenario, ControllerSpec(name="detector"), fidelity="quick")


def test_a_car_out_of_view_lights_the_zone_its_beam_reaches_only_when_beams_are_detected():
    # one car with headlights, scripted along the street: before the first camera sees the car,
    # its beam is in view; a model that detects beams (and nothing else) lights lamps for it
    car = {"traffic": {"classes": {}, "scripted": [{"cls": "vehicle", "t_s": 0.0, "direction": 1,
                                                    "speed_kmh": 29.0, "light_on": True}]}}  # fmt: skip
    scenario = scenario_from_mapping(tiny_scenario(**car))
    beams_only = constant_model(0.0)
    p = np.array(beams_only.p_hit)
    p[KINDS.index(BEAM)] = 1.0
    beams_only.p_hit = p.tolist()
    beams_only.track = {**beams_only.track, "p_hit": beams_only.p_hit}
    beams_only.plausible = {**beams_only.plausible, "p_hit": beams_only.p_hit}
    seen = fast(scenario, "detector_confirmed", beams_only)
    blind = fast(scenario, "detector_confirmed", constant_model(0.0))
    assert triggers(blind) == 0 and triggers(seen) > 0
    assert seen["detection"]["tp"] == 0  # a beam is nobody's truth box


def test_a_hit_stands_as_far_ahead_of_its_road_user_as_calibration_found():
    # a car seen only by the spot its headlights throw 15 m ahead: its detections stand there
    from citysim.fast.sense import fast_sensors
    from citysim.sim.night import build_night
    from citysim.world.agents import AgentState

    scenario = scenario_from_mapping(tiny_scenario())
    night = build_night(scenario)
    model = constant_model(1.0)
    model.hit_ahead_m = {"vehicle": [15.0]}
    sensors = fast_sensors(night, model)
    cam = sensors.geometry.cameras[0]
    x0 = float(cam.position_m[0])
    car = AgentState(7, "vehicle", x0 + 8.0, -1.6, 0.0, 10.0, 4.5, 1.8, 1.5, light_on=True)  # camera 0's candidate
    sensors.observe(0, [car], np.full(3, 0.2))
    (det,) = sensors.detectors(None, 0.5)[0]._candidates(0, False, sensors.lamps_lit())
    x, y, w, h = det.box_px
    ground = cam.pixel_to_ground(np.array([[x + w / 2 - 0.5, y + h - 0.5]]))[0]
    assert ground[0] == pytest.approx(x0 + 23.0, abs=0.5) and ground[1] == pytest.approx(-1.6, abs=0.5)


@pytest.mark.parametrize("keep", [0.0, 0.95])
def test_the_threshold_segmenter_draws_big_regions_in_episodes_as_long_as_calibration_saw(keep):
    # nothing in view; calibration saw a region over 5 % of the frame in 1 frame of 10, in episodes
    # of 1 / (1 - keep) frames: the draws keep that share, and the episodes' length
    from citysim.fast.sense import fast_sensors
    from citysim.fast.sensors import SensedFrame
    from citysim.sim.night import build_night

    model = constant_model(0.0)
    model.area_fraction = {"none/dim": [0.0] * 9 + [0.1]}
    model.area_persistence = keep
    sensors = fast_sensors(build_night(scenario_from_mapping(tiny_scenario())), model)
    segmenter = sensors.segmenters(None)[0]
    over = []
    for k in range(20000):
        sensors.observe(k, [], np.full(3, 0.2))
        regions = segmenter.apply(SensedFrame(sensors, 0), 1e-3)
        over.append(len(regions) > 0)
    over = np.array(over)
    starts = int((over[1:] & ~over[:-1]).sum()) + int(over[0])
    # share over: 0.1 (episodes of 20 frames: about 100 of them, so a standard error near 0.01)
    assert over.mean() == pytest.approx(0.1, abs=0.04)
    # mean episode: 1 / (1 - keep - (1 - keep) 0.1) frames, 1.1 for independent draws, 18.2 for keep 0.95
    assert over.sum() / starts == pytest.approx(1.0 / ((1.0 - keep) * 0.9), rel=0.25)
