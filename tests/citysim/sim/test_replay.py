"""Traffic simulated once and replayed: the same agents bit for bit, the same run folder byte for byte."""

import json

import pytest

from citysim.config.scenario import scenario_from_mapping
from citysim.sim import replay
from citysim.sim.compare import run_comparison
from citysim.sim.night import build_night
from citysim.sim.replay import TrafficError, TrafficReplay, record_traffic
from tests.citysim.sim.test_loop import tiny_scenario


def busy_street(duration_s: float, lamps_x_m=(4.0,)) -> dict:
    """Every kind of road user, often, so groups (members), animals (pauses), crossings and
    overtaking all happen within a few tens of seconds."""
    lamps = {**tiny_scenario()["lamps"], "x_m": list(lamps_x_m)}
    classes = {
        "pedestrian": {"rate_per_hour": 600, "crossing_fraction": 0.5},
        "group": {"rate_per_hour": 200},
        "cyclist": {"rate_per_hour": 200},
        "vehicle": {"rate_per_hour": 300},
        "animal": {"rate_per_hour": 300},
        "e_scooter": {"rate_per_hour": 100},
    }
    data = tiny_scenario(duration_s=duration_s, lamps=lamps, traffic={"classes": classes})
    data["street"]["crossings_x_m"] = [30.0]
    return data


def stepped(scenario) -> list:
    """(t_s, agents, spawned) after every physics step of a world stepped in this process."""
    night = build_night(scenario)
    out = []
    night.start_physics(lambda t_s, agents: out.append((t_s, agents, night.spawned_count)))
    t = 0.0
    while t < scenario.duration_s:  # whole seconds, as the run loop's clock
        t = min(scenario.duration_s, t + 1.0)
        night.run_until(t)
    return out


def test_replayed_traffic_is_the_stepped_world_bit_for_bit(tmp_path, monkeypatch):
    monkeypatch.setattr(replay, "CHUNK_STEPS", 97)  # many chunks, none a whole number of seconds
    scenario = scenario_from_mapping(busy_street(45.0))
    steps = record_traffic(scenario, tmp_path)
    live = stepped(scenario)
    night = build_night(scenario, replay=TrafficReplay(tmp_path))
    replayed = []
    night.start_physics(lambda t_s, agents: replayed.append((t_s, agents, night.spawned_count)))
    night.run_until(scenario.duration_s)

    assert steps == len(live) == len(replayed) == 45 * 30 - 1  # steps at k/30 s before the end
    kinds = {a.cls for _, agents, _ in live for a in agents}
    assert {"pedestrian", "group", "vehicle", "animal"} <= kinds
    assert any(a.members for _, agents, _ in live for a in agents)
    assert live[-1][2] >= 10
    # AgentState is a frozen dataclass: == compares every float exactly, members included
    for (t_live, a_live, n_live), (t_rep, a_rep, n_rep) in zip(live, replayed, strict=True):
        assert t_live == t_rep and n_live == n_rep
        assert a_live == list(a_rep)
        assert [vars(a) for a in a_live] == [vars(a) for a in a_rep]  # the same fields, none more


def test_a_reader_stops_on_a_failed_or_too_short_recording(tmp_path):
    scenario = scenario_from_mapping(busy_street(2.0))
    record_traffic(scenario, tmp_path / "short")
    reader = TrafficReplay(tmp_path / "short", wait_s=5.0)
    for _ in range(2 * 30 - 1):
        reader.next_step()
    with pytest.raises(TrafficError, match="ends before chunk 1"):
        reader.next_step()
    (tmp_path / "broken").mkdir()
    (tmp_path / "broken" / "failed.txt").write_text("traffic recording failed: boom\n")
    with pytest.raises(TrafficError, match="boom"):
        TrafficReplay(tmp_path / "broken", wait_s=5.0).next_step()


def read_run(folder) -> tuple[dict, bytes, bytes]:
    return (json.loads((folder / "summary.json").read_text()), (folder / "lamps.csv").read_bytes(),
            (folder / "objects.csv").read_bytes())  # fmt: skip


@pytest.mark.slow
def test_a_comparison_replaying_traffic_writes_the_run_folder_of_one_world_per_controller(tmp_path):
    # 31 s at 60 Hz: two chunks (1,860 steps), streamed from the recorder process to the
    # controllers' processes; the busy street's physics is most of this test's time
    data = busy_street(31.0, lamps_x_m=(4.0, 34.0))
    # a quarter of the pixels: the test is about the traffic the controllers see, not the image
    data["lamps"]["camera"] = {**data["lamps"]["camera"], "width_px": 160, "height_px": 120}
    scenario = scenario_from_mapping({**data, "physics_hz": 60.0})
    names = ["detector_confirmed"]  # always_on and the oracle join it: three controllers, three processes
    run_comparison(scenario, names, out_dir=tmp_path / "worlds", replay_traffic=False)
    run_comparison(scenario, names, out_dir=tmp_path / "replayed", workers=2)
    summary_worlds, lamps_worlds, objects_worlds = read_run(tmp_path / "worlds")
    summary_replayed, lamps_replayed, objects_replayed = read_run(tmp_path / "replayed")
    assert summary_replayed == summary_worlds  # every value of every controller
    assert lamps_replayed == lamps_worlds and objects_replayed == objects_worlds  # every row
    assert objects_worlds.count(b"\n") > 10
    assert summary_worlds["controllers"]["detector_confirmed"]["agents_spawned"] >= 10
    assert not (tmp_path / "replayed" / ".traffic").exists()
