"""Agent states -> the detector's 3D models (``detector.train.shapes``), posed for drawing.

A registry maps each 3D model's name (a kind's ``AgentKind.shape``,
``citysim.config.kinds``) to how its model is keyed (everything but the pose)
and built at the origin. The renderer caches models by key, with
gait phases rounded to PHASE_STEPS per cycle, together with each part's
outline table (``citysim.render.outline``), and poses all agents in one
vectorised rotation + translation (``draw_models``); ``agent_shape`` gives one
agent's exact model at its pose (for tests and tools).

Conventions: world frame of DESIGN.md (x, y ground, z up, m); ``heading_rad``
counter-clockwise from +x; model dimensions as in ``detector.train.shapes``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from citysim.config.kinds import AGENT_KINDS
from citysim.render.outline import KnownTopology, model_topology
from citysim.world.agents import AgentState
from detector.train.shapes import (
    Shape,
    animal_shape,
    cyclist_shape,
    group_shape,
    pedestrian_shape,
    vehicle_shape,
)

#: Gait phases are rounded to this many steps per cycle before a model is looked up in the
#: cache (0.2 rad: below what a 320x240 frame can show), so walkers reuse their models.
PHASE_STEPS = 32
_PHASE_STEP_RAD = 2.0 * math.pi / PHASE_STEPS


def quantised_phase(phase_rad: float) -> float:
    """The cached model's gait phase for ``phase_rad`` (nearest of PHASE_STEPS per cycle)."""
    return (round(phase_rad / _PHASE_STEP_RAD) % PHASE_STEPS) * _PHASE_STEP_RAD


def _exact(phase_rad: float) -> float:
    return phase_rad


PhaseMap = Callable[[float], float]


@dataclass(frozen=True)
class AgentModel:
    """How one class becomes a ``detector.train.shapes`` model: ``key`` names the model of an agent
    (everything but its pose; phases through the given map) and ``build`` makes it at the
    origin, heading +x."""

    key: Callable[[AgentState, PhaseMap], tuple]
    build: Callable[[tuple], Shape]


def _group_key(a: AgentState, phase: PhaseMap) -> tuple:
    if not a.members:
        raise ValueError(f"AgentState {a.object_id}: a 'group' needs members, got none")
    return (
        "group",
        tuple(
            (m.forward_m, m.left_m, m.width_m, m.height_m, m.length_m, phase(m.gait_phase_rad))
            for m in a.members
        ),
    )


#: Model name (``AgentKind.shape``) -> its 3D model (the detector's own shapes).
AGENT_MODELS: dict[str, AgentModel] = {
    "pedestrian": AgentModel(
        lambda a, phase: ("pedestrian", a.width_m, a.height_m, a.length_m, phase(a.gait_phase_rad)),
        lambda k: pedestrian_shape(0.0, 0.0, 0.0, *k[1:]),
    ),
    "group": AgentModel(_group_key, lambda k: group_shape(0.0, 0.0, 0.0, k[1])),
    "cyclist": AgentModel(
        lambda a, phase: ("cyclist", a.width_m, a.height_m, a.length_m, phase(a.gait_phase_rad)),
        lambda k: cyclist_shape(0.0, 0.0, 0.0, *k[1:]),
    ),
    "vehicle": AgentModel(
        lambda a, phase: ("vehicle", a.width_m, a.height_m, a.length_m),
        lambda k: vehicle_shape(0.0, 0.0, 0.0, *k[1:]),
    ),
    "animal": AgentModel(
        lambda a, phase: ("animal", a.width_m, a.height_m, a.length_m, phase(a.gait_phase_rad)),
        lambda k: animal_shape(0.0, 0.0, 0.0, *k[1:]),
    ),
}


def model_of(agent: AgentState) -> AgentModel:
    """The 3D model of the agent's kind; ValueError naming the class if it has none."""
    kind = AGENT_KINDS.get(agent.cls)
    model = None if kind is None else AGENT_MODELS.get(kind.shape)
    if model is None:
        valid = sorted(k.name for k in AGENT_KINDS.values() if k.shape in AGENT_MODELS)
        raise ValueError(
            f"AgentState {agent.object_id}: cls {agent.cls!r} cannot be rendered; valid: {valid}"
        )
    return model


@lru_cache(maxsize=8192)
def _model_at_origin(key: tuple) -> Shape:
    return AGENT_MODELS[key[0]].build(key)


def agent_shape(agent: AgentState, quantise_phase: bool = False) -> Shape:
    """The agent's 3D model at its pose (world frame). With ``quantise_phase`` the gait is the
    one the renderer draws (see PHASE_STEPS). ValueError naming the class if it is unknown."""
    key = model_of(agent).key(agent, quantised_phase if quantise_phase else _exact)
    local = _model_at_origin(key) if quantise_phase else AGENT_MODELS[key[0]].build(key)
    return Shape(
        _place(local.corners_m, agent.x_m, agent.y_m, agent.heading_rad),
        local.ir_reflectance,
        local.part_kind,
    )


def _place(
    corners_m: np.ndarray,
    x_m: np.ndarray | float,
    y_m: np.ndarray | float,
    heading_rad: np.ndarray | float,
) -> np.ndarray:
    """Rotate local (P, K, 3) corners by heading about z and move them to (x, y); the pose
    arguments are scalars or (P,) per part."""
    c = np.reshape(np.cos(heading_rad), (-1, 1))
    s = np.reshape(np.sin(heading_rad), (-1, 1))
    out = np.empty_like(corners_m)
    out[..., 0] = np.reshape(x_m, (-1, 1)) + c * corners_m[..., 0] - s * corners_m[..., 1]
    out[..., 1] = np.reshape(y_m, (-1, 1)) + s * corners_m[..., 0] + c * corners_m[..., 1]
    out[..., 2] = corners_m[..., 2]
    return out


@dataclass(frozen=True, eq=False)
class DrawModel:
    """One cached model at the origin, heading +x, ready for drawing.

    ``geometry`` (P, K + 1 + MAX_FACES, 3) stacks each part's K vertices, its
    centre (the vertices' mean) and its faces' outward unit normals (zero for
    unused faces), so that one rotation turns all into the camera frame.
    ``faces`` (P, 1 + MAX_FACES) holds each part's outline table row (-1: no
    table, take the hull; ``citysim.render.outline``) and each face's plane
    offset ``normal . point on the face`` (m; 1 for unused faces): a face looks
    at a camera at model-frame point c when ``normal . c > offset``.
    """

    geometry: np.ndarray
    faces: np.ndarray
    reflectance: np.ndarray  # (P,)

    @property
    def n_parts(self) -> int:
        return len(self.geometry)


#: (class, part kind) -> topologies parts of that kind had (a few): models of one class are
#: built alike, so building a model checks these instead of searching
_TOPOLOGY_CANDIDATES: dict[tuple[str, str], list] = {}
#: a model's key with its gait phases set to zero -> its parts' topologies, checked once: a
#: gait only swings limbs (sheared boxes stay boxes), so its other phases reuse them
_CHECKED_TOPOLOGY: dict[tuple, list] = {}
#: key -> model, in the order built; past MAX_CACHED_MODELS the oldest goes (agents come and go)
_DRAW_MODELS: dict[tuple, DrawModel] = {}
MAX_CACHED_MODELS = 4096


def _still(phase_rad: float) -> float:
    return 0.0


def _build_draw_model(key: tuple, still_key: tuple) -> DrawModel:
    shape = AGENT_MODELS[key[0]].build(key)
    corners = shape.corners_m
    known = _CHECKED_TOPOLOGY.get(still_key)
    if known is not None and len(known.rows) == len(corners):
        rows, normals, on_face = known.setup(corners)
    else:
        candidates = [_TOPOLOGY_CANDIDATES.setdefault((key[0], k), []) for k in shape.part_kind]
        rows, normals, on_face, found = model_topology(corners, candidates)
        if len(_CHECKED_TOPOLOGY) >= MAX_CACHED_MODELS:
            _CHECKED_TOPOLOGY.pop(next(iter(_CHECKED_TOPOLOGY)))
        _CHECKED_TOPOLOGY[still_key] = KnownTopology.of(found)
    geometry = np.concatenate([corners, corners.mean(axis=1, keepdims=True), normals], axis=1)
    on_plane = corners[np.arange(len(corners))[:, None], on_face]  # (P, F, 3)
    offsets = np.einsum("pfk,pfk->pf", normals, on_plane)
    offsets[~np.any(normals != 0.0, axis=2)] = 1.0  # unused faces never look at the camera
    faces = np.column_stack([rows, offsets])
    for arr in (geometry, faces):
        arr.flags.writeable = False
    return DrawModel(geometry, faces, np.asarray(shape.ir_reflectance, dtype=np.float64))


def prepare_models() -> None:
    """Work out the part topologies of every class once (a typical model each), so that the
    first frames need not: later models of a class only check them."""
    if _TOPOLOGY_CANDIDATES:
        return
    walker = (0.0, 0.0, 0.5, 1.75, 0.6, 1.0)
    typical = (
        ("pedestrian", 0.5, 1.75, 0.6, 1.0),
        ("group", (walker, (0.0, 0.8, 0.5, 1.7, 0.6, 2.0))),
        ("cyclist", 0.6, 1.8, 1.7, 1.0),
        ("vehicle", 1.8, 1.5, 4.4),
        ("animal", 0.3, 0.5, 0.8, 1.0),
    )
    for key in typical:
        if key[0] in AGENT_MODELS:
            _build_draw_model(key, key)


def draw_models(agents: Sequence[AgentState]) -> list[DrawModel]:
    """Each agent's cached model at the origin (gait phases rounded, see PHASE_STEPS);
    ValueError naming the class for an unknown one."""
    out = []
    for a in agents:
        maker = model_of(a)
        key = maker.key(a, quantised_phase)
        model = _DRAW_MODELS.get(key)
        if model is None:
            model = _build_draw_model(key, maker.key(a, _still))
            if len(_DRAW_MODELS) >= MAX_CACHED_MODELS:
                _DRAW_MODELS.pop(next(iter(_DRAW_MODELS)))
            _DRAW_MODELS[key] = model
        out.append(model)
    return out
