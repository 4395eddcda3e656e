"""Lamp-to-lamp messages: loss rate, latency floor, jitter, determinism, clear errors."""

from __future__ import annotations

import math

import numpy as np
import pytest
import simpy

from citysim.config.scenario import NetworkSpec
from citysim.control.network import Message, Network


def _run(spec: NetworkSpec, seed: int, n_sends: int = 2000, n_lamps: int = 5):
    """Lamp 0 notifies lamps 1 and 2 every 0.1 s; returns (network, delivered messages)."""
    env = simpy.Environment()
    net = Network(env, n_lamps, spec, np.random.default_rng(seed))
    received: list[Message] = []

    def sender():
        for k in range(n_sends):
            net.send(0, [1, 2], "approach", {"k": k})
            yield env.timeout(0.1)

    def listener(i):
        while True:
            received.append((yield net.inbox(i).get()))

    env.process(sender())
    for i in (1, 2):
        env.process(listener(i))
    env.run(until=n_sends * 0.1 + 1.0)
    return net, received


def test_loss_latency_and_jitter_statistics_over_many_messages():
    spec = NetworkSpec(latency_ms=20.0, jitter_ms=5.0, loss_probability=0.1)
    net, received = _run(spec, seed=11)
    copies = 2 * 2000
    assert net.stats.sent == copies
    assert net.stats.delivered + net.stats.lost == copies
    assert net.stats.delivered == len(received)
    # binomial: 4 sigma around the loss probability
    sigma = math.sqrt(0.1 * 0.9 / copies)
    assert abs(net.stats.loss_rate - 0.1) < 4 * sigma
    delays_s = np.array([m.t_delivered_s - m.t_sent_s for m in received])
    assert delays_s.min() >= 0.020 - 1e-12
    # latency + |N(0, 5 ms)| has mean 20 + 5 sqrt(2/pi) ms and spread of a half-normal
    assert delays_s.mean() == pytest.approx(0.020 + 0.005 * math.sqrt(2 / math.pi), abs=3e-4)
    assert delays_s.std() == pytest.approx(0.005 * math.sqrt(1 - 2 / math.pi), rel=0.1)
    assert net.stats.delay_min_s == pytest.approx(delays_s.min())
    assert net.stats.delay_max_s == pytest.approx(delays_s.max())
    assert {m.receiver for m in received} == {1, 2}
    assert all(m.sender == 0 and m.kind == "approach" for m in received)
    assert net.stats.by_kind == {"approach": copies}


def test_same_seed_same_deliveries_other_seed_other_deliveries():
    spec = NetworkSpec(loss_probability=0.2)
    _, a = _run(spec, seed=5, n_sends=200)
    _, b = _run(spec, seed=5, n_sends=200)
    _, c = _run(spec, seed=6, n_sends=200)

    def key(ms):
        return [(m.receiver, m.payload["k"], m.t_delivered_s) for m in ms]

    assert key(a) == key(b)
    assert key(a) != key(c)


def test_lossless_jitterless_link_delivers_everything_at_the_latency():
    net, received = _run(
        NetworkSpec(latency_ms=7.0, jitter_ms=0.0, loss_probability=0.0), seed=1, n_sends=50
    )
    assert net.stats.lost == 0 and len(received) == 100
    assert all(m.t_delivered_s - m.t_sent_s == pytest.approx(0.007) for m in received)


def test_a_dead_link_delivers_nothing():
    net, received = _run(NetworkSpec(loss_probability=1.0), seed=1, n_sends=50)
    assert received == [] and net.stats.lost == 100 and net.stats.in_flight == 0


@pytest.mark.parametrize(
    "field, value",
    [
        ("latency_ms", -1.0),
        ("jitter_ms", float("nan")),
        ("loss_probability", 1.5),
        ("repeat_s", -3.0),
    ],
)
def test_network_spec_errors_name_the_field(field, value):
    with pytest.raises(ValueError, match=rf"NetworkSpec[\s\S]*{field}"):
        NetworkSpec(**{field: value})


def test_send_errors_name_the_argument():
    net = Network(simpy.Environment(), 3, NetworkSpec(), np.random.default_rng(0))
    with pytest.raises(ValueError, match="sender"):
        net.send(3, [1], "x", {})
    with pytest.raises(ValueError, match="receivers"):
        net.send(0, [1, 7], "x", {})
    with pytest.raises(ValueError, match="cannot send to itself"):
        net.send(1, [1], "x", {})
    with pytest.raises(ValueError, match="kind"):
        net.send(0, [1], "", {})
    with pytest.raises(ValueError, match="Network.n_lamps"):
        Network(simpy.Environment(), 0, NetworkSpec(), np.random.default_rng(0))
