"""Folders the command-line tests write into, or cannot write into."""

import os
import tempfile
from pathlib import Path

import pytest


def unwritable_folder(tmp_path: Path) -> Path:
    """A folder this process cannot write in: permission bits, or for root a read-only system folder."""
    if os.geteuid() != 0:
        locked = tmp_path / "locked"
        locked.mkdir(mode=0o500)
        return locked
    for candidate in (Path("/sys"), Path("/proc")):
        try:
            Path(tempfile.mkdtemp(dir=candidate)).rmdir()
        except OSError:
            return candidate
    pytest.skip("no folder this root process cannot write in")
