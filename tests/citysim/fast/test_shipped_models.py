"""The sensor models shipped in scenarios/sensor_models/: found without calibrating, never stale.

A shipped model is data (a calibration's fit on one machine; scikit-learn and numpy may give other
last digits elsewhere), so nothing here refits it: the tests check that its name's key is the key
of its scenario as the code computes it now (a change to the cameras, street, environment, traffic
kinds, detector model file or MODEL_VERSION makes that key differ, and then this test fails until
the model is calibrated again), that it loads, and that a fresh clone's empty cache finds it.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from citysim.config.scenario import load_scenario
from citysim.fast.model import SensorModel
from citysim.sim import calibration
from citysim.sim.calibration import SHIPPED_DIR, model_path, sensor_model_for

SCENARIOS = Path(__file__).resolve().parents[3] / "scenarios"
SHIPPED = sorted(SHIPPED_DIR.glob("*.json"))
RECALIBRATE = ("calibrate it again: citysim calibrate scenarios/{name}.yaml --cache scenarios/sensor_models, "
               "then git rm the old file")  # fmt: skip


def _scenario_of(path: Path):
    """(name, key, scenario) of a shipped model: its scenario file is scenarios/NAME.yaml, else the
    one scenarios/*/NAME.yaml (an imported street's, e.g. scenarios/osm/)."""
    name, _, key = path.stem.rpartition("-")
    found = [SCENARIOS / f"{name}.yaml"] if (SCENARIOS / f"{name}.yaml").exists() else sorted(SCENARIOS.glob(f"*/{name}.yaml"))
    assert len(found) == 1, f"{path.name}: no single scenario file named {name}.yaml under {SCENARIOS}: {found}"
    return name, key, load_scenario(found[0])


def test_suburban_night_the_demo_scenario_ships_a_model():
    assert any(p.stem.startswith("suburban_night-") for p in SHIPPED)


@pytest.mark.parametrize("path", SHIPPED, ids=[p.stem for p in SHIPPED])
def test_a_shipped_model_has_its_scenarios_current_key_and_loads(path):
    name, key, scenario = _scenario_of(path)
    expected = model_path(scenario, SHIPPED_DIR, calibration.DEFAULT_DURATION_S, calibration.DEFAULT_RUNS)
    assert expected.name == path.name, f"{path.name} is stale (the key is now {expected.stem}): " + RECALIBRATE.format(
        name=name
    )
    model = SensorModel.load(path)
    assert model.key == path.stem
    # a model fitted on real calibration nights, not a placeholder
    assert model.frames > 1000 and model.candidate_frames > 100
    assert path.stat().st_size < 2_000_000, "a shipped model should stay small"


@pytest.mark.parametrize("path", SHIPPED, ids=[p.stem for p in SHIPPED])
def test_an_empty_cache_finds_the_shipped_model_without_calibrating(path, tmp_path, monkeypatch):
    _, _, scenario = _scenario_of(path)
    monkeypatch.setattr(calibration, "calibrate", lambda *a, **k: pytest.fail("calibrated although shipped"))
    assert sensor_model_for(scenario, tmp_path / "empty-cache", progress=False) == SensorModel.load(path)
