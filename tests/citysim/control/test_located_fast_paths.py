"""detector_located's fast paths give what the code they replaced gave, bit for bit."""

from __future__ import annotations

import numpy as np

from citysim.control import located


def test_the_line_slope_of_lists_is_polyfits_of_the_positions_array():
    # LocatedTrack.observe passes lists (times from the first, positions); it used to pass
    # np.array(recent).T's columns, the times less the first
    rng = np.random.default_rng(11)
    for n in list(range(3, 30)) * 30:
        recent = [(t_s, x_m) for t_s, x_m in zip((100.0 * rng.random() + np.cumsum(rng.uniform(0.03, 0.2, n))).tolist(),
                                                 (rng.uniform(-50, 400) + rng.normal(0, 8) * np.arange(n) / 15
                                                  + rng.normal(0, 0.3, n)).tolist(), strict=True)]  # fmt: skip
        if n % 5 == 0:
            recent[1] = (recent[1][0], -0.0)  # polyfit's + 0.0 makes it 0.0
        ts, xs = np.array(recent).T
        t0_s = recent[0][0]
        got = located.line_slope([t - t0_s for t, _ in recent], [x for _, x in recent])
        assert got == float(np.polyfit(ts - ts[0], xs, 1)[0])


def test_the_zones_found_by_bisection_are_those_the_scan_finds():
    from pathlib import Path

    from citysim.config.scenario import ControllerSpec, load_scenario
    from citysim.sim.loop import build_controller
    from citysim.sim.night import build_night

    scenario = load_scenario(Path(__file__).resolve().parents[3] / "scenarios" / "suburban_night.yaml")
    controller = build_controller(build_night(scenario), ControllerSpec(name="detector_located"))
    assert controller.zones_in_order
    bounds = sorted({b for pair in controller.zone_bounds_m for b in pair})
    rng = np.random.default_rng(3)
    xs = [*bounds, *(b + d for b in bounds for d in (-3.0, 3.0, -1e-9, 1e-9)), *rng.uniform(-50, 450, 500).tolist(),
          float("nan"), float("inf"), -float("inf")]  # fmt: skip
    speeds = [None, 0.0, 0.2, -0.2, 1.4, -1.4, 13.9, -13.9, 40.0, float("nan")]
    for x_m in xs:
        for vx_mps in speeds:
            for cls in ("pedestrian", "vehicle"):
                controller.zones_in_order = True
                fast = controller.zones_for(x_m, vx_mps, cls)
                controller.zones_in_order = False
                assert fast == controller.zones_for(x_m, vx_mps, cls)
