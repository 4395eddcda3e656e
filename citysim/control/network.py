"""Wireless links between lamps: latency, jitter and loss, on a simpy clock.

Lamps tell their neighbours that a target is coming. Each copy of a message
(one per receiver) is lost independently with ``loss_probability``; a copy
that survives arrives in the receiver's inbox (a ``simpy.Store``) after
``latency_ms + |N(0, jitter_ms)|``, so no copy ever beats the base latency.

Repeating is the sender's business: the paper's lamps repeat their neighbour
notifications every 3 s while the object is present, which is what makes a
lossy link usable. ``NetworkSpec.repeat_s`` (the scenario's ``network``) carries that period so every
controller reads the same number; ``Network`` sends each call once.

Times: simpy's clock in seconds; link parameters in milliseconds as named.
All randomness comes from the one ``numpy.random.Generator`` passed in; each
``send`` draws a fixed number of variates per receiver, so the same seed and
the same calls give the same deliveries bit for bit.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import simpy

from citysim.config.scenario import NetworkSpec


@dataclass(frozen=True)
class Message:
    """One notification. ``receiver`` and ``t_delivered_s`` are filled in on the delivered copy.

    ``payload`` is shared by all copies of one send: treat it as read-only.
    """

    sender: int
    t_sent_s: float
    kind: str
    payload: Mapping[str, Any]
    receiver: int = -1
    t_delivered_s: float = math.nan


@dataclass
class NetworkStats:
    """Running counts over message copies (one copy per receiver); delays in s."""

    sent: int = 0
    delivered: int = 0
    lost: int = 0
    delay_min_s: float = math.inf
    delay_max_s: float = 0.0
    by_kind: dict[str, int] = field(default_factory=dict)  # copies sent per message kind

    @property
    def in_flight(self) -> int:
        return self.sent - self.delivered - self.lost

    @property
    def loss_rate(self) -> float:
        decided = self.delivered + self.lost
        return self.lost / decided if decided else 0.0


class Network:
    """All links of one run. ``inbox(i)`` is lamp i's ``simpy.Store`` of delivered ``Message``s."""

    def __init__(
        self, env: simpy.Environment, n_lamps: int, spec: NetworkSpec, rng: np.random.Generator
    ) -> None:
        if isinstance(n_lamps, bool) or not isinstance(n_lamps, int) or n_lamps < 1:
            raise ValueError(f"Network.n_lamps must be an int >= 1, got {n_lamps!r}")
        if not isinstance(spec, NetworkSpec):
            raise ValueError(f"Network.spec must be a NetworkSpec, got {type(spec).__name__}")
        if not isinstance(rng, np.random.Generator):
            raise ValueError(
                f"Network.rng must be a numpy.random.Generator, got {type(rng).__name__}"
            )
        self.env = env
        self.n_lamps = n_lamps
        self.spec = spec
        self.rng = rng
        self.stats = NetworkStats()
        self._inboxes = [simpy.Store(env) for _ in range(n_lamps)]

    def inbox(self, lamp_index: int) -> simpy.Store:
        self._check_lamp("lamp_index", lamp_index)
        return self._inboxes[lamp_index]

    def _check_lamp(self, name: str, index: object) -> None:
        if (
            isinstance(index, bool)
            or not isinstance(index, int | np.integer)
            or not 0 <= index < self.n_lamps
        ):
            raise ValueError(
                f"Network.send {name}: lamp index must be in [0, {self.n_lamps}), got {index!r}"
            )

    def send(
        self, sender: int, receivers: Sequence[int], kind: str, payload: Mapping[str, Any]
    ) -> None:
        """Send one message from ``sender`` to each of ``receivers`` (not to itself)."""
        self._check_lamp("sender", sender)
        for r in receivers:
            self._check_lamp("receivers", r)
            if r == sender:
                raise ValueError(f"Network.send receivers: lamp {sender} cannot send to itself")
        if not isinstance(kind, str) or not kind:
            raise ValueError(f"Network.send kind must be a non-empty str, got {kind!r}")
        n = len(receivers)
        if n == 0:
            return
        lost = self.rng.random(n) < self.spec.loss_probability
        delays_s = (
            self.spec.latency_ms + np.abs(self.rng.normal(0.0, 1.0, n)) * self.spec.jitter_ms
        ) / 1e3
        message = Message(int(sender), float(self.env.now), kind, dict(payload))
        self.stats.sent += n
        self.stats.by_kind[kind] = self.stats.by_kind.get(kind, 0) + n
        for receiver, is_lost, delay_s in zip(receivers, lost, delays_s, strict=True):
            if is_lost:
                self.stats.lost += 1
                continue
            # a bare timeout with a callback: cheaper than a process per copy
            arrival = self.env.timeout(float(delay_s), value=(int(receiver), float(delay_s)))
            arrival.callbacks.append(lambda event, m=message: self._deliver(m, *event.value))

    def _deliver(self, message: Message, receiver: int, delay_s: float) -> None:
        stats = self.stats
        stats.delivered += 1
        stats.delay_min_s = min(stats.delay_min_s, delay_s)
        stats.delay_max_s = max(stats.delay_max_s, delay_s)
        self._inboxes[receiver].put(
            replace(message, receiver=receiver, t_delivered_s=float(self.env.now))
        )
