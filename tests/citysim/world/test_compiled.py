"""The compiled step against numpy's statement of the same rules (``numpy_statement.py``, the
behaviour as it ran before it was compiled, each body handed its move one by one): bit for bit on
random crowds and along a busy minute, the moves integrated by the world's pymunk bodies; the
world's bodies where its snapshots say; the pieces whose float operations are the same (wrap,
gait phase, leg ends) against numpy and Python; the overlap pre-check never lets a pair through
that numpy's check would have caught.
"""

import math
from dataclasses import fields
from pathlib import Path

import numpy as np
import pymunk
import pytest
import simpy

from citysim.config.scenario import load_scenario, override
from citysim.world import physics
from citysim.world.agents import AgentState, MemberState
from citysim.world.behaviour import move_agents
from citysim.world.bodies import Bodies
from citysim.world.geometry import Leg, Route, oriented_overlaps
from citysim.world.moves_compiled import (
    DS,
    N_WORK,
    NEW_TH,
    NEW_X,
    NEW_Y,
    STAGE,
    STEP_LAT,
    advance,
    propose,
)  # fmt: skip
from citysim.world.moves_compiled import wrap_angle as compiled_wrap
from citysim.world.rows import (
    LEG_LEN,
    LENGTH,
    N_COLUMNS,
    OMEGA,
    PAUSE,
    PHASE,
    REACH,
    SPEED,
    STILL,
    STRIDE,
    SX,
    SY,
    TARGET,
    TH,
    UNIT,
    VEL,
    WAITING,
    WIDTH,
    Mover,
    X,
    Y,
    new_row,
)  # fmt: skip
from citysim.world.street import build_street
from citysim.world.traffic import draw_arrival, start_traffic
from tests.citysim.world.numpy_statement import reference_move, wrap_angle

SUBURBAN = Path(__file__).resolve().parents[3] / "scenarios" / "suburban_night.yaml"
COLUMNS = {"x": X, "y": Y, "th": TH, "speed": SPEED, "target": TARGET, "waiting": WAITING}
PLANNED = {"ds": DS, "step_lat": STEP_LAT, "new_x": NEW_X, "new_y": NEW_Y, "new_th": NEW_TH, "stage": STAGE}


def bits(a) -> np.ndarray:
    """The IEEE bit patterns of a float array (so 0.0 and -0.0 differ, as NaN equals NaN)."""
    return np.ascontiguousarray(a, dtype=np.float64).view(np.int64)


def same_move(movers, state, vu, dt, t_s) -> tuple[bool, dict]:
    """Run the compiled step on copies of the arrays, its moves integrated by the world's bodies,
    and numpy's statement; (bit for bit the same, the statement's answer)."""
    want = reference_move(movers, state, vu, dt, t_s)
    got_state, got_vu = state.copy(), vu.copy()
    work = np.zeros((N_WORK, len(state)))
    blocked = move_agents(got_state, got_vu, dt, t_s, work)
    bodies = Bodies()
    for x, y, th, length, width in got_state[:, [X, Y, TH, LENGTH, WIDTH]].tolist():
        bodies.add((x, y, th), length, width)
    bodies.step(got_state, got_vu, dt)
    same = blocked == want["blocked"] and np.array_equal(bits(got_vu[VEL]), bits(want["velocity"]))
    for name, col in COLUMNS.items():
        same &= np.array_equal(bits(got_state[:, col]), bits(want[name]))
    for name, row in PLANNED.items():  # the plan itself: its last bits rarely reach the poses
        same &= np.array_equal(bits(work[row]), bits(want[name]))
    return bool(same), want


@pytest.fixture(scope="module")
def scenario():
    return load_scenario(SUBURBAN)


def _crowd(scenario, street, seed: int):
    """Up to a dozen agents of every kind drawn as traffic draws them, put down at random on a
    30 m stretch of their routes (walkers often at or before a crossing), a quarter of them on a
    leg at a random angle instead, with random speeds, targets, patience and pauses; some headings
    off their leg. (movers, state, vu, t_s)."""
    rng = np.random.default_rng(seed)
    specs = [s for s in scenario.traffic.classes.all() if s.rate_per_hour > 0]
    x0 = float(rng.uniform(20.0, street.length_m - 50.0))
    movers, rows, vus, t_s = [], [], [], float(rng.uniform(0.0, 100.0))
    for oid in range(int(rng.integers(1, 13))):
        spec = specs[int(rng.integers(len(specs)))]
        traits, route = draw_arrival(street, spec, rng)
        if rng.random() < 0.25:  # across everyone's way, at any angle
            start = (x0 + float(rng.uniform(0.0, 30.0)), float(rng.uniform(-6.0, 6.0)))
            angle = float(rng.uniform(0.0, 2.0 * math.pi))
            end = (start[0] + 20.0 * math.cos(angle), start[1] + 20.0 * math.sin(angle))
            route = Route((Leg(start, end, (-1.5, 1.5), (-0.2, 0.2), 0.0),), "skew")
        mover = Mover(oid, traits, route.legs)
        mover.leg_i = int(rng.integers(len(route.legs)))
        leg = mover.leg
        if route.entry_key == "skew":
            s_lo, s_hi = 0.0, leg.length_m
        elif len(route.legs) == 1:  # a whole-street leg: onto the stretch
            s_lo = abs(x0 - leg.start_xy_m[0])
            s_hi = s_lo + 30.0
        else:  # anywhere on its leg, or at its start, or within 3 m of its end
            s_lo, s_hi = [(0.0, leg.length_m), (0.0, 0.3), (leg.length_m - 3.0, leg.length_m)][int(rng.integers(3))]
        s = float(rng.uniform(max(s_lo, 0.0), min(s_hi, leg.length_m - 1e-3)))
        offset = float(rng.uniform(*leg.band_m))
        x, y = leg.point(s, offset)
        heading = leg.heading_rad + float(rng.normal(0.0, 0.3) if rng.random() < 0.3 else 0.0)
        row, vu = new_row(mover, (x, y, heading), float(rng.uniform(0.0, 1.2) * traits.desired_speed_mps))
        row[0, TARGET] = float(rng.uniform(*leg.band_m)) if rng.random() < 0.5 else leg.pref_m
        row[0, STILL] = float(rng.choice([0.0, rng.uniform(0.0, 10.0)]))
        row[0, PAUSE] = t_s + float(rng.uniform(-2.0, 2.0)) if mover.pauses else -1.0
        vu[VEL, 0] = row[0, SPEED] * np.array(leg.unit) + rng.normal(0.0, 0.1, 2)
        movers.append(mover)
        rows.append(row)
        vus.append(vu)
    return movers, np.concatenate(rows), np.concatenate(vus, axis=1), t_s


@pytest.mark.parametrize("dt", [1 / 30, 0.1, 0.25])
def test_step_is_numpys_on_random_crowds(scenario, dt):
    street = build_street(scenario)
    seen = {"waits": 0, "blocked": 0, "aside": 0}
    for seed in range(150):
        movers, state, vu, t_s = _crowd(scenario, street, seed)
        same, want = same_move(movers, state, vu, dt, t_s)
        assert same, seed
        seen["waits"] += int(want["waiting"].sum() > 0)
        seen["blocked"] += want["blocked"]
        seen["aside"] += int(np.any(want["target"] != state[:, TARGET]))
    # the crowds did exercise giving way, cutting moves back and choosing offsets
    assert seen["waits"] and seen["blocked"] and seen["aside"] > 20, seen


@pytest.fixture(scope="module")
def busy_minutes(scenario):
    """Two minutes of five times the suburban traffic at 30 Hz, each step's move checked against
    numpy's statement on copies of the arrays; the footprints checked for overlaps."""
    busy = override(scenario, {f"traffic.classes.{k}.rate_per_hour": getattr(scenario.traffic.classes, k).rate_per_hour * 5
                               for k in ("pedestrian", "group", "cyclist", "vehicle", "animal")})  # fmt: skip
    rng = np.random.default_rng(busy.seed)
    world = physics.World(build_street(busy), rng.spawn(1)[0])
    env = simpy.Environment()
    start_traffic(env, world, busy, rng)
    move, advance_ = physics._compiled()
    out = {"steps": 0, "differ": 0, "overlapping": 0, "moves": 0, "bodies_off": 0, "reordered": 0}

    def checked(state, vu, dt, t_s):
        same, _ = same_move(world._movers, state, vu, dt, t_s)
        out["differ"] += not same
        out["moves"] += len(state)
        return move(state, vu, dt, t_s)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(physics, "_compiled", lambda: (checked, advance_))
        for k in range(30 * 120):
            env.run(until=(k + 1) / 30)
            world.step(1 / 30)
            states = world.states()
            out["steps"] += 1
            out["bodies_off"] += not bodies_where_snapshots_say(world, states)
            rows = world._bodies._rows
            out["reordered"] += rows is not None and not np.array_equal(rows, np.arange(len(rows)))
            if len(states) > 1:
                xy = np.array([(a.x_m, a.y_m) for a in states])
                th = np.array([a.heading_rad for a in states])
                ln, wd = np.array([a.length_m for a in states]), np.array([a.width_m for a in states])
                out["overlapping"] += bool(oriented_overlaps(xy, th, ln, wd, margin_m=-1e-6).any())
    return out


def test_busy_minutes_move_as_numpy_did(busy_minutes):
    assert busy_minutes["moves"] > 30 * 120 * 5  # a crowded street
    assert busy_minutes["differ"] == 0


def test_busy_minutes_at_30_hz_never_overlaps(busy_minutes):
    assert busy_minutes["overlapping"] == 0


def bodies_where_snapshots_say(world, states) -> bool:
    """Each agent in the street is a kinematic body in the world's space with its box shape, at
    the pose of its snapshot and moving at its speed, bit for bit; the space holds nothing else."""
    bodies = world._bodies.bodies
    if set(world.space.bodies) != set(bodies) or not len(world.space.shapes) == len(bodies) == len(states):
        return False
    omega = world._state[:, OMEGA].tolist()
    for s, body, w in zip(states, bodies, omega, strict=True):
        (shape,) = body.shapes
        corners = {(abs(v.x), abs(v.y)) for v in shape.get_vertices()}
        pose = [*body.position, (body.angle + math.pi) % (2.0 * math.pi) - math.pi]
        if (
            body.body_type != pymunk.Body.KINEMATIC
            or bits(pose).tolist() != bits([s.x_m, s.y_m, s.heading_rad]).tolist()
            or math.hypot(*body.velocity) != s.speed_mps
            or body.angular_velocity != w
            or corners != {(s.length_m / 2, s.width_m / 2)}
        ):
            return False
    return True


def test_busy_minutes_bodies_are_where_the_snapshots_say(busy_minutes):
    """The moves reach the pymunk bodies and the bodies' poses the rows, also after others left
    (the space then orders its bodies otherwise than the rows)."""
    assert busy_minutes["bodies_off"] == 0
    assert busy_minutes["reordered"] > 100


def test_wrap_gait_and_leg_end_are_numpys_and_pythons():
    rng = np.random.default_rng(3)
    a = np.concatenate([rng.uniform(-20, 20, 5000), np.arange(-8, 9) * math.pi, [0.0, -0.0, 1e-300]])
    assert bits([compiled_wrap(v) for v in a]).tolist() == bits(wrap_angle(a)).tolist()
    n, dt, t_s = 300, 1 / 30, 12.0
    state, vu = np.zeros((n, N_COLUMNS)), np.zeros((2, n, 2))
    state[:, PHASE], state[:, STRIDE] = rng.uniform(0, 2 * math.pi, n), rng.uniform(0.5, 2.0, n)
    state[:, X], state[:, SX], state[:, LEG_LEN] = rng.uniform(0, 50, n), rng.uniform(-5, 5, n), 20.0
    state[:, Y], state[:, SY] = rng.uniform(-3, 3, n), rng.uniform(-3, 3, n)
    vu[UNIT, :, 0], vu[UNIT, :, 1] = 0.6, 0.8
    speed = rng.uniform(0, 3, n) * (rng.random(n) < 0.8)
    before = state.copy()
    done = np.zeros(n, dtype=bool)
    advance(state, vu, speed, dt, t_s, done)
    for i in range(n):
        phase = (before[i, PHASE] + 2.0 * math.pi * (speed[i] * dt) / before[i, STRIDE]) % (2.0 * math.pi)
        assert state[i, PHASE] == phase and math.copysign(1, state[i, PHASE]) == math.copysign(1, phase)
        assert state[i, STILL] == (dt if speed[i] < 0.05 else 0.0)
        along = (before[i, X] - before[i, SX]) * 0.6 + (before[i, Y] - before[i, SY]) * 0.8
        assert done[i] == (not along < 20.0)


def test_overlap_precheck_never_misses_a_pair_numpy_would_check():
    rng = np.random.default_rng(11)
    state, vu = np.zeros((2, N_COLUMNS)), np.zeros((2, 2, 2))
    work = np.zeros((N_WORK, 2))
    vu[UNIT, :, 0] = 1.0
    missed = checked = 0
    for _ in range(20000):
        reach = rng.uniform(0.1, 3.0, 2)
        state[:, REACH] = reach
        angle, r = rng.uniform(0, 2 * math.pi), (reach[0] + reach[1]) * (1 + rng.normal(0, 1e-15) * rng.choice([0, 1, 1e6]))
        state[0, X], state[0, Y] = rng.uniform(-10, 400), rng.uniform(-10, 10)
        state[1, X], state[1, Y] = state[0, X] + r * math.cos(angle), state[0, Y] + r * math.sin(angle)
        work[DS], work[STEP_LAT], work[STAGE] = 0.0, 0.0, 0.0
        near = propose(state, vu, work, 1 / 30)
        d = work[[NEW_X, NEW_Y], 1] - work[[NEW_X, NEW_Y], 0]
        if np.hypot(d[0], d[1]) < reach[0] + reach[1]:
            checked += 1
            missed += not near
    assert checked > 1000 and missed == 0


def test_states_are_agent_states_as_their_constructor_makes_them(scenario):
    """``World.states`` builds its snapshots without the frozen dataclass's ``__init__``."""
    street = build_street(scenario)
    world = physics.World(street, np.random.default_rng(0))
    for seed in range(20):  # every kind, groups among them
        rng = np.random.default_rng(seed)
        for spec in scenario.traffic.classes.all():
            if spec.rate_per_hour > 0:
                world.spawn(*draw_arrival(street, spec, rng))
    for _ in range(30 * 20):
        world.step(1 / 30)
    states = world.states()
    assert len(states) > 10 and any(s.members for s in states)
    for s in states:
        made = AgentState(**{f.name: getattr(s, f.name) for f in fields(AgentState)})
        assert made == s and repr(made) == repr(s) and vars(made) == vars(s)
        for m in s.members:
            assert MemberState(**vars(m)) == m and list(vars(m)) == [f.name for f in fields(MemberState)]
        assert list(vars(s)) == [f.name for f in fields(AgentState)]
