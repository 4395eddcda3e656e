"""Calibration on real render-and-detect: records, the cache key, the cache, the command line."""

from __future__ import annotations

import numpy as np
import pytest

from citysim.cli import main
from citysim.config.scenario import ControllerSpec, override, scenario_from_mapping
from citysim.fast.model import KINDS
from citysim.sim import calibration
from citysim.sim.calibration import (
    calibrate,
    calibration_key,
    general_model_path,
    model_path,
    record_run,
    sensor_model_for,
)
from citysim.sim.loop import run_controller
from tests.citysim.fast.synthetic import constant_model, tiny_scenario


@pytest.fixture(scope="module")
def scenario():
    return scenario_from_mapping(tiny_scenario())


@pytest.mark.slow
def test_a_short_full_fidelity_night_gives_candidate_and_frame_rows(scenario):
    rows, frames = record_run(scenario, calibration.calibration_nights(1)[0], 6.0)
    n = len(rows["hit"])
    assert n > 0 and all(len(v) == n for v in rows.values())
    assert len(frames["camera"]) >= 6 * 3  # every camera judged at least once a second
    assert set(np.unique(rows["camera"])) <= {0, 1, 2}
    assert set(np.unique(rows["kind"])) <= set(range(len(KINDS)))
    assert (rows["forward_m"] > 0).all() and (rows["forward_m"] <= 30.0).all()
    # a hit carries the class the detector said; a miss none
    assert ((rows["det_class"] >= 0) == rows["hit"]).all()
    assert ((frames["area_fraction"] >= 0) & (frames["area_fraction"] <= 1)).all()


@pytest.mark.slow
def test_a_quiet_night_sees_everyone_under_dim_lamps_where_a_busy_one_lights_them(scenario):
    from citysim.fast.model import LIT_LEVEL

    busy_night, quiet_night = calibration.calibration_nights(1)[:2]
    busy, _ = record_run(scenario, busy_night, 6.0)
    quiet, quiet_frames = record_run(scenario, quiet_night._replace(seed=busy_night.seed), 6.0)
    assert (busy["light"] >= LIT_LEVEL).any()  # the controller lit lamps for the people it saw
    assert len(quiet["hit"]) > 0 and len(quiet_frames["camera"]) > 0
    assert (quiet["light"] < LIT_LEVEL).all() and (quiet_frames["light"] < LIT_LEVEL).all()
    assert not (quiet["young"] & (quiet["frame"] > 15)).any()  # no lamp switched: no background rebuilt


@pytest.mark.slow
def test_a_region_night_records_its_threshold_baselines_own_largest_regions(scenario):
    from citysim.fast.model import LIT_LEVEL, threshold_conditions
    from citysim.fast.region_records import REGION_COLUMNS

    night = next(n for n in calibration.calibration_nights(1) if n.controller == "threshold_05")
    # at the scenario's own traffic (a walker every 6 s), its 20 s bring people close to a camera
    rows, frames = record_run(scenario, night, 20.0)
    assert rows is None and set(frames) == set(REGION_COLUMNS)
    n = len(frames["camera"])
    assert n >= 20 * 3 and all(len(v) == n for v in frames.values())  # every camera judged at least once a second
    assert ((frames["area_fraction"] >= 0) & (frames["area_fraction"] <= 1)).all()
    assert (frames["near_kind"] >= 0).any() and (frames["area_fraction"] > 0).any()  # people in view
    # threshold_05 lit a lamp for a region over 0.5 % of the frame: the frames after it show it lit
    assert (frames["area_fraction"] > 0.005).any() and (frames["light"] >= LIT_LEVEL).any()
    # every row has a condition the fit files it under
    assert all(threshold_conditions(int(k), float(d), bool(lit >= LIT_LEVEL), int(a), far)
               for k, d, lit, a, far in zip(frames["near_kind"], frames["near_forward_m"], frames["light"],
                                            frames["age_bin"], frames["far_change_s"], strict=True))  # fmt: skip


def test_calibration_nights_are_busy_quiet_then_each_baselines_region_nights_on_seeds_of_their_own():
    nights = calibration.calibration_nights(2)
    assert [(n.controller, n.lamps_held_dim) for n in nights] == [
        ("detector_confirmed", False), ("detector_confirmed", False), ("detector_confirmed", True),
        ("detector_confirmed", True), ("threshold_05", False), ("threshold_05", False),
        ("threshold_5", False), ("threshold_5", False)]  # fmt: skip
    assert [n.records_regions for n in nights] == [False] * 4 + [True] * 4
    # the detector's nights are busier than the scenario; the region nights are at its own traffic
    assert [n.traffic_factor for n in nights] == [calibration.TRAFFIC_FACTOR] * 4 + [1.0] * 4
    assert len({n.seed for n in nights[:4]}) == 4  # busy and quiet on seeds of their own
    assert {n.seed for n in nights[4:]}.isdisjoint({n.seed for n in nights[:4]})
    # the two baselines see the same traffic, each switching its own lamps
    assert [n.seed for n in nights[4:6]] == [n.seed for n in nights[6:]]


def test_the_cache_key_hashes_the_detector_model_the_detector_loads():
    # the key finds the model file without importing detector.general_model (scikit-learn)
    from detector.general_model import GENERAL_MODEL_PATH

    assert general_model_path() == GENERAL_MODEL_PATH


def test_the_cache_key_follows_cameras_and_environment_not_seed_or_rates(scenario):
    key = calibration_key(scenario, 60.0, 1)
    assert calibration_key(override(scenario, {"seed": 99}), 60.0, 1) == key
    assert calibration_key(override(scenario, {"traffic.classes.pedestrian.rate_per_hour": 5}), 60.0, 1) == key
    assert calibration_key(override(scenario, {"lamps.luminaire.hold_s": 5}), 60.0, 1) == key
    assert calibration_key(override(scenario, {"lamps.camera.tilt_deg": 20}), 60.0, 1) != key
    assert calibration_key(override(scenario, {"environment.insects_per_min": 20}), 60.0, 1) != key
    assert calibration_key(scenario, 120.0, 1) != key


def test_the_cache_key_follows_the_backward_cameras(scenario):
    # a second camera per pole sees other ground and other false alarms: its own model
    key = calibration_key(scenario, 60.0, 1)
    back = calibration_key(override(scenario, {"lamps.camera.back_heading_deg": 188}), 60.0, 1)
    assert back != key
    assert calibration_key(override(scenario, {"lamps.camera.back_heading_deg": 170}), 60.0, 1) not in (key, back)


def test_a_cached_model_is_loaded_not_recalibrated(scenario, tmp_path, monkeypatch):
    model = constant_model(0.3)
    model.save(model_path(scenario, tmp_path, calibration.DEFAULT_DURATION_S, calibration.DEFAULT_RUNS))
    monkeypatch.setattr(calibration, "calibrate", lambda *a, **k: pytest.fail("calibrated although cached"))
    assert sensor_model_for(scenario, tmp_path, progress=False) == model


@pytest.mark.slow
def test_calibrate_caches_a_model_whose_fast_runs_agree_with_full(scenario, tmp_path):
    model, path = calibrate(scenario, tmp_path, duration_s=20.0, runs=1, progress=False, workers=1)
    assert path.exists() and path.parent == tmp_path and model.frames > 0
    assert sensor_model_for(scenario, tmp_path, duration_s=20.0, runs=1, progress=False) == model
    night = override(scenario, {"duration_s": 30.0})
    spec = ControllerSpec(name="detector_confirmed")
    full = run_controller(night, spec)
    fast = run_controller(night, spec, fidelity="fast", sensor_model=model)
    print({k: (full[k], fast[k]) for k in ("savings_vs_always_on", "lit_on_entry_rate", "zone_entries",
                                            "lag_p95_s", "false_on_time_s")})  # fmt: skip
    # 30 s on three lamps hold about a dozen zone entries and a few lamp holds of 30 s, calibrated
    # on 20 s: one entry lit late moves lit_on_entry by ~8 points and one hold more or less moves
    # the savings by ~15 points, so this checks the model is of the right size, not the validation
    # tolerances (those are checked by citysim validate on the real scenarios, see README)
    assert fast["zone_entries"] == full["zone_entries"]  # the same traffic
    assert abs(fast["savings_vs_always_on"] - full["savings_vs_always_on"]) <= 0.20
    assert abs(fast["lit_on_entry_rate"] - full["lit_on_entry_rate"]) <= 0.25


def test_a_bad_fidelity_exits_2_naming_the_valid_values(capsys, tmp_path):
    with pytest.raises(SystemExit) as info:  # argparse refuses while reading the command line
        main(["run", "scenarios/suburban_night.yaml", "--out", str(tmp_path / "o"), "--fidelity", "quick"])
    err = capsys.readouterr().err
    assert info.value.code == 2
    assert "--fidelity" in err and "'full'" in err and "'fast'" in err
    assert not (tmp_path / "o").exists()


def test_validate_and_calibrate_refuse_bad_arguments_before_any_work(capsys):
    assert main(["validate", "scenarios/suburban_night.yaml", "--controllers", "detector,nope"]) == 2
    assert "controllers: unknown 'nope'" in capsys.readouterr().err
    with pytest.raises(SystemExit) as info:
        main(["calibrate", "scenarios/suburban_night.yaml", "--runs", "0"])
    assert info.value.code == 2 and "--runs" in capsys.readouterr().err
