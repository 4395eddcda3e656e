"""A replayed step's geometry cut from its chunk's one numpy pass is the step's own, bit for bit."""

from __future__ import annotations

import numpy as np

from citysim.config.scenario import scenario_from_mapping
from citysim.fast.geometry import CameraGeometry
from citysim.fast.model import table_shape
from citysim.fast.pairs import CandidatePairs
from citysim.fast.steps import StepGeometries, StepGeometry, step_of_agents
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
    steps = StepGeometries(geometry, table_shape())
    compared = []
    rng = np.random.default_rng(1)

    def compare(t_s, agents):
        rows = night.replay.rows_of(agents)
        assert rows is not None and night.replay.rows_of(list(agents)) is None  # only the step's own list
        cut, own = steps.of(agents, rows), step_of_agents(geometry, agents)
        matrices = ("forward_m", "bearing_rad", "seen", "wake", "beam_seen")
        assert all(same_bits(getattr(cut.cand, m), getattr(own.cand, m)) for m in matrices)
        assert same_bits(cut.cand.awake, own.cand.awake) and same_bits(cut.nearest_lamp, own.nearest_lamp)
        assert cut.awake() == own.awake() == own.cand.awake.tolist()
        beams = own.cand.beam_seen  # a beam's geometry means something only where it is seen
        for m in ("beam_forward_m", "beam_bearing_rad"):
            assert same_bits(getattr(cut.cand, m)[beams], getattr(own.cand, m)[beams])
        assert all(same_bits(a, b) for a, b in zip(cut.cells, own.cells, strict=True))
        cut_pairs, own_pairs = cut.pairs(table_shape()), own.pairs(table_shape())
        assert all(getattr(cut_pairs, f) == getattr(own_pairs, f) for f in ("agents", "forward_m", "kind", "lamp",
                                                                             "cell", "starts", "beams"))  # fmt: skip
        assert own_pairs.beams == int(own.cand.beam_seen.sum())
        pairs_read_as_numpy_reads_them(own, rng)
        compared.append((len(agents), int(own.cand.seen.sum()), int(beams.sum())))

    night.start_physics(compare)
    night.run_until(scenario.duration_s)
    assert len(compared) == 30 * 30 - 1
    # steps with agents, candidates and beams of lit road users out of view were all compared
    assert max(c[0] for c in compared) >= 3 and sum(c[1] for c in compared) and sum(c[2] for c in compared)


def pairs_read_as_numpy_reads_them(step: StepGeometry, rng: np.random.Generator) -> None:
    """A step's pair lists (``StepPairs``) hold, camera by camera, what numpy's per-camera reads
    gave: the candidates (``CandidatePairs``), their forward distances, kinds and p_hit (of a table
    of distinct values, at random lamps lit, both background ages)."""
    table = rng.permutation(np.prod(table_shape())).reshape(table_shape()) / 1e5
    n_lamps, n_cameras = 3, step.cand.seen.shape[1]
    lamps_lit = rng.integers(0, 2, n_lamps).tolist()
    pairs, reference = step.pairs(table_shape()), CandidatePairs(step.cand.seen, n_cameras)
    kind, distance, bearing, speed = step.cells
    lit = np.array(lamps_lit)[step.nearest_lamp]
    for i in range(n_cameras):
        first, end = pairs.bounds(i)
        idx = reference.of(i)
        assert pairs.agents[first:end] == idx.tolist() and pairs.count(i) == len(idx)
        assert pairs.forward_m[first:end] == step.cand.forward_m[idx, i].tolist()
        assert pairs.kind[first:end] == kind[idx].tolist()
        for young in (False, True):
            expected = table[kind[idx], distance[idx, i], bearing[idx, i], lit[idx], int(young), speed[idx]]
            assert pairs.p_hit(i, table.ravel().tolist(), lamps_lit, young) == expected.tolist()
