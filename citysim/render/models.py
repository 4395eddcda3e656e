"""Agent states -> the detector's 3D models (``detector.train.shapes``), posed for drawing.

A registry maps each 3D model's name (a kind's ``AgentKind.shape``,
``citysim.config.kinds``) to how its model is keyed (everything but the pose)
and built at the origin. The renderer caches models by key, with
gait phases rounded to PHASE_STEPS per cycle, together with each part's
outline table (``citysim.render.outline``), and poses all agents in one
vectorised rotation + translation (``draw_models``); ``agent_shape`` gives one
agent's exact model at its pose (for tests and tools).

Conventions: world frame of docs/design/architecture.md (x, y ground, z up, m); ``heading_rad``
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
    Parts,
    Shape,
    animal_shape,
    box,
    cyclist_shape,
    group_shape,
    octagon,
    pedestrian_shape,
    slab,
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


#: E-scooter wheels: 8.5-10 inch tyres, m.
SCOOTER_WHEEL_RADIUS_M = 0.11
#: Top of the deck the rider stands on, its thickness and half width, m.
SCOOTER_DECK_TOP_M, SCOOTER_DECK_THICK_M, SCOOTER_DECK_HALF_W_M = 0.15, 0.05, 0.08


def e_scooter_shape(width_m: float, height_m: float, length_m: float) -> Shape:
    """A rider standing on an e-scooter, at the origin heading +x (11 parts): two small wheels,
    a low deck and a steering column (frame), the handlebar, and the rider, legs together on
    the deck, leaning a little forward, arms reaching forward and down to the handlebar.

    Rear tyre to front tyre = ``length_m``; handlebar width = ``width_m``; top of the rider's
    head = ``height_m``. Built from the parts of ``detector.train.shapes`` like the detector's own
    models; the rider has a walker's proportions (hips at 0.48, shoulders at 0.85 of the
    rider's height above the deck).
    """
    w, h = width_m, height_m
    parts = Parts()
    r = SCOOTER_WHEEL_RADIUS_M
    f_rear, f_front = -length_m / 2 + r, length_m / 2 - r
    parts.add(octagon(f_rear, 0.0, r, r), "wheel")
    parts.add(octagon(f_front, 0.0, r, r), "wheel")
    z_deck, half_deck = SCOOTER_DECK_TOP_M, SCOOTER_DECK_HALF_W_M
    deck_end = f_front - 0.12  # the deck stops short of the front wheel
    parts.add(
        box(f_rear, deck_end, -half_deck, half_deck, z_deck - SCOOTER_DECK_THICK_M, z_deck), "frame"
    )
    rider_h = h - z_deck
    z_bar = z_deck + 0.55 * rider_h  # just above the rider's hips
    f_bar = f_front - 0.08  # the column leans back from the front axle
    parts.add(slab((f_front, 0.0, r), (f_bar, 0.0, z_bar), 0.025, 0.025), "frame")
    parts.add(
        box(f_bar - 0.03, f_bar + 0.03, -w / 2, w / 2, z_bar - 0.03, z_bar + 0.03), "handlebar"
    )

    z_hip, z_shoulder, z_neck = (z_deck + k * rider_h for k in (0.48, 0.85, 0.87))
    f_feet = f_rear + 0.4 * (deck_end - f_rear)
    f_shoulder = f_feet + 0.08  # leaning toward the handlebar
    for side in (-1.0, 1.0):  # legs together: side by side, touching
        lat = side * 0.065
        parts.add(
            slab((f_feet, lat, z_deck), (f_feet, lat, z_hip + 0.02 * rider_h), 0.06, 0.06), "leg"
        )
    torso_d = min(0.36 * w, 0.22)
    parts.add(slab((f_feet, 0.0, z_hip), (f_shoulder, 0.0, z_neck), torso_d / 2, 0.32 * w), "torso")
    head_w = min(0.32 * w, 0.2)
    parts.add(box(f_shoulder - 0.1, f_shoulder + 0.1, -head_w / 2, head_w / 2, z_neck, h), "head")
    shoulder_w = 0.8 * w
    for side in (-1.0, 1.0):
        hand = (f_bar, side * (w / 2 - 0.06), z_bar)
        parts.add(
            slab(hand, (f_shoulder, side * (shoulder_w / 2 - 0.05), z_shoulder), 0.04, 0.04), "arm"
        )
    return parts.place(0.0, 0.0, 0.0)


#: Model name (``AgentKind.shape``) -> its 3D model (the detector's own shapes, and the
#: e-scooter built here from the detector's parts).
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
    # its wheels' turn does not show in a 320x240 frame: the phase is not part of the key
    "e_scooter": AgentModel(
        lambda a, phase: ("e_scooter", a.width_m, a.height_m, a.length_m),
        lambda k: e_scooter_shape(*k[1:]),
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
        ("e_scooter", 0.5, 1.8, 1.1),
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
