"""One writer per output folder: a lock file beside the folder, naming the process that holds it.

``output_lock(out)`` holds ``.NAME.lock`` beside the folder ``NAME`` (not inside it: the folder is
built aside and renamed into place) for as long as the job writes. The file carries the holder's
process id; the lock itself is the kernel's (``flock``), so it is released the moment its process
ends, however it ends: a lock left behind by a killed job is found free, taken over, and reported.
A second job on the same folder is refused at once with ``OutputLockedError`` naming the holder.
"""

from __future__ import annotations

import fcntl
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from detector.outdir import OutputDirError, check_writable


class OutputLockedError(OutputDirError):
    """Another running process writes the same output; the message names its process id."""


def lock_path(out_dir: str | Path) -> Path:
    """The lock file of the output ``out_dir``: hidden, beside it."""
    out = Path(out_dir)
    return out.parent / f".{out.name}.lock"


def _read_pid(fd: int) -> int | None:
    os.lseek(fd, 0, os.SEEK_SET)
    text = os.read(fd, 32).decode(errors="replace").strip()
    return int(text) if text.isdigit() else None


def _acquire(path: Path, out: Path, arg: str) -> int:
    """An open descriptor of ``path`` holding its exclusive lock; OutputLockedError if another
    process holds it."""
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _read_pid(fd)
            os.close(fd)
            who = f"process {holder}" if holder else "another process"
            raise OutputLockedError(f"{arg}: {out} is being written by {who} (lock file {path}); wait for it to "
                                    "finish or choose another folder") from None  # fmt: skip
        # the holder before us may have removed the file between our open and our lock: retry on the new one
        try:
            if os.fstat(fd).st_ino == os.stat(path).st_ino:
                return fd
        except FileNotFoundError:
            pass
        os.close(fd)


@contextmanager
def output_lock(out_dir: str | Path, arg: str = "--out") -> Iterator[int | None]:
    """Hold the lock of the output ``out_dir`` for the block; yields the process id of an earlier
    holder that died without removing its lock file (taken over), else None. The lock file, and
    any parent folder made for it that is still empty, are removed at the end.

    Raises OutputLockedError (exit 2 in the command-line tools) when a running process holds it,
    OutputDirError when no file can be made beside ``out_dir``."""
    out = Path(out_dir)
    check_writable(out.parent, arg)
    made = [p for p in (out.parent, *out.parent.parents) if not p.exists()]  # deepest first
    out.parent.mkdir(parents=True, exist_ok=True)
    path = lock_path(out)
    fd = _acquire(path, out, arg)
    try:
        previous = _read_pid(fd)
        os.ftruncate(fd, 0)
        os.lseek(fd, 0, os.SEEK_SET)
        os.write(fd, f"{os.getpid()}\n".encode())
        yield previous if previous not in (None, os.getpid()) else None
    finally:
        try:
            path.unlink()  # still ours: nobody else can hold it while we do
        except FileNotFoundError:
            pass
        os.close(fd)
        for folder in made:
            try:
                folder.rmdir()
            except OSError:
                break
