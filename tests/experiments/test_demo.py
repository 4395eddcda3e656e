"""make demo's options: bad values stop it before any simulation, naming the option, exit code 2."""

import pytest

from experiments import demo
from experiments.idle_cores import Finished


class _RecordedBehind:
    """Stands in for the commands beside the night: records them, runs none."""

    def __init__(self, steps, calls):
        self.steps, self.reaped_cpu_s = steps, 0.0
        calls.extend(argv for _, argv, _ in steps)

    def finished(self):
        return iter([Finished(title, 0, "(output)", 1.0, 1.0) for title, _, _ in self.steps])

    def stop(self):
        pass


@pytest.mark.parametrize(("argv", "option"), [
    (["--night-s", "0"], "--night-s"), (["--night-s", "28801"], "--night-s"),
    (["--check-s", "0"], "--check-s"), (["--night-s", "120", "--check-s", "121"], "--check-s"),
    (["--year-sample-s", "10"], "--year-sample-s"), (["--controllers", "pir,detectr"], "--controllers"),
])  # fmt: skip
def test_bad_demo_options_exit_2_before_any_simulation(argv, option, capsys, monkeypatch):
    monkeypatch.setattr(demo, "citysim", lambda *a: pytest.fail("simulated although an option was bad"))
    monkeypatch.setattr(demo, "start_behind", lambda *a: pytest.fail("started the check although an option was bad"))
    with pytest.raises(SystemExit) as stop:
        demo.main(argv)
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert option in err and ("must be in" in err or "did you mean detector" in err)


def test_the_demo_runs_the_three_commands_and_says_where_the_reports_are(tmp_path, capsys, monkeypatch):
    calls = []
    monkeypatch.setattr(demo, "citysim", lambda argv: calls.append(argv) or 0)
    started = []
    monkeypatch.setattr(demo, "start_behind", lambda steps: started.append(steps) or _RecordedBehind(steps, calls))
    assert demo.main(["--out", str(tmp_path)]) == 0
    # the check and the year are started first, beside the night (the night is the foreground):
    # the check at the night's priority, the year at the lowest
    assert [c[0] for c in calls] == ["validate", "year", "run"]
    assert [nice for _, _, nice in started[0]] == [0, demo.LOWEST_PRIORITY_NICE]
    calls = [calls[2], calls[0], calls[1]]
    assert calls[0][calls[0].index("--fidelity") + 1] == "fast"
    assert calls[0][calls[0].index("--duration") + 1] == "28800"  # the whole night by default
    # the night's controllers are the year's: its table and the year's answer the same question
    night_controllers = calls[0][calls[0].index("--controllers") + 1]
    assert night_controllers == calls[2][calls[2].index("--controllers") + 1]
    assert calls[1][calls[1].index("--duration") + 1] == f"{demo.CHECK_S:g}"
    # the year sets the camera controller a planner would install beside the bound and the conventional schemes
    year_controllers = calls[2][calls[2].index("--controllers") + 1].split(",")
    assert {"oracle", "pir", "schedule", "detector_located"} <= set(year_controllers)
    out = capsys.readouterr().out
    assert str(tmp_path / "night" / "report.html") in out and str(tmp_path / "year" / "report.html") in out


def test_all_controllers_runs_the_scenarios_own_list(tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(demo, "citysim", lambda argv: calls.append(argv) or 0)
    monkeypatch.setattr(demo, "start_behind", lambda steps: _RecordedBehind(steps, []))
    assert demo.main(["--out", str(tmp_path), "--controllers", "all", "--night-s", "600"]) == 0
    assert "--controllers" not in calls[0]  # citysim run's default: every controller of the scenario
    assert calls[0][calls[0].index("--duration") + 1] == "600"


def test_a_failed_night_stops_the_commands_behind_it(tmp_path, monkeypatch):
    stopped = []
    behind = _RecordedBehind([("2. the check", ["validate"], 0)], [])
    behind.stop = lambda: stopped.append(True)
    monkeypatch.setattr(demo, "citysim", lambda argv: 3)
    monkeypatch.setattr(demo, "start_behind", lambda steps: behind)
    with pytest.raises(SystemExit) as stop:
        demo.main(["--out", str(tmp_path)])
    assert stop.value.code == 3 and stopped == [True]
