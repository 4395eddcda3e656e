"""Results folders: checked before any work, written all at once.

``check_output_dir`` refuses, before a job starts, an output folder it could not or should not
write: an existing file, a place the user cannot write to, or a folder holding anything but an
earlier output of the same kind (which the job may replace). ``staged_output`` writes files
into a hidden staging folder beside the destination and moves them into place only when the
whole job succeeded; on any error the staging folder, and any parent folder it had to create,
is removed and the destination is left as it was.

A job stopped from outside cleans up too: ``exit_on_terminate`` (the command-line entry points
call it) turns SIGTERM, what ``kill`` and job schedulers send, into the same exit Ctrl-C takes,
so the staging folder goes. A job killed outright (SIGKILL, a power cut) cannot clean up; its
staging folder names its process, and the next job writing beside it removes it once that
process is gone.
"""

from __future__ import annotations

import os
import shutil
import signal
import tempfile
import threading
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path


class OutputDirError(ValueError):
    """An output folder that cannot be used; the message names the argument and what is valid."""


def check_output_dir(out_dir: str | Path, kind: str, names: Sequence[str], arg: str = "--out") -> None:
    """Raise OutputDirError unless ``out_dir`` is new, empty or an earlier ``kind`` output.

    ``names``: the files and folders a ``kind`` output holds (a folder written "plots/"); a
    folder holding only these is an earlier output the job may replace. Creates nothing.
    """
    out = Path(out_dir)
    valid = f"valid: a new or empty folder, or an earlier {kind} folder ({', '.join(names)})"
    if out.exists() and not out.is_dir():
        raise OutputDirError(f"{arg}: {out} is a file, not a folder; {valid}")
    if out.is_dir():
        own = {n.rstrip("/") for n in names}
        foreign = sorted(p.name + ("/" if p.is_dir() else "") for p in out.iterdir() if p.name not in own)
        if foreign:
            shown = ", ".join(foreign[:4]) + (f" and {len(foreign) - 4} more" if len(foreign) > 4 else "")
            raise OutputDirError(f"{arg}: {out} holds files that are not from a {kind} ({shown}); {valid}")
    _check_writable(out, arg)


def check_output_file(path: str | Path, arg: str = "--out") -> None:
    """Raise OutputDirError unless a file can be written at ``path`` (new, or replacing a file)."""
    path = Path(path)
    if path.is_dir():
        raise OutputDirError(f"{arg}: {path} is a folder; valid: a file path, e.g. {path / 'model.joblib'}")
    _check_writable(path.parent, arg)


def _check_writable(out: Path, arg: str) -> None:
    """Can a folder be made in ``out`` (if it exists) or in its nearest existing ancestor?"""
    place = out.absolute()
    while not place.exists():
        place = place.parent
    if not place.is_dir():
        raise OutputDirError(f"{arg}: {out} cannot be created: {place} is a file; valid: a path of folders")
    # try it rather than trust permission bits: root ignores them, a read-only mount does not
    try:
        Path(tempfile.mkdtemp(prefix=".write-check-", dir=place)).rmdir()
    except OSError as exc:
        raise OutputDirError(f"{arg}: cannot write in {place} ({exc.strerror or exc}); "
                             "valid: a folder you can write to") from None


#: exit status of a process ended by SIGTERM (128 + the signal's number), as shells report it
TERMINATED_EXIT = 128 + signal.SIGTERM


#: set by the SIGTERM handler: its exception can be lost (below), the flag cannot
_terminated = threading.Event()


def _raise_exit(signum, frame) -> None:
    _terminated.set()
    raise SystemExit(TERMINATED_EXIT)


def raise_if_terminated() -> None:
    """Raise ``SystemExit(143)`` if SIGTERM arrived within ``exit_on_terminate``.

    The handler's own exception is lost when the signal lands inside a callback from C: Python
    prints it ("Exception ignored from callback") and goes on (seen: pymunk freeing a body
    through cffi during the world's step, and the run then finished and wrote its output). So
    the simulation loops call this once per simulated second, and ``staged_output`` before it
    moves anything into place."""
    if _terminated.is_set():
        raise SystemExit(TERMINATED_EXIT)


@contextmanager
def exit_on_terminate() -> Iterator[None]:
    """Within this block SIGTERM ends the process as an exception (``SystemExit(143)``), so
    ``finally`` blocks and ``staged_output`` clean up; the default action comes back after it.
    Only from the main thread and only over the default action: a program embedding the job
    keeps its own handler."""
    install = threading.current_thread() is threading.main_thread() and signal.getsignal(signal.SIGTERM) is signal.SIG_DFL
    if install:
        _terminated.clear()
        signal.signal(signal.SIGTERM, _raise_exit)
    try:
        yield
    finally:
        if install:
            signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _stage_prefix(out: Path) -> str:
    return f".{out.name}.partial-"


def _process_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)  # signal 0: only asks whether the process exists
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        return True
    return True


def remove_orphan_stages(out: Path) -> list[Path]:
    """Remove the staging folders beside ``out`` whose job's process no longer exists (a job killed
    outright); returns them. A stage whose name carries no process id is left alone."""
    removed = []
    prefix = _stage_prefix(out)
    for stage in out.parent.glob(f"{prefix}*"):
        pid = stage.name[len(prefix):].split("-", 1)[0]
        if stage.is_dir() and pid.isdigit() and not _process_alive(int(pid)):
            shutil.rmtree(stage, ignore_errors=True)
            removed.append(stage)
    return removed


@contextmanager
def staged_output(out_dir: str | Path) -> Iterator[Path]:
    """Yield a staging folder; on success move its files into ``out_dir``."""
    out = Path(out_dir)
    made = [p for p in (out.parent, *out.parent.parents) if not p.exists()]  # deepest first
    out.parent.mkdir(parents=True, exist_ok=True)
    remove_orphan_stages(out)
    stage = Path(tempfile.mkdtemp(prefix=f"{_stage_prefix(out)}{os.getpid()}-", dir=out.parent))
    try:
        yield stage
        raise_if_terminated()
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        for folder in made:  # the parents this job created, if still empty
            try:
                folder.rmdir()
            except OSError:
                break
        raise
    out.mkdir(parents=True, exist_ok=True)
    for item in stage.iterdir():
        target = out / item.name
        if target.is_dir() and not target.is_symlink():
            shutil.rmtree(target)
        item.replace(target)
    shutil.rmtree(stage, ignore_errors=True)
