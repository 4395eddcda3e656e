"""simpy process of fast mode: the lamp cameras judged by the sensor model instead of filmed.

``sense`` takes the place of ``citysim.sim.cameras.film``: the same frame times (k / fps), the
same choice of which cameras are judged (every camera every ``idle_frame_stride``-th frame; in
between, those with an agent in their wider view, motion in their last judged frame, or a lamp
in view ramping), and the same calls (``controller.on_frame``, then every collector's
``on_frame``), but nothing is rendered: the controller's detectors are ``FastSensors``' stand-ins
and the "frame" is a ``SensedFrame``.
"""

from __future__ import annotations

from collections.abc import Sequence

from citysim.control.lamps import Lamp
from citysim.fast.sensors import FastSensors, SensedFrame
from citysim.metrics.collector import Collector


def sense(night, sensors: FastSensors, controller, lamps: Sequence[Lamp], collectors: Sequence[Collector]):
    """simpy process: every camera frame at the cameras' frame rate, judged by the sensor model."""
    env = night.env
    fps = night.street.lamps[0].camera.fps
    stride = night.scenario.simulation.idle_frame_stride
    lamp_states = controller.ctx.lamp_states
    n_lamps = len(lamps)
    camera_lamps = night.street.camera_lamps  # per camera (two per pole with backward cameras), its pole
    n = len(camera_lamps)
    # each camera watches its own pole's lamp and the neighbours' (their light changes its scene)
    watch = [list(range(max(0, j - 1), min(n_lamps, j + 2))) for j in camera_lamps]
    # bound once: the loop below runs per camera per frame (~300k times an hour)
    on_frame, in_motion = controller.on_frame, controller.cameras_in_motion
    collect = [collector.on_frame for collector in collectors]
    k = 0
    while True:
        yield env.timeout(max(0.0, k / fps - env.now))
        t = env.now
        agents = night.agents
        every = stride <= 1 or k % stride == 0
        any_ramping = lamp_states.any_ramping(t)
        # each camera's motion, read before any is judged (a camera's own frame is what changes it)
        moving = None if every else in_motion()
        if not every and not agents and not any(moving) and not any_ramping:
            k += 1  # a still street with nothing moving in view: no camera is judged
            continue
        ramping = lamp_states.ramping(t)
        rows = night.replay.rows_of(agents) if night.replay is not None else None
        sensors.observe(k, agents, lamp_states.levels_at(t), rows)
        awake = sensors.awake_cameras()
        # what decides whether a camera is judged was read above, before any camera is judged
        if every:
            judged = range(n)
        else:
            judged = [i for i in range(n)
                      if awake[i] or moving[i] or (any_ramping and any(ramping[j] for j in watch[i]))]  # fmt: skip
        for i in judged:
            frame = SensedFrame(sensors, i)
            detections = on_frame(i, t, frame)
            if collect:
                truth = frame.truth if detections is not None else ()
                for collector_on_frame in collect:
                    collector_on_frame(i, t, truth, detections)
        k += 1


def fast_sensors(night, model) -> FastSensors:
    """The night's sensor stand-ins: the model's draws from the night's per-camera streams."""
    return FastSensors(model, night.street, night.camera_streams(), night.street.lamps[0].camera.fps)

