"""Agent states -> the detector's 3D models (``detector.shapes``), posed for drawing.

A registry maps ``AgentState.cls`` to how its model is keyed (everything but
the pose) and built at the origin. The renderer caches models by key, with
gait phases rounded to PHASE_STEPS per cycle, and poses all agents in one
vectorised rotation + translation; ``agent_shape`` gives one agent's exact
model at its pose (for tests and tools).

Conventions: world frame of DESIGN.md (x, y ground, z up, m); ``heading_rad``
counter-clockwise from +x; model dimensions as in ``detector.shapes``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from citysim.agents import AgentState
from detector.shapes import (
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
    """How one class becomes a ``detector.shapes`` model: ``key`` names the model of an agent
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


#: AgentState.cls -> its 3D model (the detector's own shapes).
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


def _model_of(agent: AgentState) -> AgentModel:
    model = AGENT_MODELS.get(agent.cls)
    if model is None:
        raise ValueError(
            f"AgentState {agent.object_id}: cls {agent.cls!r} cannot be rendered; valid: {sorted(AGENT_MODELS)}"
        )
    return model


@lru_cache(maxsize=8192)
def _model_at_origin(key: tuple) -> Shape:
    return AGENT_MODELS[key[0]].build(key)


def agent_shape(agent: AgentState, quantise_phase: bool = False) -> Shape:
    """The agent's 3D model at its pose (world frame). With ``quantise_phase`` the gait is the
    one the renderer draws (see PHASE_STEPS). ValueError naming the class if it is unknown."""
    key = _model_of(agent).key(agent, quantised_phase if quantise_phase else _exact)
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


def posed_models(agents: Sequence[AgentState]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """All agents' cached models placed at their poses in one go:
    (corners (sum P, K, 3) world, reflectances (sum P,), parts per agent (N,))."""
    locals_ = [_model_at_origin(_model_of(a).key(a, quantised_phase)) for a in agents]
    n_parts = np.array([m.n_parts for m in locals_])
    pose = np.array([[a.x_m, a.y_m, a.heading_rad] for a in agents])
    per_part = np.repeat(pose, n_parts, axis=0)
    corners = _place(
        np.concatenate([m.corners_m for m in locals_]),
        per_part[:, 0],
        per_part[:, 1],
        per_part[:, 2],
    )
    return corners, np.concatenate([m.ir_reflectance for m in locals_]), n_parts
