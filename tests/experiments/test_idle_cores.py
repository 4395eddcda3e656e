"""Commands behind the foreground: real processes, in order, at the lowest priority, output kept whole."""

import os
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


def test_stop_ends_the_running_commands():
    sleeps = [PY, "-c", "import time; time.sleep(3600)"]
    together = BehindTogether([("sleeps", sleeps, LOWEST_PRIORITY_NICE), ("sleeps too", sleeps, 0)])
    time.sleep(0.5)
    together.stop()
    outcomes = list(together.finished())  # an hour's sleep that ran on would hang here
    # a command that slept to its end exits 0; a stopped one does not
    assert [o.title for o in outcomes] == ["sleeps", "sleeps too"] and all(o.exit_code != 0 for o in outcomes)


# each command leaves its flag and waits (up to two minutes) for the other's: run one after the
# other, the first would wait alone and say so; no clock is compared, so a loaded machine passes too
RENDEZVOUS = """
import os, pathlib, sys, time
me, other = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
me.touch()
for _ in range(1200):
    if other.exists():
        print("met", "nice", os.nice(0))
        break
    time.sleep(0.1)
else:
    print("alone", "nice", os.nice(0))
"""


def test_together_the_commands_run_at_once_each_at_its_priority(tmp_path):
    a, b = str(tmp_path / "beside.flag"), str(tmp_path / "behind.flag")
    together = BehindTogether([("beside", [PY, "-c", RENDEZVOUS, a, b], 0),
                               ("behind", [PY, "-c", RENDEZVOUS, b, a], LOWEST_PRIORITY_NICE)])  # fmt: skip
    outcomes = list(together.finished())
    together.stop()
    assert [o.title for o in outcomes] == ["beside", "behind"]
    assert all(o.output.startswith("met") for o in outcomes), [o.output for o in outcomes]
    assert f"nice {os.nice(0)}" in outcomes[0].output  # beside: this process's own priority
    if at_priority(["x"])[0] != "x":
        assert f"nice {LOWEST_PRIORITY_NICE}" in outcomes[1].output
    assert together.reaped_cpu_s == sum(o.cpu_s for o in outcomes)
