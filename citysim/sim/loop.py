"""The simulation loop: world, cameras, controllers and lamps on one simpy clock.

``run_controller`` runs one controller over a scenario's night; ``run_comparison``
runs every controller of a comparison on the same traffic (the world and its
random streams never depend on the controller) and writes the run folder.

simpy processes (each a small generator):

* traffic arrivals (``citysim.world.traffic``) spawn agents into the world;
* ``physics`` steps the pymunk world at ``physics_hz``, updates the zone
  metrics, lets the controller see the agents (PIR) and release held lamps;
* ``cameras`` renders every lamp camera at its frame rate (only for camera
  controllers), hands the frame to the controller and scores its detections;
* one ``inbox`` per lamp delivers network messages to the controller.

Random streams are children of the scenario seed in a fixed order (traffic,
world, per-lamp render noise, control, network), so every controller sees the
same agents, and the same seed gives the same results bit for bit.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import simpy

from citysim.config.scenario import ControllerSpec, Scenario
from citysim.control.controllers import CONTROLLERS, ControlContext
from citysim.control.lamps import Lamp, LuminaireSpec, always_on_energy_j
from citysim.control.network import LinkSpec, Network
from citysim.metrics.energy import DetectionConfusion, ZoneTracker, energy_summary
from citysim.world.physics import World
from citysim.world.street import Street, build_street
from citysim.world.traffic import start_traffic

if TYPE_CHECKING:
    from citysim.render.camera import CameraRenderer, RenderParams

LAMPS_CSV_HEADER = ["controller", "t_s", "lamp", "level", "power_w"]
OBJECTS_CSV_HEADER = ["controller", "object_id", "cls", "lamp", "t_enter_s", "t_exit_s", "lag_s", "dark_s", "lit_on_entry"]
#: Streams split off the scenario seed, in this order; never reorder (results would change).
STREAMS = ("traffic", "world", "render", "control", "network")
#: Rain streaks per frame in a ``weather: rain`` night.
RAIN_DROPS_PER_FRAME = 120


class RunError(ValueError):
    """A run that cannot start (e.g. an unknown controller); the message names the field."""


def seed_streams(seed: int) -> dict[str, np.random.Generator]:
    children = np.random.SeedSequence(seed).spawn(len(STREAMS))
    return {name: np.random.default_rng(child) for name, child in zip(STREAMS, children, strict=True)}


def luminaire_of(scenario: Scenario, controller: ControllerSpec) -> LuminaireSpec:
    lum = scenario.lamps.luminaire
    hold_s = lum.hold_s if controller.hold_s is None else controller.hold_s
    return LuminaireSpec(rated_power_w=lum.rated_power_w, dim_level=lum.dim_level, standby_power_w=lum.standby_power_w,
                         ramp_up_s=lum.ramp_up_s, fade_s=lum.fade_s, hold_s=hold_s, sensing_power_w=lum.sensing_power_w)


def render_params_of(scenario: Scenario) -> RenderParams:
    from citysim.render.camera import RenderParams

    env = scenario.environment
    return RenderParams(
        ambient_light=0.0 if scenario.night else 1.0,
        sensor_noise_std_dn=env.sensor_noise_std_dn,
        exposure_ms=env.exposure_ms,
        distortion=env.lens_distortion,
        rain_drops_per_frame=RAIN_DROPS_PER_FRAME if env.weather == "rain" else 0,
        insects_per_min=env.insects_per_min,
        wind_mps=env.wind_mps,
    )


def controller_spec(scenario: Scenario, name: str) -> ControllerSpec:
    """The scenario's spec for ``name`` (its label or registry name), else a default one."""
    for spec in scenario.controllers:
        if name in (spec.display_name, spec.name):
            return spec
    return ControllerSpec(name=name)


def check_controllers(names: list[str]) -> None:
    unknown = [n for n in names if n not in CONTROLLERS]
    if unknown:
        raise RunError(f"controllers: unknown {', '.join(map(repr, unknown))}; valid: {', '.join(CONTROLLERS)}")


class LampLog:
    """Streams lamps.csv rows (one per lamp per simulated second) to a writer."""

    def __init__(self, label: str, lamps: list[Lamp], writer: csv.writer | None):
        self.label, self.lamps, self.writer = label, lamps, writer

    def process(self, env: simpy.Environment):
        while True:
            if self.writer is not None:
                t = env.now
                for lamp in self.lamps:
                    self.writer.writerow([self.label, f"{t:.3f}", lamp.index, f"{lamp.level_at(t):.4f}", f"{lamp.power_w(t):.3f}"])
            yield env.timeout(1.0)


class CameraSchedule:
    """Which lamp cameras are judged this frame: every one that may see something, the rest sparsely.

    A camera is *busy* when an agent stands in its view (projected inside the frame, with a margin
    for what is about to enter), when the light in its view is changing, or when its last judged
    frame held a moving region (an insect, a swaying branch, an animal: it stays at full rate while
    that lasts). An idle camera looks at a static scene; it is judged every ``idle_stride``-th frame,
    which keeps its background model fed (at the learning rate of every frame taken, see
    ``control.BackgroundClock``) and samples the noise that would wake it. With
    ``idle_stride`` 1 every frame of every camera is judged (exact, and slow).
    """

    MARGIN = 0.25  # fraction of the frame size an agent may stand outside it and still count as in view
    # the detector ignores what is beyond 25 m; 15 m more wakes a camera ~1 s before a car at
    # 60 km/h comes into its range, so nothing in range is ever judged at the idle rate
    MAX_FORWARD_M = 40.0

    def __init__(self, street: Street, idle_stride: int):
        self.cameras = [site.camera for site in street.lamps]
        self.idle_stride = idle_stride
        self.n = len(self.cameras)
        self.watch = [list(range(max(0, i - 1), min(self.n, i + 2))) for i in range(self.n)]

    def in_view(self, agents) -> np.ndarray:
        busy = np.zeros(self.n, dtype=bool)
        if not agents:
            return busy
        pts = np.array([[a.x_m, a.y_m, 0.9] for a in agents])
        for i, cam in enumerate(self.cameras):
            fwd = cam.forward_and_lateral_m(pts)[:, 0]
            near = (fwd > 0.0) & (fwd < self.MAX_FORWARD_M)
            if not near.any():
                continue
            px = cam.project(pts[near], distort=False)
            mu, mv = self.MARGIN * cam.width_px, self.MARGIN * cam.height_px
            inside = (px[:, 0] > -mu) & (px[:, 0] < cam.width_px + mu) & (px[:, 1] > -mv) & (px[:, 1] < cam.height_px + mv)
            busy[i] = bool(inside.any())
        return busy

    def active(self, k: int, t_s: float, agents, lamps: list[Lamp], controller) -> np.ndarray:
        if self.idle_stride <= 1 or k % self.idle_stride == 0:
            return np.ones(self.n, dtype=bool)
        busy = self.in_view(agents)
        for i in range(self.n):
            if not busy[i]:
                busy[i] = controller.motion_seen(i) or any(lamps[j].is_ramping(t_s) for j in self.watch[i])
        return busy


class FalseOnTime:
    """Lamp-seconds lit above dim while no target object is in the lamp's zone."""

    def __init__(self, street: Street, dim_level: float):
        self.starts = np.array([s.zone_start_m for s in street.lamps])
        self.ends = np.array([s.zone_end_m for s in street.lamps])
        self.dim_level = dim_level
        self.seconds = 0.0

    def add(self, dt_s: float, target_x_m: np.ndarray, levels: np.ndarray) -> None:
        lit = levels > self.dim_level + 1e-6
        if not lit.any():
            return
        if len(target_x_m):
            occupied = ((target_x_m[None, :] >= self.starts[:, None]) & (target_x_m[None, :] < self.ends[:, None])).any(axis=1)
        else:
            occupied = np.zeros(len(levels), dtype=bool)
        self.seconds += dt_s * float(np.count_nonzero(lit & ~occupied))


def run_controller(
    scenario: Scenario,
    spec: ControllerSpec,
    *,
    lamps_writer: csv.writer | None = None,
    objects_writer: csv.writer | None = None,
    on_progress: Callable[[float], None] | None = None,
) -> dict:
    """Simulate the scenario's night under one controller; returns its summary (summary.json entry)."""
    check_controllers([spec.name])
    label = spec.display_name
    rngs = seed_streams(scenario.seed)
    street = build_street(scenario)
    world = World(street, rngs["world"])
    env = simpy.Environment()
    start_traffic(env, world, scenario, rngs["traffic"])

    controller_cls = CONTROLLERS[spec.name]
    lum = luminaire_of(scenario, spec)
    initial = 1.0 if controller_cls.initial_level == "full" else lum.dim_level
    lamps = [Lamp(i, lum, senses=controller_cls.senses, initial_level=initial) for i in range(len(street.lamps))]
    net = scenario.network
    network = Network(env, len(lamps), LinkSpec(latency_ms=net.latency_ms, jitter_ms=net.jitter_ms,
                                                 loss_probability=net.loss_probability, repeat_s=net.repeat_s), rngs["network"])
    ctx = ControlContext(street=street, lamps=lamps, hold_s=lum.hold_s, dim_level=lum.dim_level,
                         frame_period_s=1.0 / street.lamps[0].camera.fps, rng=rngs["control"], network=network,
                         start_hour=scenario.start_hour, spec=spec, neighbours_ahead=net.neighbours_ahead)
    controller = controller_cls(ctx)

    # the per-class figures list the detector's own classes always, other kinds when present
    zones = ZoneTracker(street, required_level=dict.fromkeys(scenario.traffic.reported_kinds(), 1.0))
    confusion = DetectionConfusion()
    false_on = FalseOnTime(street, lum.dim_level)
    state = {"agents": []}
    dt_s = 1.0 / scenario.physics_hz

    def levels_at(t_s: float) -> np.ndarray:
        return np.array([lamp.level_at(t_s) for lamp in lamps])

    def physics():
        k = 0
        while True:
            k += 1
            yield env.timeout(max(0.0, k * dt_s - env.now))
            world.step(dt_s)
            t = env.now
            agents = world.states()
            state["agents"] = agents
            levels = levels_at(t)
            zones.update(t, agents, levels)
            false_on.add(dt_s, np.array([a.x_m for a in agents if a.is_target]), levels)
            controller.on_physics_step(t, agents)
            if objects_writer is not None:
                write_object_rows(objects_writer, label, zones)

    def cameras(renderers: list[CameraRenderer], fps: float, schedule: CameraSchedule):
        k = 0
        while True:
            yield env.timeout(max(0.0, k / fps - env.now))
            t = env.now
            levels = levels_at(t)
            active = schedule.active(k, t, state["agents"], lamps, controller)
            for i in np.flatnonzero(active):
                frame = renderers[i].render(t, state["agents"], levels, frame_index=k)
                detections = controller.on_frame(int(i), t, frame.image)
                if detections is not None:
                    confusion.add(frame.truth, detections, int(i), t)
            k += 1

    def inbox(i: int):
        store = network.inbox(i)
        while True:
            message = yield store.get()
            controller.on_message(i, env.now, message)

    env.process(physics())
    if controller_cls.uses_camera:
        # imported here: the renderer loads numba (~150 MB), which light controllers never need
        from citysim.render.camera import CameraRenderer

        params = render_params_of(scenario)
        render_rngs = rngs["render"].spawn(len(street.lamps))
        renderers = [CameraRenderer(site.camera, street, params, rng) for site, rng in zip(street.lamps, render_rngs, strict=True)]
        # frames come half a physics step after the physics tick they show, so both orderings agree
        camera_schedule = CameraSchedule(street, scenario.simulation.idle_frame_stride)
        env.process(cameras(renderers, street.lamps[0].camera.fps, camera_schedule))
    for i in range(len(lamps)):
        env.process(inbox(i))
    env.process(LampLog(label, lamps, lamps_writer).process(env))

    hourly_kwh = []
    t_end = scenario.duration_s
    chunk_s = 1.0
    t = 0.0
    last_energy_j = 0.0
    while t < t_end - 1e-9:
        t_next = min(t_end, t + chunk_s)
        env.run(until=t_next)
        if on_progress is not None:
            on_progress(t_next - t)
        t = t_next
        if math.isclose(t % 3600.0, 0.0, abs_tol=1e-6) or t >= t_end - 1e-9:
            for lamp in lamps:
                lamp.advance(t)
            energy_j = sum(lamp.energy_j for lamp in lamps)
            hourly_kwh.append((energy_j - last_energy_j) / 3.6e6)
            last_energy_j = energy_j

    for lamp in lamps:
        lamp.advance(t_end)
    zones.finish(t_end)
    confusion.finish()
    if objects_writer is not None:
        write_object_rows(objects_writer, label, zones)
    energy = energy_summary(lamps, always_on_energy_j(len(lamps), lum, t_end))
    zsum = zones.summary()
    overall = zsum["overall"]
    return {
        "controller": spec.name,
        "energy_kwh": energy["energy_kwh"],
        "savings_vs_always_on": energy["savings_vs_always_on"],
        "lag_p50_s": overall["lag_p50_s"],
        "lag_p95_s": overall["lag_p95_s"],
        "lag_max_s": overall["lag_max_s"],
        "dark_exposure_s": overall["dark_exposure_total_s"],
        "unlit_crossings": overall["unlit_crossings"],
        "switches": energy["switches"],
        "on_time_s": energy["on_time_s"],
        "false_on_time_s": false_on.seconds,
        "energy_per_hour_kwh": hourly_kwh,
        "energy_split_kwh": {k.removesuffix("_energy_kwh"): energy[k] for k in
                             ("luminaire_energy_kwh", "standby_energy_kwh", "sensing_energy_kwh")},
        "objects": overall["objects"],
        "per_class": {cls: {"objects": s["objects"], "lag_p50_s": s["lag_p50_s"], "lag_p95_s": s["lag_p95_s"],
                            "lag_max_s": s["lag_max_s"], "dark_exposure_s": s["dark_exposure_total_s"],
                            "unlit_crossings": s["unlit_crossings"]}
                      for cls, s in zsum["by_class"].items()},
        "detection": confusion.summary() if controller_cls.uses_camera and confusion.frames else {},
        "lamp_triggers": [{"lamp": i, "triggers": int(controller.bank.triggers[i]),
                           "first_s": _finite(controller.bank.first_trigger_s[i]),
                           "last_s": _finite(controller.bank.last_trigger_s[i])} for i in range(len(lamps))],
        "network": {"sent": network.stats.sent, "delivered": network.stats.delivered, "lost": network.stats.lost},
        "agents_spawned": world.spawned_count,
    }


def _finite(x: float) -> float | None:
    return None if math.isnan(x) else float(x)


def write_object_rows(writer: csv.writer, label: str, zones: ZoneTracker) -> None:
    for row in zones.rows(drain=True):
        writer.writerow([label, row["object_id"], row["cls"], row["lamp"], f"{row['t_enter_s']:.3f}",
                         f"{row['t_exit_s']:.3f}", f"{row['lag_s']:.3f}", f"{row['dark_s']:.3f}", int(bool(row["lit_on_entry"]))])


def run_to_files(scenario: Scenario, spec: ControllerSpec, part_dir: Path, on_progress=None) -> dict:
    """One controller's run writing its part of lamps.csv / objects.csv into ``part_dir``."""
    part_dir.mkdir(parents=True, exist_ok=True)
    label = spec.display_name
    with open(part_dir / f"{label}.lamps.csv", "w", newline="") as lf, open(part_dir / f"{label}.objects.csv", "w", newline="") as of:
        return run_controller(scenario, spec, lamps_writer=csv.writer(lf), objects_writer=csv.writer(of), on_progress=on_progress)


def run_comparison(*args, **kwargs) -> dict:
    """See ``citysim.sim.compare.run_comparison`` (kept here too: sim is the house's entry point)."""
    from citysim.sim.compare import run_comparison as compare

    return compare(*args, **kwargs)
