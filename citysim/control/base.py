"""What every controller shares: its context, the lamp bank of holds, and the base class.

A controller owns one decision-maker per lamp and is fed by the simulation loop
(``citysim.sim.loop``): camera frames at the camera's frame rate (only if ``uses_camera``; by
camera index, ``ControlContext.camera_lamps`` saying which lamp each camera hangs on),
agent snapshots at the physics rate (PIR needs them: it senses heat, not pixels) and network
messages. It decides by calling ``bank.trigger`` (light this lamp now and keep it lit for the
hold time) or by setting lamp targets; the ``LampBank`` releases lamps after the hold time.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from citysim.config.scenario import ControllerSpec
from citysim.config.street import LuminaireSpec
from citysim.control.lamps import Lamp, LampStates
from citysim.control.network import Network
from citysim.world.agents import AgentState
from citysim.world.street import Street


@dataclass
class ControlContext:
    """What every controller may read: the street, the lamps, their luminaire and the network."""

    street: Street
    lamps: list[Lamp]
    luminaire: LuminaireSpec  # the scenario's, with the controller's own hold_s if it sets one
    frame_period_s: float
    rng: np.random.Generator
    network: Network
    start_hour: float = 22.0
    spec: ControllerSpec = field(default_factory=lambda: ControllerSpec(name="always_on"))
    #: Where camera controllers get their per-camera detectors and segmenters: None, the real
    #: ones on rendered frames; in fast mode a sensor model (``citysim.fast.sensors.FastSensors``:
    #: ``detectors(ctx, threshold)`` and ``segmenters(ctx)``) with the same interface.
    sensors: object | None = None
    #: The lamps' levels and ramping, read once per step by everything that needs them (made from
    #: ``lamps`` when not given)
    lamp_states: LampStates | None = None
    #: The world's step (1 / ``physics_hz``), s: controllers that decide once a step allow for it
    physics_step_s: float = 1.0 / 30.0

    def __post_init__(self) -> None:
        if self.lamp_states is None:
            self.lamp_states = LampStates(self.lamps)

    @property
    def camera_lamps(self) -> tuple[int, ...]:
        """The lamp each camera hangs on, by camera index (``Street.cameras``: camera i is lamp i's own)."""
        return self.street.camera_lamps

    @property
    def hold_s(self) -> float:
        return self.luminaire.hold_s

    @property
    def dim_level(self) -> float:
        return self.luminaire.dim_level


class LampBank:
    """Lamps lit by triggers and released to dim after the hold time."""

    def __init__(self, ctx: ControlContext):
        self.ctx = ctx
        # plain lists of plain floats and ints: a controller triggers lamps up to every physics step,
        # where numpy's per-element access was most of a trigger's cost
        n = len(ctx.lamps)
        self.lit_until_s: list[float] = [-math.inf] * n
        self.first_trigger_s: list[float] = [math.nan] * n
        self.last_trigger_s: list[float] = [math.nan] * n
        self.triggers: list[int] = [0] * n
        # no hold runs out before this time: release_expired has nothing to do until then (lamps
        # start unheld, so the first call looks at every lamp, as a lamp starting at full needs)
        self._next_expiry_s = -math.inf
        #: when set, triggers change nothing: calibration's quiet nights (``citysim.sim.calibration``)
        #: run the cameras and the detector as usual on a street whose lamps all stay dim
        self.held_dim = False

    def trigger(self, lamp_index: int, t_s: float, hold_s: float | None = None) -> None:
        self.trigger_all((lamp_index,), t_s, hold_s)

    def trigger_all(self, lamp_indices: Sequence[int], t_s: float, hold_s: float | None = None) -> None:
        """``trigger`` each of ``lamp_indices`` in turn (the oracle's lamps of a physics step)."""
        if self.held_dim:
            return
        until = t_s + (self.ctx.hold_s if hold_s is None else hold_s)
        triggers, lit_until_s, lamps = self.triggers, self.lit_until_s, self.ctx.lamps
        for i in lamp_indices:
            if triggers[i] == 0:
                self.first_trigger_s[i] = t_s
            self.last_trigger_s[i] = t_s
            triggers[i] += 1
            if until > lit_until_s[i]:
                lit_until_s[i] = until
            self._next_expiry_s = min(self._next_expiry_s, lit_until_s[i])
            lamp = lamps[i]
            if lamp.target_level < 1.0:
                lamp.set_target(t_s, 1.0)

    def release_expired(self, t_s: float) -> None:
        """Called every physics step: lamps whose hold ran out go back to dim."""
        if t_s < self._next_expiry_s:
            return
        for i, until_s in enumerate(self.lit_until_s):
            lamp = self.ctx.lamps[i]
            if until_s <= t_s and lamp.target_level > self.ctx.dim_level:
                lamp.set_target(t_s, self.ctx.dim_level)
        self._next_expiry_s = min((u for u in self.lit_until_s if u > t_s), default=math.inf)


class Controller:
    """Base: a named way of switching the lamps. Subclasses override the hooks they need."""

    name: ClassVar[str] = ""
    uses_camera: ClassVar[bool] = False
    senses: ClassVar[bool] = True  # pays the sensing power (camera/board/IR or PIR)
    initial_level: ClassVar[str] = "dim"  # "dim" or "full"
    #: takes the detector's track decisions rather than each frame's (camera controllers that
    #: run the detector; a scenario's controller spec may override it)
    tracking: ClassVar[bool] = False

    def __init__(self, ctx: ControlContext):
        self.ctx = ctx
        self.bank = LampBank(ctx)

    @classmethod
    def decides_per_track(cls, spec) -> bool:
        """Whether this controller, as ``spec`` (a ``ControllerSpec``) sets it up, decides on the
        detector's tracks: the class's ``tracking`` unless the spec sets it."""
        return cls.tracking if spec.tracking is None else bool(spec.tracking)

    @classmethod
    def decisions(cls, spec) -> str:
        """Which of the detector's decisions this controller, as ``spec`` sets it up, counts: 'frame'
        (each frame's own) or 'track' (its track's); fast mode draws from that fit of the sensor model."""
        return "track" if cls.decides_per_track(spec) else "frame"

    def on_physics_step(self, t_s: float, agents: Sequence[AgentState]) -> None:
        self.bank.release_expired(t_s)

    def on_frame(self, camera_index: int, t_s: float, image: np.ndarray) -> list | None:
        """Handle one frame of camera ``camera_index`` (on lamp ``ctx.camera_lamps[camera_index]``);
        return the detector's detections if there are any (for confusion metrics)."""
        return None

    def on_message(self, lamp_index: int, t_s: float, message) -> None:
        pass

    def motion_seen(self, camera_index: int) -> bool:
        """Does this camera need every frame now? (see ``citysim.sim.cameras.CameraSchedule``)

        True while its last judged frame held a moving region.
        """
        return False

    def cameras_in_motion(self) -> list[bool]:
        """``motion_seen`` of every camera at once (fast mode's sense loop asks every frame)."""
        return [self.motion_seen(i) for i in range(len(self.ctx.camera_lamps))]
