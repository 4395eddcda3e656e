"""A replayed step's geometry cut from its chunk's one numpy pass is the step's own, bit for bit."""

from __future__ import annotations

import numpy as np

from citysim.config.scenario import scenario_from_mapping
from citysim.fast.geometry import CameraGeometry
from citysim.fast.steps import StepGeometries, step_of_agents
from citysim.sim import replay
from citysim.sim.night import build_night
from citysim.sim.replay import TrafficReplay, record_traffic
from tests.citysim.sim.test_replay import busy_street


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def test_chunk_geometry_is_each_steps_own_bit_for_bit(tmp_path, monkeypatch):
    monkeypatch.setattr(replay, "CHUNK_STEPS", 97)  # many chunks, none a whole number of seconds
    scenario = scenario_from_mapping(busy_street(30.0, lamps_x_m=(4.0, 30.0, 56.0)))
    record_traffic(scenario, tmp_path)
    night = build_night(scenario, replay=TrafficReplay(tmp_path))
    geometry = CameraGeometry(night.street)
    steps = StepGeometries(geometry)
    compared = []

    def compare(t_s, agents):
        rows = night.replay.rows_of(agents)
        assert rows is not None and night.replay.rows_of(list(agents)) is None  # only the step's own list
        cut, own = steps.of(agents, rows), step_of_agents(geometry, agents)
        matrices = ("forward_m", "bearing_rad", "seen", "wake", "beam_seen")
        assert all(same_bits(getattr(cut.cand, m), getattr(own.cand, m)) for m in matrices)
        assert same_bits(cut.cand.awake, own.cand.awake) and same_bits(cut.nearest_lamp, own.nearest_lamp)
        beams = own.cand.beam_seen  # a beam's geometry means something only where it is seen
        for m in ("beam_forward_m", "beam_bearing_rad"):
            assert same_bits(getattr(cut.cand, m)[beams], getattr(own.cand, m)[beams])
        assert all(same_bits(a, b) for a, b in zip(cut.cells, own.cells, strict=True))
        compared.append((len(agents), int(own.cand.seen.sum()), int(beams.sum())))

    night.start_physics(compare)
    night.run_until(scenario.duration_s)
    assert len(compared) == 30 * 30 - 1
    # steps with agents, candidates and beams of lit road users out of view were all compared
    assert max(c[0] for c in compared) >= 3 and sum(c[1] for c in compared) and sum(c[2] for c in compared)
