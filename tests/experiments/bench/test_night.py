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
