"""Scenario schema: loading, defaults, derived values and field-path error messages."""

import copy
import shutil
from pathlib import Path

import pytest
import yaml

from citysim.config.motion import MAX_SPEED_MPS
from citysim.config.scenario import ScenarioError, load_scenario, override, scenario_from_mapping
from citysim.world.street import build_street

SCENARIOS = Path(__file__).resolve().parents[3] / "scenarios"
SUBURBAN = SCENARIOS / "suburban_night.yaml"


@pytest.fixture(scope="module")
def suburban():
    return load_scenario(SUBURBAN)


@pytest.fixture
def raw():
    return yaml.safe_load(SUBURBAN.read_text())


def _set(data: dict, dotted: str, value) -> dict:
    data = copy.deepcopy(data)
    keys = dotted.split(".")
    node = data
    for k in keys[:-1]:
        node = node[int(k)] if isinstance(node, list) else node.setdefault(k, {})
    if isinstance(node, list):
        node[int(keys[-1])] = value
    else:
        node[keys[-1]] = value
    return data


def _write(tmp_path: Path, data: dict) -> Path:
    """A scenario file in tmp_path, with the camera files it refers to beside it."""
    shutil.copytree(SCENARIOS / "cameras", tmp_path / "cameras", dirs_exist_ok=True)
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_suburban_camera_hangs_on_the_pole(suburban):
    cam = suburban.lamps.camera_model
    # intrinsics from the scene-A file, pose from the lamps section
    assert (cam.focal_mm, cam.width_px, cam.height_px) == (3.67, 424, 240)
    assert cam.height_m == suburban.lamps.pole_height_m == 5.5
    assert cam.tilt_deg == 15.0 and cam.yaw_deg == -8.0 and cam.k1 == -0.05


def test_lamp_chain_and_zones(suburban):
    xs = suburban.lamps.positions_x_m
    assert len(xs) >= 10 and all(b - a == 30 for a, b in zip(xs[:-1], xs[1:], strict=True))
    zones = suburban.lamps.zones(suburban.street.length_m)
    # the end lamps reach half a spacing beyond themselves; the street's ends are approaches
    assert zones[0] == (xs[0] - 15.0, xs[0] + 15.0) and zones[-1] == (xs[-1] - 15.0, xs[-1] + 15.0)
    assert zones[1] == (xs[1] - 15.0, xs[1] + 15.0)  # half-way to each neighbour
    assert all(a[1] == b[0] for a, b in zip(zones[:-1], zones[1:], strict=True))


def test_animal_rate_is_one_number(suburban, raw):
    assert (
        suburban.environment.animals_per_hour
        == suburban.traffic.classes.animal.rate_per_hour
        == 1.5
    )
    data = _set(raw, "traffic.classes.animal", {})
    data = _set(data, "environment.animals_per_hour", 4)
    s = scenario_from_mapping(data, base_dir=SCENARIOS)
    assert s.traffic.classes.animal.rate_per_hour == 4


def test_rate_follows_hourly_profile(suburban):
    ped = suburban.traffic.classes.pedestrian
    assert ped.rate_per_s(10.0) == pytest.approx(36 / 3600)
    assert ped.rate_per_s(3600 * 2 + 5) == pytest.approx(36 * 0.4 / 3600)
    assert ped.rate_per_s(3600 * 50) == pytest.approx(36 * 0.6 / 3600)  # last value holds
    assert ped.max_rate_per_s == pytest.approx(36 / 3600)


def test_speeds_are_converted_and_capped(suburban):
    veh = suburban.traffic.classes.vehicle.speed()
    assert veh.min_mps == pytest.approx(30 / 3.6) and veh.max_mps == pytest.approx(50 / 3.6)
    assert veh.max_mps <= MAX_SPEED_MPS
    # a class without a speed gets the registry default
    assert suburban.traffic.classes.animal.speed().max_mps > 0


def test_inline_camera_without_file(raw):
    data = _set(
        raw,
        "lamps.camera",
        {
            "tilt_deg": 20,
            "focal_mm": 3.6,
            "sensor_w_mm": 3.45,
            "sensor_h_mm": 1.94,
            "width_px": 424,
            "height_px": 240,
        },
    )
    s = scenario_from_mapping(data)
    assert s.lamps.camera_model.tilt_deg == 20 and s.lamps.camera_model.yaw_deg == 0.0


def test_explicit_lamp_positions(raw):
    lamps = dict(raw["lamps"])
    for k in ("count", "spacing_m", "first_x_m"):
        lamps.pop(k)
    lamps["x_m"] = [10, 50, 100]
    s = scenario_from_mapping({**raw, "lamps": lamps}, base_dir=SCENARIOS)
    assert s.lamps.positions_x_m == (10, 50, 100)
    assert s.lamps.zones(s.street.length_m)[1] == (30.0, 75.0)


def test_override_revalidates(suburban):
    s = override(suburban, {"lamps.camera.tilt_deg": 25, "street.lanes.0.width_m": 3.0})
    assert s.lamps.camera_model.tilt_deg == 25 and s.street.lanes[0].width_m == 3.0
    assert suburban.lamps.camera_model.tilt_deg == 15  # the original is untouched
    with pytest.raises(ScenarioError, match=r"lamps\.camera\.tilt_deg"):
        override(suburban, {"lamps.camera.tilt_deg": -29})


def test_scenery_is_seeded_and_off_the_walking_room(suburban):
    a, b = build_street(suburban), build_street(suburban)
    assert a.scenery == b.scenery
    rooms = [a.walking_room_m(sw) for sw in a.sidewalks]
    for obj in a.scenery:
        lo, hi = obj.y_m - obj.width_m / 2, obj.y_m + obj.width_m / 2
        assert all(hi <= r_lo or lo >= r_hi for r_lo, r_hi in rooms), obj
    other = build_street(override(suburban, {"street.scenery.seed": 99}))
    assert other.scenery != a.scenery


# (dotted path to set, value, dotted path the message must name, what it must say)
BAD_FIELDS = [
    ("lamps.camera.focal", 3.0, "lamps.camera.focal", "unknown field"),
    ("street.lanes.0.width", 3.0, "street.lanes.0.width", "unknown field"),
    ("traffic.classes.truck", {"rate_per_hour": 3}, "traffic.classes.truck", "unknown field"),
    # a field that nothing would read is refused, not silently ignored
    ("controllers.0", {"name": "detector", "use_neighbours": True}, "controllers.0.use_neighbours", "unknown field"),
    ("lamps.camera.tilt_deg", "steep", "lamps.camera.tilt_deg", "valid number"),
    ("duration_s", -5, "duration_s", "greater than 0"),
    (
        "traffic.classes.vehicle.speed_kmh.min",
        -5,
        "traffic.classes.vehicle.speed_kmh.min",
        "greater than 0",
    ),
    (
        "traffic.classes.pedestrian.speed_mps.min",
        -1.2,
        "traffic.classes.pedestrian.speed_mps.min",
        "greater than 0",
    ),
    (
        "traffic.classes.vehicle.speed_kmh.max",
        70,
        "traffic.classes.vehicle.speed_kmh.max",
        "less than or equal to 60",
    ),
    (
        "traffic.classes.cyclist.speed_mps.max",
        20,
        "traffic.classes.cyclist.speed_mps.max",
        "less than or equal to 16.6",
    ),
    (
        "traffic.classes.vehicle.speed_kmh",
        {"min": 50, "max": 40},
        "traffic.classes.vehicle.speed_kmh.max",
        ">= min",
    ),
    ("lamps.camera.tilt_deg", -28, "lamps.camera.tilt_deg", "cannot see the ground"),
    ("lamps.pole_height_m", -2, "lamps.pole_height_m", "greater than 0"),
    ("lamps.y_m", 4.0, "lamps.y_m", "walking room"),
    ("lamps.y_m", 1.0, "lamps.y_m", "inside lane"),
    ("lamps.count", 20, "lamps.count", "outside the street"),
    ("street.lanes.1.y_center_m", -1.0, "street.lanes.1.y_center_m", "overlaps"),
    ("street.lanes.0.direction", 2, "street.lanes.0.direction", "+1"),
    ("street.crossings_x_m", [5], "street.crossings_x_m.0", "within 10..380"),
    ("controllers", ["always_on", "always_on"], "controllers.1.label", "used twice"),
    ("controllers", [{"name": "detector", "k": 4, "n": 3}], "controllers.0.k", "<= n"),
    ("controllers", ["Always On"], "controllers.0.name", "pattern"),
    ("environment.animals_per_hour", 7, "environment.animals_per_hour", "conflicts"),
    ("environment.weather", "snow", "environment.weather", "'clear' or 'rain'"),
    (
        "traffic.classes.group.size",
        {"min": 1, "max": 4},
        "traffic.classes.group.size.min",
        "greater than or equal to 2",
    ),
]


@pytest.mark.parametrize(
    ("dotted", "value", "where", "says"),
    BAD_FIELDS,
    ids=[b[0] + "=" + str(b[1]) for b in BAD_FIELDS],
)
def test_bad_field_names_file_and_path(tmp_path, raw, dotted, value, where, says):
    path = _write(tmp_path, _set(raw, dotted, value))
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    msg = str(info.value)
    assert msg.startswith(f"{path}: ")
    assert f"{where}: " in msg
    assert says in msg


def test_camera_file_errors_name_the_file(tmp_path, raw):
    path = _write(tmp_path, raw)
    (tmp_path / "cameras" / "scene_a.yaml").write_text(
        "tilt_deg: -28\nfocal_mm: 3.67\nsensor_w_mm: 4.8\nsensor_h_mm: 3.6\nwidth_px: 424\nheight_px: 240\n"
    )
    data = _set(raw, "lamps.camera", {"file": "cameras/scene_a.yaml"})
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(
        ScenarioError,
        match=r"lamps\.camera\.tilt_deg: camera cannot see the ground.*from camera file .*scene_a\.yaml",
    ):
        load_scenario(path)
    data = _set(raw, "lamps.camera.file", "cameras/missing.yaml")
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(
        ScenarioError, match=r"lamps\.camera\.file: camera file .*missing\.yaml.* not found"
    ):
        load_scenario(path)


def test_missing_field_and_bad_files(tmp_path, raw):
    data = copy.deepcopy(raw)
    del data["seed"]
    with pytest.raises(ScenarioError, match=r"seed: Field required"):
        load_scenario(_write(tmp_path, data))
    with pytest.raises(ScenarioError, match=r"nope\.yaml: scenario file not found"):
        load_scenario(tmp_path / "nope.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: [unclosed\n")
    with pytest.raises(ScenarioError, match=r"bad\.yaml: not valid YAML"):
        load_scenario(bad)
    bad.write_text("- a\n- b\n")
    with pytest.raises(ScenarioError, match=r"bad\.yaml: a scenario is a YAML mapping"):
        load_scenario(bad)


@pytest.mark.parametrize(
    ("rename", "says"),
    [
        (("lamps.luminaire", "dim_level", "dim_levle"), "lamps.luminaire.dim_levle: unknown field; did you mean dim_level?"),
        (("lamps.camera", "tilt_deg", "tilt_dg"), "lamps.camera.tilt_dg: unknown field; did you mean tilt_deg?"),
        (("traffic.classes.pedestrian", "speed_mps", "sped_mps"),
         "traffic.classes.pedestrian.sped_mps: unknown field; did you mean speed_mps"),
        (("environment", "wind_mps", "wnd"), "environment.wnd: unknown field; valid: time_of_day, weather, wind_mps"),
    ],
    ids=["dim_levle", "tilt_dg", "sped_mps", "wnd"],
)
def test_unknown_field_suggests_the_nearest_valid_name(tmp_path, raw, rename, says):
    section, good, typo = rename
    data = copy.deepcopy(raw)
    node = data
    for key in section.split("."):
        node = node[key]
    node[typo] = node.pop(good, 1.0)
    with pytest.raises(ScenarioError) as info:
        load_scenario(_write(tmp_path, data))
    assert says in str(info.value)


def test_unknown_field_in_a_list_item_suggests_too(tmp_path, raw):
    data = copy.deepcopy(raw)
    data["traffic"]["scripted"][0]["spede_kmh"] = data["traffic"]["scripted"][0].pop("speed_kmh")
    with pytest.raises(ScenarioError, match=r"traffic\.scripted\.0\.spede_kmh: unknown field; did you mean speed_kmh\?"):
        load_scenario(_write(tmp_path, data))
