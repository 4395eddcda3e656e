"""The simulation loop: one controller over one night, on one simpy clock.

``run_controller`` builds the night (``citysim.sim.night``), the controller with its lamps and
radio network, and the collectors of every figure (``citysim.metrics``), then runs the clock:

* traffic arrivals spawn agents into the world (started by the night builder);
* the physics process steps the world; after each step the collectors see the agents and the
  lamps' levels, then the controller does (PIR senses bodies; held lamps are released);
* for a camera controller, ``citysim.sim.cameras.film`` renders and judges the lamp cameras;
* one inbox per lamp delivers network messages to the controller;
* every whole simulated second the collectors are told (lamps.csv, hourly energy).

Random streams are children of the scenario seed in a fixed order (see ``night.STREAMS``), so
every controller sees the same agents, and the same seed gives the same results bit for bit.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from citysim.config.scenario import ControllerSpec, Scenario
from citysim.control.base import ControlContext, Controller
from citysim.control.lamps import Lamp
from citysim.control.network import Network
from citysim.control.registry import CONTROLLERS
from citysim.fast import FIDELITIES
from citysim.metrics.collector import Collector, overriding
from citysim.metrics.confusion import ConfusionCollector
from citysim.metrics.crossings import CrossingsCollector
from citysim.metrics.energy import EnergyCollector
from citysim.metrics.false_on import FalseOnTime
from citysim.metrics.lamp_log import LampLog
from citysim.sim.cameras import film
from citysim.sim.frames import CameraFrames, SharedFrames
from citysim.sim.night import Night, build_night
from citysim.sim.replay import TrafficReplay
from detector.cliargs import did_you_mean

#: The keys of one controller's summary, in the order summary.json lists them.
SUMMARY_KEYS = (
    "controller", "energy_kwh", "savings_vs_always_on", "lit_on_entry_rate", "lit_on_entry_interval_95",
    "zone_entries",
    "dark_s_per_100_entries", "lag_p50_s", "lag_p95_s", "lag_max_s",
    "dark_exposure_s", "unlit_crossings", "switches", "on_time_s", "false_on_time_s",
    "energy_per_hour_kwh", "energy_split_kwh", "energy_per_lamp_kwh", "objects", "per_class", "detection",
    "lamp_triggers", "network", "agents_spawned",
)  # fmt: skip


class RunError(ValueError):
    """A run that cannot start (e.g. an unknown controller); the message names the field."""


def check_fidelity(fidelity: str) -> None:
    if fidelity not in FIDELITIES:
        raise RunError(f"fidelity: unknown {fidelity!r}; valid: {', '.join(FIDELITIES)}")


def controller_spec(scenario: Scenario, name: str) -> ControllerSpec:
    """The scenario's spec for ``name`` (its label or registry name), else a default one."""
    for spec in scenario.controllers:
        if name in (spec.display_name, spec.name):
            return spec
    return ControllerSpec(name=name)


def check_controllers(names: list[str]) -> None:
    unknown = [n for n in names if n not in CONTROLLERS]
    if unknown:
        listed = ", ".join(map(repr, unknown))
        raise RunError(f"controllers: unknown {listed}{did_you_mean(unknown[0], list(CONTROLLERS))}")


def build_controller(night: Night, spec: ControllerSpec, sensors: object | None = None) -> Controller:
    """The controller of ``spec`` with its lamps (at their initial level) and radio network."""
    scenario = night.scenario
    controller_cls = CONTROLLERS[spec.name]
    lum = scenario.lamps.luminaire
    if spec.hold_s is not None:
        lum = lum.model_copy(update={"hold_s": spec.hold_s})
    initial = 1.0 if controller_cls.initial_level == "full" else lum.dim_level
    lamps = [Lamp(i, _own_luminaire(lum, site.rated_power_w), senses=controller_cls.senses, initial_level=initial)
             for i, site in enumerate(night.street.lamps)]  # fmt: skip
    network = Network(night.env, len(lamps), scenario.network, night.streams["network"])
    ctx = ControlContext(street=night.street, lamps=lamps, luminaire=lum,
                         frame_period_s=1.0 / night.street.lamps[0].camera.fps, rng=night.streams["control"],
                         network=network, start_hour=scenario.start_hour, spec=spec, sensors=sensors,
                         physics_step_s=night.physics_dt_s)  # fmt: skip
    return controller_cls(ctx)


def _own_luminaire(lum, rated_power_w: float | None):
    """``lum`` with a surveyed lamp's own ``rated_power_w`` (W), when it has one that differs."""
    if rated_power_w is None or rated_power_w == lum.rated_power_w:
        return lum
    return lum.model_copy(update={"rated_power_w": rated_power_w})


def deliver_messages(night: Night, controller: Controller, lamp_index: int):
    """simpy process: lamp ``lamp_index``'s network messages to the controller, as they arrive."""
    store = controller.ctx.network.inbox(lamp_index)
    while True:
        message = yield store.get()
        controller.on_message(lamp_index, night.env.now, message)


def _fast_cameras(scenario: Scenario, spec: ControllerSpec, fidelity: str, sensor_model) -> bool:
    """Whether the run's cameras are judged by the sensor model; refuses what fast mode cannot run."""
    check_controllers([spec.name])
    check_fidelity(fidelity)
    # controllers that watch no camera run alike in both fidelities and need no sensor model
    fast_cameras = fidelity == "fast" and CONTROLLERS[spec.name].uses_camera
    if fast_cameras and sensor_model is None:
        raise RunError("fidelity: 'fast' needs a calibrated sensor model (citysim calibrate SCENARIO)")
    return fast_cameras


def run_controller(
    scenario: Scenario,
    spec: ControllerSpec,
    *,
    on_progress: Callable[[float], None] | None = None,
    **options,
) -> dict:
    """Simulate the scenario's night under one controller; returns its summary (summary.json entry).

    ``options`` are ``ControllerRun``'s; ``on_progress(dt_s)`` after each simulated second.
    """
    run = ControllerRun(scenario, spec, **options)
    run.night.run_whole_seconds(run.on_second, on_progress)
    return run.summary()


class ControllerRun:
    """One controller's night, set up and ready to run.

    Parameters
    ----------
    scenario : citysim.config.scenario.Scenario
        The street, lamps, traffic and environment; ``scenario.duration_s`` (s) is the night's length.
    spec : citysim.config.scenario.ControllerSpec
        The controller to run and its settings.
    lamps_writer, objects_writer : csv.writer, optional
        Where lamps.csv rows (one per lamp and second) and objects.csv rows (one per zone visit)
        go; None writes none.
    traffic : pathlib.Path, optional
        A folder of this scenario's recorded traffic (``citysim.sim.replay``) to replay instead of
        stepping the world; the agents, and so the summary, are the same bit for bit.
    fidelity : {"full", "fast"}
        "full" renders every judged camera frame and runs the detector on it; "fast" draws the
        detections from ``sensor_model``.
    sensor_model : citysim.fast.model.SensorModel, optional
        Needed for ``fidelity="fast"`` with a camera controller (see ``citysim.sim.calibration``).
    sensors : object, optional
        Replaces the cameras' detectors in full fidelity (calibration records them).
    observers : sequence of citysim.metrics.collector.Collector
        Extra collectors (calibration's recorder).
    lamps_held_dim : bool
        The controller's triggers (``LampBank.trigger``, how every controller but the clock
        schedules lights a lamp) change no level, so the lamps stay dim (calibration's quiet nights).
    shared_frames : citysim.sim.frames.SharedFrames, optional
        Full fidelity's camera frames are taken from, and given to, the frames of the controllers
        run in step with this one (``citysim.sim.together``).

    Attributes
    ----------
    night : citysim.sim.night.Night
        The simpy environment, world and cameras of this run.
    controller : citysim.control.base.Controller
        The controller switching the lamps.
    collectors : list of citysim.metrics.collector.Collector
        What the run measures; ``summary()`` gathers their figures.
    """

    def __init__(
        self,
        scenario: Scenario,
        spec: ControllerSpec,
        *,
        lamps_writer: csv.writer | None = None,
        objects_writer: csv.writer | None = None,
        traffic: Path | None = None,
        fidelity: str = "full",
        sensor_model=None,
        sensors: object | None = None,
        observers: Sequence[Collector] = (),
        lamps_held_dim: bool = False,
        shared_frames: SharedFrames | None = None,
    ) -> None:
        fast_cameras = _fast_cameras(scenario, spec, fidelity, sensor_model)
        self.scenario, self.spec = scenario, spec
        self.night = night = build_night(scenario, replay=None if traffic is None else TrafficReplay(traffic))
        if fast_cameras:
            from citysim.fast.sense import fast_sensors  # the detector's classes: camera runs only

            # each controller draws from the fit on the decisions it counts (insects seldom make a target track)
            model = sensor_model.for_decisions(CONTROLLERS[spec.name].decisions(spec))
            sensors = fast_sensors(night, model)
        self.controller = controller = build_controller(night, spec, sensors)
        controller.bank.held_dim = lamps_held_dim
        lamps, label = controller.ctx.lamps, spec.display_name
        self.collectors: list[Collector] = [
            # the per-class figures list the detector's own classes always, other kinds when present
            CrossingsCollector(night.street, label, objects_writer, scenario.traffic.reported_kinds()),
            FalseOnTime(night.street, controller.ctx.dim_level, night.physics_dt_s),
            ConfusionCollector(),
            EnergyCollector(lamps, controller.ctx.luminaire),
            LampLog(label, lamps, lamps_writer),
            *observers,
        ]
        # the base Collector's hooks do nothing: only the collectors that override one are called
        self._second_collectors = overriding(self.collectors, "on_second")
        night.start_physics(self._after_step_hook())
        if controller.uses_camera:
            frame_collectors = overriding(self.collectors, "on_frame")
            # frames come half a physics step after the physics tick they show, so both orderings agree
            if fast_cameras:
                from citysim.fast.sense import sense

                night.env.process(sense(night, sensors, controller, lamps, frame_collectors))
            else:
                frames = CameraFrames(night.renderers(), shared_frames)
                night.env.process(film(night, frames, controller, lamps, frame_collectors))
        for i in range(len(lamps)):
            night.env.process(deliver_messages(night, controller, i))

    def _after_step_hook(self) -> Callable[[float, Any], None]:
        lamp_states, controller = self.controller.ctx.lamp_states, self.controller
        step_collectors = overriding(self.collectors, "on_step")

        def after_step(t_s: float, agents) -> None:
            levels = lamp_states.levels_at(t_s)
            for collector in step_collectors:
                collector.on_step(t_s, agents, levels)
            controller.on_physics_step(t_s, agents)

        return after_step

    def on_second(self, t_s: float) -> None:
        """Before second ``t_s`` runs: the collectors that count seconds (lamps.csv, hourly energy).

        Parameters
        ----------
        t_s : float
            Simulated time, s from the start of the night (a whole second).
        """
        for collector in self._second_collectors:
            collector.on_second(t_s)

    def summary(self) -> dict:
        """The run's summary.json entry, once the clock has reached the scenario's end.

        Returns
        -------
        dict
            The controller's figures (keys ``SUMMARY_KEYS``): energy in kWh, savings and
            lit-on-entry rates as shares 0..1, lags and dark exposure in s, counts.
        """
        figures: dict[str, Any] = {"controller": self.spec.name}
        for collector in self.collectors:
            figures.update(collector.finish(self.scenario.duration_s))
        figures.update(_controller_figures(self.controller, self.night))
        return {key: figures[key] for key in SUMMARY_KEYS}


def _controller_figures(controller: Controller, night: Night) -> dict[str, Any]:
    bank, stats = controller.bank, controller.ctx.network.stats
    return {
        "lamp_triggers": [{"lamp": i, "triggers": int(bank.triggers[i]), "first_s": _finite(bank.first_trigger_s[i]),
                           "last_s": _finite(bank.last_trigger_s[i])} for i in range(len(controller.ctx.lamps))],
        "network": {"sent": stats.sent, "delivered": stats.delivered, "lost": stats.lost},
        "agents_spawned": night.spawned_count,
    }  # fmt: skip


def _finite(x: float) -> float | None:
    return None if math.isnan(x) else float(x)
