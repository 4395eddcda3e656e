"""The whole-night bench's options: bad values stop it before any work, with exit code 2."""

import pytest

from experiments.bench.figures import main
from experiments.bench.night import bench_night


@pytest.mark.parametrize("argv", [["--night-s", "600"], ["--night", "--night-s", "0"], ["--night", "--night-s", "30000"]])
def test_bad_night_options_exit_2_naming_the_option(argv, capsys):
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    assert "--night-s" in capsys.readouterr().err


def test_a_night_longer_than_the_night_is_refused_before_any_work():
    with pytest.raises(ValueError, match="duration_s"):
        bench_night(28_801.0)


def test_an_hour_of_the_night_runs_at_its_clock_hour_and_its_traffic():
    from citysim.config.scenario import load_scenario
    from experiments.bench.night import SUBURBAN, bench_night_fast, night_hour

    base = load_scenario(SUBURBAN)
    first, fourth = night_hour(base, 0, 600.0), night_hour(base, 3, 600.0)
    assert first.duration_s == fourth.duration_s == 600.0
    assert first.start_hour == base.start_hour and first.traffic.scripted == base.traffic.scripted
    assert fourth.start_hour == (base.start_hour + 3) % 24 and not fourth.traffic.scripted
    walkers = base.traffic.classes.pedestrian.hourly_profile
    assert tuple(fourth.traffic.classes.pedestrian.hourly_profile) == tuple(walkers[3:])
    with pytest.raises(ValueError, match="sample_s"):
        bench_night_fast(0.0)


@pytest.mark.parametrize("sample_s", [0.0, 3600.5])
def test_the_full_fidelity_hours_refuse_a_sample_outside_an_hour_before_any_work(sample_s):
    from experiments.bench.night import bench_night_full_hours

    with pytest.raises(ValueError, match="sample_s"):
        bench_night_full_hours(sample_s)
