"""The one place a night is built: seed streams -> street -> world -> clock -> traffic -> cameras.

``build_night(scenario)`` gives a ``Night``: the scenario's street, the pymunk world, a simpy
clock with the traffic arrivals started, and the random streams split off the seed. Every user
of a night (``citysim run``'s loop, ``citysim render``, the paper reproduction, the tests)
builds it here, so the same seed always means the same people, cars and sensor noise.

``Night.start_physics(on_step)`` adds the process that steps the world at ``physics_hz`` and
hands each step's agent snapshots to ``on_step``; ``Night.renderer(camera)`` is that camera's
renderer (``Street.cameras``: camera i hangs on lamp i, backward cameras follow), fed by its own
child of the render stream (one per camera, split once, in camera order), so a camera's noise
does not depend on which other cameras are rendered.

``build_night(scenario, replay=...)`` is the same night with the world's agents read back from a
recording (``citysim.sim.replay``) instead of stepped: no traffic process runs and the world is
never stepped, but every physics step comes at the same time with the same agents.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

import numpy as np
import simpy

from citysim.config.scenario import Scenario
from citysim.world.agents import AgentColumns, AgentState
from citysim.world.physics import World
from citysim.world.street import Street, build_street
from citysim.world.traffic import start_traffic
from detector.outdir import raise_if_terminated

if TYPE_CHECKING:
    from citysim.render.camera import CameraRenderer

#: Streams split off the scenario seed, in this order; never reorder (results would change).
STREAMS = ("traffic", "world", "render", "control", "network")

StepHook = Callable[[float, Sequence[AgentState]], None]


class AgentSource(Protocol):
    """Recorded agents, step by step (``citysim.sim.replay.TrafficReplay``)."""

    spawned_count: int  # agents that had entered the street by the latest step

    def next_step(self) -> Sequence[AgentState]: ...

    def rows_of(self, agents: Sequence[AgentState]) -> tuple[AgentColumns, int] | None:
        """The recording's columns holding the latest step's ``agents`` and their first row (None:
        ``agents`` is not that step's list)."""


def seed_streams(seed: int) -> dict[str, np.random.Generator]:
    """One independent generator per stream name of ``STREAMS``, children of ``seed``."""
    children = np.random.SeedSequence(seed).spawn(len(STREAMS))
    return {name: np.random.default_rng(child) for name, child in zip(STREAMS, children, strict=True)}


@dataclass
class Night:
    """A scenario's street, world, clock and random streams, with the traffic running."""

    scenario: Scenario
    streams: dict[str, np.random.Generator]
    street: Street
    world: World
    env: simpy.Environment
    #: the agents after the latest physics step (empty before the first)
    agents: Sequence[AgentState] = field(default_factory=list)
    _camera_streams: list[np.random.Generator] | None = None
    #: the recorded agents replayed instead of stepping ``world`` (None: step it)
    replay: AgentSource | None = None
    #: run a physics step at once when no other event of the clock comes before it (``_physics``);
    #: False: every step waits on its own timeout (the same steps at the same times, in the same order)
    skip_idle_clock: bool = True

    @property
    def physics_dt_s(self) -> float:
        return 1.0 / self.scenario.physics_hz

    @property
    def spawned_count(self) -> int:
        """Agents that had entered the street by the latest physics step."""
        return self.world.spawned_count if self.replay is None else self.replay.spawned_count

    @property
    def n_lamps(self) -> int:
        return len(self.street.lamps)

    def start_physics(self, on_step: StepHook | None = None, snapshots: bool = True) -> None:
        """Step the world at ``physics_hz`` from t = 0; ``on_step(t_s, agents)`` after each step.
        ``snapshots`` False: the stepped world's agents are not made into snapshots (``agents``
        stays empty; the traffic recorder reads ``World.snapshot_rows`` instead)."""
        self.env.process(self._physics(on_step, snapshots))

    def _physics(self, on_step: StepHook | None, snapshots: bool = True):
        dt_s = self.physics_dt_s
        env = self.env
        k = 0
        while True:
            k += 1
            # scheduled at k * dt from the start, so steps do not drift with float sums
            now_s = env.now
            delay_s = max(0.0, k * dt_s - now_s)
            if self.skip_idle_clock and env.peek() > now_s + delay_s:
                # no event is due before this step (not even the end of ``run_until``): waiting on
                # the clock would only pop this step's own timeout, at the time simpy would give it
                # (``Environment.schedule``: now + delay). A night whose other processes sleep
                # between whole seconds so runs most steps without simpy's event machinery.
                env._now = now_s + delay_s
            else:
                yield env.timeout(delay_s)
            if self.replay is None:
                self.world.step(dt_s)
                if snapshots:
                    self.agents = self.world.states()
            else:
                self.agents = self.replay.next_step()
            if on_step is not None:
                on_step(self.env.now, self.agents)

    def run_until(self, t_s: float) -> None:
        """Advance the clock to ``t_s`` (events at exactly ``t_s`` have not run yet)."""
        if t_s > self.env.now:
            self.env.run(until=t_s)

    def run_whole_seconds(self, on_second: Callable[[float], None] | None = None,
                          on_progress: Callable[[float], None] | None = None) -> None:  # fmt: skip
        """Run the clock from 0 to the scenario's end one simulated second at a time:
        ``on_second(t_s)`` before second ``t_s`` runs, ``on_progress(dt_s)`` after it. Between
        seconds a SIGTERM whose exception a C callback (pymunk's) swallowed stops the run."""
        for t_s in whole_seconds(self.scenario.duration_s):
            t_next_s = self.run_second(t_s, on_second)
            if on_progress is not None:
                on_progress(t_next_s - t_s)

    def run_second(self, t_s: float, on_second: Callable[[float], None] | None = None) -> float:
        """One step of ``run_whole_seconds``: ``on_second(t_s)``, then the clock to the next whole
        second (or the end); returns that time. Runs in step call it for each night in turn."""
        if on_second is not None:
            on_second(t_s)
        t_next_s = min(self.scenario.duration_s, t_s + 1.0)
        self.run_until(t_next_s)
        raise_if_terminated()
        return t_next_s

    @property
    def n_cameras(self) -> int:
        """Lamp cameras: one per pole, two with ``lamps.camera.back_heading_deg``."""
        return len(self.street.cameras)

    def camera_streams(self) -> list[np.random.Generator]:
        """One render stream per camera, split once off the render stream, in camera order.

        The first n_lamps children are the same whether or not backward cameras follow them, so
        adding backward cameras leaves the forward cameras' noise as it was.
        """
        if self._camera_streams is None:
            self._camera_streams = self.streams["render"].spawn(self.n_cameras)
        return self._camera_streams

    def renderer(self, camera_index: int) -> CameraRenderer:
        """The renderer of one camera (``Street.cameras``; camera i is lamp i's own) under the scenario's environment."""
        # imported here: the renderer loads numba (~150 MB), which light controllers never need
        from citysim.render.camera import CameraRenderer

        if not 0 <= camera_index < self.n_cameras:
            raise IndexError(f"camera: must be in 0..{self.n_cameras - 1}, got {camera_index}")
        site = self.street.cameras[camera_index]
        env = self.scenario.environment
        return CameraRenderer(site.camera, self.street, env, self.camera_streams()[camera_index])

    def renderers(self, cameras: Sequence[int] | None = None) -> list[CameraRenderer]:
        return [self.renderer(i) for i in (range(self.n_cameras) if cameras is None else cameras)]


def whole_seconds(duration_s: float) -> Iterator[float]:
    """The start of every simulated second of a night ``duration_s`` long: 0, 1, 2, ... (the last
    second may be cut short by the end; ``Night.run_second`` runs each)."""
    t_s = 0.0
    while t_s < duration_s - 1e-9:
        yield t_s
        t_s = min(duration_s, t_s + 1.0)


def build_night(scenario: Scenario, replay: AgentSource | None = None) -> Night:
    """The scenario's night at t = 0, traffic processes started, physics not yet; with
    ``replay``, the recorded agents of that scenario instead of traffic and world steps."""
    streams = seed_streams(scenario.seed)
    street = build_street(scenario)
    world = World(street, streams["world"])
    env = simpy.Environment()
    if replay is None:
        start_traffic(env, world, scenario, streams["traffic"])
    return Night(scenario, streams, street, world, env, replay=replay)
