"""The real-street schema: centreline, side entries and surveyed poles, and their errors."""

import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from citysim.config.base import ScenarioError
from citysim.config.scenario import load_scenario, scenario_from_mapping

ROOT = Path(__file__).resolve().parents[3]
SUBURBAN = ROOT / "scenarios" / "suburban_night.yaml"


def curved(**street) -> dict:
    """suburban_night on a 90-degree bend (200 m east, 190 m north), with ``street`` fields set."""
    data = yaml.safe_load(SUBURBAN.read_text())
    data["street"].pop("length_m")
    data["street"]["centreline_m"] = [[0, 0], [200, 0], [200, 190]]
    data["street"].update(street)
    return data


def load(data: dict):
    return scenario_from_mapping(data, source="test.yaml", base_dir=SUBURBAN.parent)


def test_the_length_is_the_centrelines():
    scenario = load(curved())
    assert scenario.street.length_m == pytest.approx(390.0)
    assert scenario.street.centreline_points_m == ((0.0, 0.0), (200.0, 0.0), (200.0, 190.0))
    assert load(curved(length_m=390.4)).street.length_m == 390.4  # within 0.5 m
    with pytest.raises(ScenarioError, match=r"street\.length_m: .*centreline's length 390\.00 m"):
        load(curved(length_m=392.0))


def test_a_straight_street_is_the_centreline_along_x():
    scenario = load_scenario(SUBURBAN)
    assert scenario.street.centreline_m is None
    assert scenario.street.centreline_points_m == ((0.0, 0.0), (390.0, 0.0))


@pytest.mark.parametrize(
    ("points", "message"),
    [
        ([[0, 0], [200, 0], [200.3, 0]], r"centreline_m\.2: point 2 is 0\.3 m from point 1"),
        ([[0, 0], [200, 0], [200, 100], [100, -200]], r"centreline_m\.2: turns 161\.6 deg at point 2"),
        ([[0, 0], [200, 0], [200, 100], [100, 100], [100, -50]], r"centreline_m\.3: segment 3 .* crosses segment 0"),
        ([[0, 0]], "at least 2 points"),
    ],
)
def test_a_bad_centreline_is_one_clear_error(points, message):
    data = curved()
    data["street"]["centreline_m"] = points
    with pytest.raises(ScenarioError, match=message):
        load(data)


def test_side_entries_shares_and_their_errors():
    entries = [{"s_m": 120, "side": "left", "share": {"pedestrian": 0.5, "car": 0.1}},
               {"s_m": 240, "side": "right", "kind": "driveway", "share": {"pedestrian": 0.4}}]  # fmt: skip
    scenario = load(curved(side_entries=entries))
    first, second = scenario.street.side_entries
    assert first.share == {"pedestrian": 0.5, "vehicle": 0.1}  # 'car' is the vehicle kind
    assert (first.side_sign, second.side_sign, second.kind) == (1.0, -1.0, "driveway")
    too_much = [entries[0], {**entries[1], "share": {"pedestrian": 0.45}}]
    with pytest.raises(ScenarioError, match=r"street\.side_entries: the shares of 'pedestrian' sum to 0\.95"):
        load(curved(side_entries=too_much))
    with pytest.raises(ScenarioError, match=r"did you mean 'pedestrian'"):
        load(curved(side_entries=[{"s_m": 10, "side": "left", "share": {"pedestrain": 0.1}}]))
    with pytest.raises(ScenarioError, match=r"side_entries\.0\.s_m: s_m=400 m lies beyond the street end"):
        load(curved(side_entries=[{"s_m": 400, "side": "left"}]))
    with pytest.raises(ScenarioError, match=r"side_entries\.0\.side"):
        load(curved(side_entries=[{"s_m": 10, "side": "up"}]))


def poles_scenario(poles: list[dict]) -> dict:
    data = curved()
    for key in ("count", "spacing_m", "first_x_m", "y_m"):
        data["lamps"].pop(key)
    data["lamps"]["poles"] = poles
    return data


def test_surveyed_poles_give_positions_zones_and_per_lamp_fields():
    poles = [{"s_m": 40, "d_m": 6.2}, {"s_m": 70, "d_m": -7.0, "height_m": 6.5, "rated_power_w": 40, "heading_deg": 95}]
    lamps = load(poles_scenario(poles)).lamps
    assert lamps.positions_x_m == (40.0, 70.0)
    assert lamps.zones(390.0) == ((25.0, 55.0), (55.0, 85.0))
    assert lamps.pole_fields(0) == (6.2, 5.5, 60.0, None)  # the chain's defaults
    assert lamps.pole_fields(1) == (-7.0, 6.5, 40.0, 95.0)


def test_bad_poles_are_one_clear_error():
    with pytest.raises(ScenarioError, match=r"lamps\.poles\.1\.s_m: poles must be in order of s, >= 1 m apart"):
        load(poles_scenario([{"s_m": 40, "d_m": 6.2}, {"s_m": 40.5, "d_m": 6.2}]))
    with pytest.raises(ScenarioError, match=r"lamps\.poles\.0\.s_m: lamp 0 at x=500 m lies outside the street"):
        load(poles_scenario([{"s_m": 500, "d_m": 6.2}]))
    data = poles_scenario([{"s_m": 40, "d_m": 6.2}])
    data["lamps"]["count"] = 3
    with pytest.raises(ScenarioError, match=r"lamps\.poles: give either poles"):
        load(data)
    data = yaml.safe_load(SUBURBAN.read_text())
    data["lamps"].pop("y_m")
    with pytest.raises(ScenarioError, match=r"lamps\.y_m: the poles' offset y_m is required"):
        load(data)


def test_the_cli_exits_2_on_a_bad_centreline_and_writes_nothing(tmp_path):
    data = curved()
    data["street"]["centreline_m"] = [[0, 0], [200, 0], [200, 100], [100, -200]]
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data).replace("cameras/scene_a.yaml", str(SUBURBAN.parent / "cameras" / "scene_a.yaml")))
    out = tmp_path / "run"
    proc = subprocess.run([sys.executable, "-m", "citysim", "run", str(path), "--out", str(out), "--duration", "5"],
                          capture_output=True, text=True, cwd=ROOT)  # fmt: skip
    assert proc.returncode == 2, proc.stderr
    assert "street.centreline_m.2: turns 161.6 deg at point 2" in proc.stderr
    assert not out.exists()
