"""Camera controllers run in step share the frames they would render alike, and nothing else changes."""

import numpy as np
import pytest

from citysim.config.scenario import ControllerSpec, scenario_from_mapping
from citysim.sim.compare import run_comparison, run_groups
from citysim.sim.frames import CameraFrames, SharedFrames
from citysim.sim.night import build_night
from citysim.sim.replay import record_traffic
from citysim.sim.together import run_together
from tests.citysim.sim.test_replay import busy_street, read_run

CAMERA_CONTROLLERS = ["detector", "detector_confirmed", "threshold_5"]


def small_busy_street(duration_s: float):
    data = busy_street(duration_s, lamps_x_m=(4.0, 34.0))
    # a quarter of the pixels: the test is about which frames are shared, not the image
    data["lamps"]["camera"] = {**data["lamps"]["camera"], "width_px": 160, "height_px": 120}
    return scenario_from_mapping(data)


def test_controllers_in_step_share_frames_where_their_lamps_stand_alike_and_only_there(tmp_path):
    scenario = small_busy_street(12.0)
    record_traffic(scenario, tmp_path / "traffic")
    specs = [ControllerSpec(name=name) for name in CAMERA_CONTROLLERS]
    _, frames = run_together(scenario, specs, tmp_path / "parts", traffic=tmp_path / "traffic")
    asked = frames.rendered + frames.reused
    # shared where alike (every lamp dim before anyone comes), rendered apart where the
    # controllers lit differently (the threshold lights nothing here, the detectors do)
    assert frames.reused > 0
    assert frames.rendered > asked / len(specs)


@pytest.mark.slow
def test_sharing_frames_leaves_every_summary_and_row_as_each_controller_alone(tmp_path):
    scenario = small_busy_street(20.0)
    run_comparison(scenario, CAMERA_CONTROLLERS, out_dir=tmp_path / "alone")  # the default
    run_comparison(scenario, CAMERA_CONTROLLERS, out_dir=tmp_path / "one_group", share_frames=True)
    run_comparison(scenario, CAMERA_CONTROLLERS, out_dir=tmp_path / "two_groups", workers=2, share_frames=True)
    summary, lamps, objects = read_run(tmp_path / "alone")
    controllers = summary["controllers"]
    assert controllers["detector"]["switches"] > 0  # lamps changed level, and not alike for all:
    assert controllers["detector"]["on_time_s"] != controllers["detector_confirmed"]["on_time_s"]
    assert objects.count(b"\n") > 10
    for shared in ("one_group", "two_groups"):
        assert read_run(tmp_path / shared) == (summary, lamps, objects)  # every value, every row


def test_a_shared_frame_is_the_one_each_controller_would_render_and_read_only():
    scenario = small_busy_street(2.0)
    levels = [0.2, 1.0]
    shared = SharedFrames()
    # two controllers' frames: each its own renderers, one cache
    mine = CameraFrames(build_night(scenario).renderers(), shared)
    yours = CameraFrames(build_night(scenario).renderers(), shared)
    first = mine.frame(0, 7, 7 / 15, [], levels)
    again = yours.frame(0, 7, 7 / 15, [], [0.2, 1.0])
    other = yours.frame(0, 7, 7 / 15, [], [0.2, 0.2])
    assert again is first and other is not first
    assert (shared.rendered, shared.reused) == (2, 1)
    own = build_night(scenario).renderer(0).render(7 / 15, [], levels, frame_index=7)
    assert np.array_equal(first.image, own.image) and first.truth == own.truth
    with pytest.raises(ValueError, match="read-only"):
        first.image[0, 0] = 0
    shared.next_second()
    assert yours.frame(0, 7, 7 / 15, [], levels) is not first
    alone = CameraFrames(build_night(scenario).renderers())  # no cache: every frame rendered
    assert alone.frame(0, 7, 7 / 15, [], levels) is not alone.frame(0, 7, 7 / 15, [], levels)


def test_the_camera_controllers_are_dealt_into_one_group_per_worker_at_full_fidelity_only():
    specs = [ControllerSpec(name=n) for n in ("always_on", "detector", "pir", "threshold_5", "detector_located")]
    names = lambda groups: [[s.name for s in g] for g in groups]  # noqa: E731
    assert names(run_groups(specs, "full", 2, True)) == [
        ["detector", "detector_located"], ["threshold_5"], ["always_on"], ["pir"]]
    assert names(run_groups(specs, "full", 1, True)) == [
        ["detector", "threshold_5", "detector_located"], ["always_on"], ["pir"]]
    alone = [["detector"], ["threshold_5"], ["detector_located"], ["always_on"], ["pir"]]
    assert names(run_groups(specs, "fast", 2, True)) == alone
    assert names(run_groups(specs, "full", 2, False)) == alone
