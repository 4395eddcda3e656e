"""IR-like camera frames of the street, with per-frame ground truth (the renderer's side of the camera model: frames plus what is truly in them).

``CameraRenderer(camera, street, environment, rng).render(t_s, agents, lamp_levels)``
returns an 8-bit grayscale frame as the lamp's camera would see it and, for
every agent whose silhouette shows in the frame, its class and bounding box.

Ground truth: boxes are OpenCV ``boundingRect`` boxes (x, y, w, h) of the agent's visible
rendered pixels in the output frame, clipped to the frame; ``distance_m`` is the forward ground
distance of the footprint centre along the camera heading (m, what ``detector.features``
estimates, eq. 4).

Design: docs/design/modules.md (Camera frames)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from citysim.config.scenario import EnvironmentSpec
from citysim.render.agents import AgentLighting, AgentPainter, DrawnAgent
from citysim.render.background import ShadingInputs, StaticScene
from citysim.render.beams import (
    LAMP_HEAD_GLARE,
    LAMP_HEAD_SIZE_M,
    agent_glare_sources,
    glare,
    shows_light,
)
from citysim.render.canvas import build_canvas
from citysim.render.effects.common import EffectFrame
from citysim.render.effects.registry import EFFECTS
from citysim.render.kernels import label_stats
from citysim.render.models import model_of, prepare_models
from citysim.render.output import FrameOutput
from citysim.render.spots import add_ground_spots, spot_reach
from citysim.world.agents import AgentState
from citysim.world.street import Street
from detector.camera import CameraModel

#: An agent hidden behind nearer things for more than this fraction is not fully visible.
MAX_HIDDEN_FRACTION = 0.5

@dataclass(frozen=True)
class RenderOptions:
    """Switches of the renderer itself, not of the night (the night is the scenario's
    ``EnvironmentSpec``): tests turn effects off to see one at a time.

    ``ir_emitter_power``: radiance x m^2 the camera's IR emitter gives a white surface facing it
    (1.0 = full scale at 1 m; 80 makes a 0.25-reflectance road 10 m ahead of a 4 m pole read
    ~60 DN and a walker there ~170 DN).
    """

    ir_emitter_power: float = 80.0
    motion_blur: bool = True
    lamp_light: bool = True
    branch_sway: bool = True

    def __post_init__(self) -> None:
        power = self.ir_emitter_power
        if isinstance(power, bool) or not isinstance(power, int | float) or not 0.0 <= power <= 1e6:
            raise ValueError(f"RenderOptions.ir_emitter_power: must be a number in [0, 1e6], got {power!r}")
        for name in ("motion_blur", "lamp_light", "branch_sway"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"RenderOptions.{name}: must be true or false, got {getattr(self, name)!r}")


@dataclass(frozen=True)
class TruthObject:
    """One agent visible in a frame. Box in px, OpenCV boundingRect convention."""

    object_id: int
    cls: str
    x: int
    y: int
    w: int
    h: int
    touches_border: bool
    fully_visible: bool
    distance_m: float


@dataclass(frozen=True)
class RenderedFrame:
    image: np.ndarray  # uint8 (H, W)
    truth: tuple[TruthObject, ...]


class CameraRenderer:
    """Renders one camera's near-infrared frames; the static scene is prepared once here.

    Parameters
    ----------
    camera : detector.camera.CameraModel
        Intrinsics, position (m, the world frame of docs/design/architecture.md), height (m),
        heading and tilt (deg) of the camera.
    street : citysim.world.street.Street
        Lanes, sidewalks, lamps and scenery, m.
    environment : citysim.config.scenario.EnvironmentSpec
        The night: ambient light, weather, wind (m/s), exposure (ms), lens distortion, insects.
    rng : numpy.random.Generator
        Draws the scene's texture, sensor noise and rain (same seed, same frames).
    options : RenderOptions
        Switches of the renderer itself (IR emitter power, motion blur, lamp light, branch sway).
    """

    def __init__(
        self,
        camera: CameraModel,
        street: Street,
        environment: EnvironmentSpec,
        rng: np.random.Generator,
        options: RenderOptions = RenderOptions(),
    ) -> None:
        self.camera = camera
        self.street = street
        self.environment = environment
        self.options = options
        self.rng = rng
        env, opt = environment, options
        self.ambient_light = env.ambient_light
        self.rain_drops_per_frame = env.rain_drops_per_frame if env.weather == "rain" else 0
        self.canvas = build_canvas(camera, env.lens_distortion)
        self.lamp_positions_m = np.array(
            [[lamp.x_m, lamp.y_m, lamp.pole_height_m] for lamp in street.lamps], dtype=np.float64
        ).reshape(-1, 3)
        shading = ShadingInputs(self.ambient_light, opt.ir_emitter_power, self.lamp_positions_m)
        self.scene = StaticScene(self.canvas, street, shading, rng, opt.branch_sway, env.wind_mps)
        self._heads_in_view = self.canvas.spheres_in_view(
            self.lamp_positions_m, np.full(len(self.lamp_positions_m), 1.0)
        )
        prepare_models()
        self.painter = AgentPainter(self.canvas, env.exposure_ms, opt.motion_blur)
        self.output = FrameOutput(self.canvas)
        self._shown_at = self.canvas.frame_to_canvas_index()
        no_uv = np.zeros((0, 0), np.float32)
        self._frame_uv = self.canvas.frame_uv or (no_uv, no_uv)
        # built in registry order: effects draw their seeds from rng in that order
        built = (effect.build(env, self.canvas, rng) for effect in EFFECTS.values())
        self.effects = [effect for effect in built if effect is not None]
        self._frame_seed = int(rng.integers(2**63))
        pole, heading = camera.position_m, camera.heading_unit
        self._forward_axis = (float(pole[0]), float(pole[1]), float(heading[0]), float(heading[1]))

    def _levels(self, lamp_levels: Sequence[float]) -> np.ndarray:
        levels = np.asarray(lamp_levels, dtype=np.float64).reshape(-1)
        if len(levels) != len(self.street.lamps):
            raise ValueError(
                f"lamp_levels: need one level per street lamp ({len(self.street.lamps)}), got {len(levels)}"
            )
        if not self.options.lamp_light:
            return np.zeros_like(levels)
        levels = np.where(levels == levels, levels, 0.0)  # NaN: off
        return np.minimum(np.maximum(levels, 0.0), 1.0)

    def _in_view(self, agents: list[AgentState]) -> tuple[list[AgentState], list[AgentState]]:
        """The agents that may show in this camera (a street holds many more), and the lit
        agents whose light spot may show. Every agent's class is checked, seen or not."""
        if not agents:
            return [], []
        for a in agents:
            model_of(a)  # ValueError naming the class if it cannot be rendered
        pos = np.array(
            [[a.x_m, a.y_m, 0.5 * a.height_m, a.length_m, a.width_m, a.height_m] for a in agents]
        )
        radius = 0.5 * np.linalg.norm(pos[:, 3:], axis=1) + 1.0  # + members' spread, walkers' limbs
        seen = self.canvas.spheres_in_view(pos[:, :3], radius)
        lit = [a for a in agents if shows_light(a)]
        spots = []
        if lit:
            shown = self.canvas.spheres_in_view(*spot_reach(lit))
            spots = [a for a, ok in zip(lit, shown, strict=True) if ok]
        return [a for a, ok in zip(agents, seen, strict=True) if ok], spots

    def render(
        self,
        t_s: float,
        agents: Sequence[AgentState],
        lamp_levels: Sequence[float],
        frame_index: int | None = None,
    ) -> RenderedFrame:
        """The frame at time ``t_s`` with ``agents`` and each street lamp at its level.

        Sensor noise and rain come from the renderer's generator, in call order;
        with ``frame_index`` (>= 0) they are a function of that index and the
        renderer's seed instead, so a frame is the same whichever frames were
        rendered before it (cameras that skip idle frames stay comparable).

        Parameters
        ----------
        t_s : float
            Simulated time, s from the start of the night.
        agents : sequence of citysim.world.agents.AgentState
            Every agent of the street (positions m, headings rad); those out of view are skipped.
        lamp_levels : sequence of float
            Each street lamp's light level, 0 (off) .. 1 (full), in lamp order.
        frame_index : int, optional
            The camera's frame number (>= 0) that seeds this frame's noise and rain.

        Returns
        -------
        RenderedFrame
            ``image``, the uint8 (H, W) frame, and ``truth``, the objects in view with their
            boxes (OpenCV ``(x, y, w, h)`` px), visibility and distance (m).
        """
        ambient, emitter = self.ambient_light, self.options.ir_emitter_power
        if frame_index is not None and frame_index < 0:
            raise ValueError(f"frame_index: must be >= 0, got {frame_index}")
        levels = self._levels(lamp_levels)
        agents, lit = self._in_view(list(agents))
        if self._still_view(levels, t_s):  # rebuilt, crowns at time t included
            depth = self.scene.depth
        else:
            depth, redrawn = self.scene.sway(t_s, levels, self.output.still, relit=False)
            self.output.still_changed(redrawn)
        img = self.output.work
        boxes: list[tuple[int, int, int, int]] = []

        spot_gain = 1.0 - ambient
        if spot_gain > 0.0 and lit:
            boxes += add_ground_spots(self.scene, img, lit, spot_gain)

        on = levels > 0.0
        lighting = AgentLighting.of(emitter, ambient, self.lamp_positions_m[on], levels[on])
        labels = np.zeros(self.canvas.shape, np.uint8 if len(agents) < 255 else np.uint16)
        drawn, drawn_boxes = self.painter.paint(
            agents, lighting, img, depth, self.scene.nearest_occluder, labels
        )
        boxes += drawn_boxes

        wet = self.rain_drops_per_frame > 0
        pts, power, size = agent_glare_sources(self.canvas, agents, ambient)
        boxes += glare(self.canvas, img, depth, pts, power, size, wet)
        exposure_s = self.environment.exposure_ms / 1000.0
        effect_frame = EffectFrame(self.canvas, img, t_s, exposure_s, emitter, ambient, self.rng,
                                   self._frame_seed, frame_index)  # fmt: skip
        for effect in self.effects:
            boxes += effect.draw(effect_frame)
        frame = self.output.finish(boxes)
        for effect in self.effects:
            frame = effect.filter(frame, effect_frame)
        truth = self._truth(agents, drawn, labels) if drawn else ()
        return RenderedFrame(frame, truth)

    def _still_view(self, levels: np.ndarray, t_s: float) -> bool:
        """Bring the cached frame of the still view (lit background, crowns, lamp heads'
        glare) up to the lamps' levels; whether it was rebuilt (crowns drawn at time t)."""
        key, lit = self.scene.lit(levels)
        heads = (levels > 0.0) & self._heads_in_view
        key = (key, tuple(levels[heads].tolist()))
        if key == self.output.key:
            return False
        layer = np.zeros(self.canvas.shape, np.float32)
        glare_boxes = glare(
            self.canvas,
            layer,
            self.scene.occluder_depth,
            self.lamp_positions_m[heads],
            LAMP_HEAD_GLARE * levels[heads],
            np.full(int(heads.sum()), LAMP_HEAD_SIZE_M),
            self.rain_drops_per_frame > 0,
        )
        self.output.set_background(
            key,
            lit,
            layer,
            np.array(glare_boxes).reshape(-1, 4),
            lambda still: self.scene.sway(t_s, levels, still, relit=True),
        )
        return True

    def _truth(
        self,
        agents: list[AgentState],
        drawn: list[DrawnAgent],
        labels: np.ndarray,
    ) -> tuple[TruthObject, ...]:
        fw, fh = self.camera.width_px, self.camera.height_px
        drawn = sorted(drawn, key=lambda d: d.index)
        rois = np.array([d.roi for d in drawn], np.int64)
        # visible canvas pixels and the frame box of each agent's labelled pixels
        stats = np.empty((len(drawn), 5), np.int64)
        wanted = np.array([d.label for d in drawn], np.int64)
        label_stats(labels, *self._frame_uv, self._shown_at, wanted, rois, stats)
        px, py, hx, hy = self._forward_axis
        out = []
        for d, (visible_px, x, y, x1, y1) in zip(drawn, stats.tolist(), strict=True):
            if visible_px == 0 or x1 <= x:
                continue
            bw, bh = x1 - x, y1 - y
            touches = x == 0 or y == 0 or x + bw == fw or y + bh == fh
            hidden = 1.0 - min(visible_px / d.silhouette_px, 1.0)
            agent = agents[d.index]
            out.append(
                TruthObject(
                    agent.object_id,
                    agent.cls,
                    int(x),
                    int(y),
                    int(bw),
                    int(bh),
                    bool(touches),
                    bool(not touches and hidden <= MAX_HIDDEN_FRACTION),
                    # the forward ground distance of the footprint centre (eq. 4's quantity)
                    float((agent.x_m - px) * hx + (agent.y_m - py) * hy),
                )
            )
        return tuple(out)
