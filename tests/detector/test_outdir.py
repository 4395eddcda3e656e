"""Staging folders of output folders: removed when their job dies, whatever killed it."""

import os
import subprocess
import sys

from detector.outdir import remove_orphan_stages, staged_output


def dead_pid() -> int:
    """The id of a process that has ended (a finished child, reaped)."""
    child = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    return int(child.stdout)


def test_stage_of_a_killed_job_is_removed_by_the_next_one(tmp_path):
    out = tmp_path / "run"
    orphan = tmp_path / f".run.partial-{dead_pid()}-abc123"
    orphan.mkdir()
    (orphan / "summary.json").write_text("{}")
    alive = tmp_path / f".run.partial-{os.getpid()}-def456"  # a job still running beside it
    alive.mkdir()
    unnamed = tmp_path / ".run.partial-xyz"  # no process id in the name: not ours to judge
    unnamed.mkdir()
    other = tmp_path / f".other.partial-{dead_pid()}-abc"  # another output's stage
    other.mkdir()
    with staged_output(out) as stage:
        (stage / "summary.json").write_text("{}")
        assert not orphan.exists()
        assert alive.exists() and unnamed.exists() and other.exists()
    assert (out / "summary.json").exists()
    assert not stage.exists()


def test_removing_orphans_says_which(tmp_path):
    out = tmp_path / "run"
    orphan = tmp_path / f".run.partial-{dead_pid()}-1"
    orphan.mkdir()
    assert remove_orphan_stages(out) == [orphan]
    assert remove_orphan_stages(out) == []
