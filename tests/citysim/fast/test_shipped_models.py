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


def recalibrate_hint(scenario_file: Path) -> str:
    """What to do about a stale model of the scenario in ``scenario_file`` (a path under
    scenarios/): the calibrate command naming that file, relative to the repository."""
    return (f"calibrate it again: citysim calibrate {scenario_file.relative_to(SCENARIOS.parent).as_posix()} "
            "--cache scenarios/sensor_models, then git rm the old file")


def _scenario_file(path: Path) -> Path:
    """A shipped model's scenario file: scenarios/NAME.yaml, else the one scenarios/*/NAME.yaml (an
    imported street's, e.g. scenarios/osm/)."""
    name = path.stem.rpartition("-")[0]
    found = [SCENARIOS / f"{name}.yaml"] if (SCENARIOS / f"{name}.yaml").exists() else sorted(SCENARIOS.glob(f"*/{name}.yaml"))
    assert len(found) == 1, f"{path.name}: no single scenario file named {name}.yaml under {SCENARIOS}: {found}"
    return found[0]


def _scenario_of(path: Path):
    """(scenario file, key, scenario) of a shipped model."""
    scenario_file = _scenario_file(path)
    return scenario_file, path.stem.rpartition("-")[2], load_scenario(scenario_file)


def test_the_recalibrate_hint_names_the_real_scenario_file():
    # geisslerweg's model is shipped and its scenario lives under scenarios/osm/, not scenarios/
    model = next(p for p in SHIPPED if p.stem.startswith("geisslerweg-"))
    hint = recalibrate_hint(_scenario_file(model))
    assert "citysim calibrate scenarios/osm/geisslerweg.yaml " in hint
    assert (SCENARIOS.parent / hint.split("citysim calibrate ")[1].split()[0]).is_file()


def test_suburban_night_the_demo_scenario_ships_a_model():
    assert any(p.stem.startswith("suburban_night-") for p in SHIPPED)


@pytest.mark.parametrize("path", SHIPPED, ids=[p.stem for p in SHIPPED])
def test_a_shipped_model_has_its_scenarios_current_key_and_loads(path):
    scenario_file, _, scenario = _scenario_of(path)
    expected = model_path(scenario, SHIPPED_DIR, calibration.DEFAULT_DURATION_S, calibration.DEFAULT_RUNS)
    assert expected.name == path.name, f"{path.name} is stale (the key is now {expected.stem}): " + recalibrate_hint(
        scenario_file
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
