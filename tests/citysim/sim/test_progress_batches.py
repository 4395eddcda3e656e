"""A worker's progress reaches the parent in few messages, and none of it is lost."""

import queue

from citysim.sim import compare


def test_progress_is_sent_at_most_every_quarter_second_and_adds_up(monkeypatch):
    clock = [0.0]
    monkeypatch.setattr(compare.time, "monotonic", lambda: clock[0])
    sent = queue.Queue()
    report = compare._Batched(sent)
    for _ in range(10_000):  # 10,000 steps of 0.05 sim s within 1 s of wall time
        report(0.05)
        clock[0] += 1e-4
    report.flush()
    parts = [sent.get() for _ in range(sent.qsize())]
    assert abs(sum(parts) - 500.0) < 1e-6  # every simulated second counted once
    # one put per 0.25 s of wall time (4 in the 1 s) and the final flush, not one per 5 sim s (100)
    assert len(parts) <= 6


def test_without_a_queue_nothing_is_sent_and_nothing_fails():
    report = compare._Batched(None)
    for _ in range(1000):
        report(1.0)
    report.flush()
    assert report.pending_s == 0.0
