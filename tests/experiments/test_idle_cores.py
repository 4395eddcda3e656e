"""Commands behind the foreground: real processes, in order, at the lowest priority, output kept whole."""

import sys
import time

from experiments.idle_cores import LOWEST_PRIORITY_NICE, BehindTogether, at_priority

PY = sys.executable


def test_commands_run_in_order_at_the_lowest_priority_with_their_output_and_cpu(tmp_path):
    busy = "import os, time\nt = time.process_time()\nwhile time.process_time() - t < 0.3: pass\nprint('nice', os.nice(0))"
    together = BehindTogether([("first", [PY, "-c", busy], LOWEST_PRIORITY_NICE),
                               ("second", [PY, "-c", "import sys; print('two'); print('err', file=sys.stderr)"],
                                LOWEST_PRIORITY_NICE)])  # fmt: skip
    outcomes = list(together.finished())
    together.stop()
    assert [o.title for o in outcomes] == ["first", "second"]
    assert all(o.exit_code == 0 for o in outcomes)
    if at_priority(["x"])[0] != "x":  # a POSIX nice was found: the command runs at nice 19
        assert f"nice {LOWEST_PRIORITY_NICE}" in outcomes[0].output
    assert outcomes[0].cpu_s >= 0.25  # the busy loop's 0.3 CPU-s, measured from the reaped process
    assert outcomes[1].output.split() == ["two", "err"]
    assert together.reaped_cpu_s >= outcomes[0].cpu_s


def test_a_failing_commands_exit_code_is_handed_over():
    outcomes = list(BehindTogether([("fails", [PY, "-c", "raise SystemExit(4)"], LOWEST_PRIORITY_NICE)]).finished())
    assert [(o.title, o.exit_code) for o in outcomes] == [("fails", 4)]


def test_stop_ends_the_running_commands_at_once():
    sleeps = [PY, "-c", "import time; time.sleep(60)"]
    together = BehindTogether([("sleeps", sleeps, LOWEST_PRIORITY_NICE), ("sleeps too", sleeps, 0)])
    time.sleep(0.5)
    t0 = time.perf_counter()
    together.stop()
    outcomes = list(together.finished())
    assert time.perf_counter() - t0 < 10
    assert [o.title for o in outcomes] == ["sleeps", "sleeps too"] and all(o.exit_code != 0 for o in outcomes)


def test_together_the_commands_run_at_once_each_at_its_priority():
    nice_after_1s = "import os, time; time.sleep(1.0); print('nice', os.nice(0))"
    together = BehindTogether([("beside", [PY, "-c", nice_after_1s], 0),
                               ("behind", [PY, "-c", nice_after_1s], LOWEST_PRIORITY_NICE)])  # fmt: skip
    t0 = time.perf_counter()
    outcomes = list(together.finished())
    wall_s = time.perf_counter() - t0
    together.stop()
    assert [o.title for o in outcomes] == ["beside", "behind"]
    assert wall_s < 1.9  # both slept at once, not one after the other (2 s)
    assert "nice 0" in outcomes[0].output
    if at_priority(["x"])[0] != "x":
        assert f"nice {LOWEST_PRIORITY_NICE}" in outcomes[1].output
    assert together.reaped_cpu_s == sum(o.cpu_s for o in outcomes)
