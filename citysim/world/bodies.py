"""The agents' pymunk bodies: the street's physics, kept in step with the world's rows.

Every agent is a *kinematic* pymunk body carrying a box shape (its ground footprint), added to
the world's ``pymunk.Space`` when it enters and removed when it leaves. Kinematic, not dynamic,
because the motion is prescribed by the behaviour model (``citysim.world.behaviour``): a
kinematic body follows the velocity it is given exactly, is never shoved off its sidewalk or lane
by a contact impulse, and costs the solver nothing (Chipmunk does not collide kinematic bodies
with each other). Each step the planned moves are handed to the bodies as velocity and angular
velocity, ``Space.step`` integrates them, and the new poses are read back into the rows
(``citysim.world.rows``) for the next step.

Both exchanges are one call each for all bodies (``pymunk.batch``, pymunk >= 6.7), through a
flat buffer filled and emptied by compiled loops (``citysim.world.moves_compiled``), instead of
four property calls per body. The space keeps its bodies in its own order (removing one moves
its last body into the gap), so ``Bodies`` keeps the row of each of the space's bodies, asked
again of the space (by the bodies' ids) after agents entered or left.

Conventions: world frame of docs/design/architecture.md, metres, seconds; angles rad CCW from +x.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterable

import numpy as np
import pymunk
from pymunk import batch

__all__ = ["Bodies"]

_VELOCITIES = batch.BodyFields.VELOCITY | batch.BodyFields.ANGULAR_VELOCITY
_POSES = batch.BodyFields.POSITION | batch.BodyFields.ANGLE


class Bodies:
    """The pymunk space and one kinematic body per row of the world's arrays, in the rows' order."""

    def __init__(self) -> None:
        self.space = pymunk.Space()
        self.bodies: list[pymunk.Body] = []  # in the rows' order
        self._ids: list[int] = []  # the bodies' ids, same order
        self._rows: np.ndarray | None = None  # the row of each of the space's bodies, in its order
        self._velocities = batch.Buffer()  # handed to the bodies: vx, vy, omega of each ...
        self._velocities_out = np.empty(0)  # ... from this array, in the space's order
        self._poses = batch.Buffer()  # read back: x, y, angle of each
        self._order = batch.Buffer()  # the bodies' ids in the space's order (pymunk never frees a
        # Buffer's arrays: the world keeps these three)

    def add(self, pose: tuple[float, float, float], length_m: float, width_m: float) -> None:
        """A new body at ``pose`` = (x, y, angle) with a ``length_m`` x ``width_m`` box, for a new
        last row."""
        body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        body.position = pose[:2]
        body.angle = pose[2]
        shape = pymunk.Poly.create_box(body, (length_m, width_m))
        self.space.add(body, shape)
        self.bodies.append(body)
        self._ids.append(body.id)
        self._rows = None

    def remove(self, rows: Iterable[int]) -> None:
        """Take the bodies of ``rows`` out of the space (in the rows' order), as the rows are dropped."""
        gone = set(rows)
        for i in sorted(gone):
            body = self.bodies[i]
            self.space.remove(*body.shapes, body)
        self.bodies = [b for i, b in enumerate(self.bodies) if i not in gone]
        self._ids = [b for i, b in enumerate(self._ids) if i not in gone]
        self._rows = None

    def step(self, state: np.ndarray, vu: np.ndarray, dt_s: float) -> None:
        """Hand each body its row's velocity and angular velocity (``rows.VEL``, ``rows.OMEGA``),
        step the space by ``dt_s`` and read the bodies' poses back into the rows (``X``, ``Y``,
        ``TH``)."""
        if not self.bodies:
            self.space.step(dt_s)
            return
        to_bodies, from_bodies = _kernels()
        if self._rows is None:
            self._index()
        to_bodies(state, vu, self._rows, self._velocities_out)
        batch.set_space_bodies(self.space, _VELOCITIES, self._velocities)
        self.space.step(dt_s)
        self._poses.clear()
        batch.get_space_bodies(self.space, _POSES, self._poses)
        from_bodies(np.frombuffer(self._poses.float_buf()), self._rows, state)

    def _index(self) -> None:
        """Ask the space for its bodies' order: the row of each, and a velocity buffer that size."""
        self._order.clear()
        batch.get_space_bodies(self.space, batch.BodyFields.BODY_ID, self._order)
        row_of = {body_id: i for i, body_id in enumerate(self._ids)}
        order = memoryview(self._order.int_buf()).cast("P").tolist()
        if len(order) != len(row_of):
            raise RuntimeError(f"the space holds {len(order)} bodies, the world {len(row_of)}")
        self._rows = np.array([row_of[body_id] for body_id in order], dtype=np.intp)
        self._velocities_out = np.empty(3 * len(order))
        self._velocities.set_float_buf(self._velocities_out)


@functools.cache
def _kernels() -> tuple[Callable, Callable]:
    """The compiled exchange (``moves_compiled.to_bodies``, ``from_bodies``), imported on the first
    step as the rest of the compiled step is (``physics._compiled``)."""
    from citysim.world.moves_compiled import from_bodies, to_bodies

    return to_bodies, from_bodies
