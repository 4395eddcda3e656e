"""Fast mode's batched and trimmed paths leave the state their one-at-a-time forms left, bit for bit."""

from __future__ import annotations

import numpy as np

from citysim.fast.drawn import SensedTracker


def test_a_frames_updates_at_once_leave_the_tracker_as_one_by_one():
    rng = np.random.default_rng(7)
    one, batch = SensedTracker(), SensedTracker()
    for frame_k in range(3000):
        # many tracks, so the history passes 256 and is pruned mid-frame; some come back after gaps
        ids = sorted({int(t) for t in rng.integers(0, 400, int(rng.integers(0, 12)))})
        hits = [bool(rng.random() < 0.4) for _ in ids]
        for track_id, hit in zip(ids, hits, strict=True):
            one.update(frame_k, track_id, hit)
        batch.update_all(frame_k, ids, hits)
        assert batch.history == one.history
        assert list(batch.history) == list(one.history)  # the same order, so the same pruning later


def test_a_replayed_steps_agents_read_from_its_rows_are_its_snapshots(tmp_path, monkeypatch):
    from citysim.config.scenario import scenario_from_mapping
    from citysim.fast.step_agents import RowAgent, StepAgents
    from citysim.sim import replay
    from citysim.sim.night import build_night
    from citysim.sim.replay import TrafficReplay, record_traffic
    from tests.citysim.sim.test_replay import busy_street

    monkeypatch.setattr(replay, "CHUNK_STEPS", 97)  # many chunks
    scenario = scenario_from_mapping(busy_street(20.0, lamps_x_m=(4.0, 30.0, 56.0)))
    record_traffic(scenario, tmp_path)
    night = build_night(scenario, replay=TrafficReplay(tmp_path))
    compared = []

    def compare(t_s, agents):
        read = StepAgents(agents)
        for j in reversed(range(len(agents))):  # any order; each made once
            got, own = read[j], agents[j]
            assert isinstance(got, RowAgent) and read[j] is got
            for name in RowAgent.__slots__:
                value, expected = getattr(got, name), getattr(own, name)
                assert type(value) is type(expected) and value == expected, name
            compared.append(own.cls)
        live = StepAgents(list(agents))  # a live step's list: its own snapshots
        assert all(live[j] is live.agents[j] for j in range(len(agents)))

    night.start_physics(compare)
    night.run_until(scenario.duration_s)
    assert len(set(compared)) >= 2 and len(compared) > 100
