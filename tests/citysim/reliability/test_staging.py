"""A run folder is complete or absent: built aside under its own name, renamed into place whole;
an earlier folder stays intact until then. The progress bar explains its unit and waits to guess."""

from __future__ import annotations

import os
import signal

import pytest

from citysim.sim.progress import UNIT, SimulatedTimeBar
from detector.outdir import Interrupted, staged_folder, stop_on_signals


def earlier(out):
    out.mkdir()
    (out / "summary.json").write_text("earlier")
    (out / "plots").mkdir()
    (out / "plots" / "old.png").write_text("old")


def test_the_new_folder_replaces_the_earlier_one_whole(tmp_path):
    out = tmp_path / "run"
    earlier(out)
    with staged_folder(out) as stage:
        assert stage.name == "run" and stage.parent.name.startswith(".run.partial-")  # the report names it so
        (stage / "summary.json").write_text("new")
        assert (out / "summary.json").read_text() == "earlier"  # intact while the new one is built
    assert (out / "summary.json").read_text() == "new"
    assert not (out / "plots").exists()  # nothing of the earlier folder mixed in
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


def test_a_failed_or_stopped_build_leaves_the_earlier_folder_and_no_stage(tmp_path):
    out = tmp_path / "run"
    earlier(out)
    with pytest.raises(RuntimeError), staged_folder(out) as stage:
        (stage / "summary.json").write_text("half")
        raise RuntimeError("plotting failed")
    with pytest.raises(Interrupted) as stopped, stop_on_signals():
        with staged_folder(out) as stage:
            (stage / "summary.json").write_text("half")
            os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C while the plots are drawn
            for _ in range(1000):  # the handler runs between bytecodes
                pass
    assert stopped.value.code == 130
    assert (out / "summary.json").read_text() == "earlier" and (out / "plots" / "old.png").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


def test_a_new_folder_and_the_parents_made_for_it_go_when_stopped(tmp_path):
    with pytest.raises(KeyError), staged_folder(tmp_path / "a" / "b" / "run"):
        raise KeyError("x")
    assert list(tmp_path.iterdir()) == []


def test_a_second_signal_during_clean_up_is_ignored():
    with pytest.raises(Interrupted) as stopped, stop_on_signals():
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            for _ in range(1000):
                pass
        finally:
            os.kill(os.getpid(), signal.SIGINT)  # the group's copy, or an impatient second Ctrl-C
            for _ in range(1000):
                pass
    assert stopped.value.code == 143  # the first signal's, the clean-up not cut short
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_the_bar_names_its_unit_and_guesses_the_time_left_only_after_warm_up():
    bar = SimulatedTimeBar(1000.0, "tiny: 3 controllers", warmup_s=3600.0, disable=False, file=open(os.devnull, "w"))
    bar.update(100.0)
    assert UNIT in str(bar) and "time left after warm-up" in str(bar)
    bar.warmup_s = 0.0
    bar.update(100.0)
    assert "time left after warm-up" not in str(bar) and f"{UNIT}/s" in str(bar)
    bar.close()
