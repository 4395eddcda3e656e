"""Results folders: checked before any work, written all at once.

``check_output_dir`` refuses, before a job starts, an output folder it could not or should not
write: an existing file, a place the user cannot write to, or a folder holding anything but an
earlier output of the same kind (which the job may replace). ``staged_output`` writes files
into a hidden staging folder beside the destination and moves them into place only when the
whole job succeeded; on any error the staging folder, and any parent folder it had to create,
is removed and the destination is left as it was.

``staged_folder`` builds a whole output folder (plots and report included) under its own name in
a hidden staging folder and renames it into place at the end, an earlier folder of the same name
staying intact until then: the folder is complete or absent.

A job stopped from outside cleans up too: ``stop_on_signals`` (``citysim``) and
``exit_on_terminate`` (SIGTERM alone) turn Ctrl-C and SIGTERM, what ``kill``, ``timeout`` and
job schedulers send, into ``Interrupted`` (a ``SystemExit`` with code 130 or 143), so ``finally``
blocks run and the staging folder goes; a repeated signal during that clean-up is ignored. A job killed outright (SIGKILL, a power cut) cannot clean up; its
staging folder names its process, and the next job writing beside it removes it once that
process is gone.
"""

from __future__ import annotations

import os
import shutil
import signal
import sys
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
    check_writable(out, arg)


def check_output_file(path: str | Path, arg: str = "--out") -> None:
    """Raise OutputDirError unless a file can be written at ``path`` (new, or replacing a file)."""
    path = Path(path)
    if path.is_dir():
        raise OutputDirError(f"{arg}: {path} is a folder; valid: a file path, e.g. {path / 'model.joblib'}")
    check_writable(path.parent, arg)


def check_writable(out: Path, arg: str) -> None:
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
#: exit status of a process ended by Ctrl-C (SIGINT)
INTERRUPTED_EXIT = 128 + signal.SIGINT


class Interrupted(SystemExit):
    """The job was stopped by SIGINT (Ctrl-C) or SIGTERM: a ``SystemExit`` whose code is 128 + the
    signal's number (130, 143), so ``except Exception`` lets it through and, uncaught, it ends the
    process with that code and no traceback. ``signum``: the signal."""

    def __init__(self, signum: int) -> None:
        # args hold the signal, not the exit code: simpy re-raises a process's exception rebuilt
        # from its args (``type(e)(*e.args)``), and Interrupted(130) would exit with 258, seen as 2
        super().__init__(int(signum))
        self.signum = int(signum)
        self.code = 128 + self.signum


#: the first stop signal that arrived within ``exit_on_terminate`` / ``stop_on_signals`` (its
#: exception can be lost, below; this record cannot)
_stopped_by: list[int] = []


def _raise_exit(signum, frame) -> None:
    if _stopped_by:  # already stopping (a second Ctrl-C, or the signal sent to the whole group):
        return  # the clean-up of the first one runs undisturbed
    _stopped_by.append(signum)
    raise Interrupted(signum)


def raise_if_terminated() -> None:
    """Raise ``Interrupted`` (exit 143 or 130) if SIGTERM or SIGINT arrived within
    ``exit_on_terminate`` / ``stop_on_signals``.

    The handler's own exception is lost when the signal lands inside a callback from C: Python
    prints it ("Exception ignored from callback") and goes on (seen: pymunk freeing a body
    through cffi during the world's step, and the run then finished and wrote its output). So
    the simulation loops call this once per simulated second, and ``staged_output`` before it
    moves anything into place."""
    if _stopped_by:
        raise Interrupted(_stopped_by[0])


def stop_requested() -> int | None:
    """The stop signal received within ``exit_on_terminate`` / ``stop_on_signals``, else None."""
    return _stopped_by[0] if _stopped_by else None


@contextmanager
def _stopping_on(signals: Sequence[int]) -> Iterator[None]:
    main = threading.current_thread() is threading.main_thread()
    defaults = {signal.SIGTERM: signal.SIG_DFL, signal.SIGINT: signal.default_int_handler}
    mine = [s for s in signals if main and signal.getsignal(s) is defaults[s]]
    _stopped_by.clear()
    for signum in mine:
        signal.signal(signum, _raise_exit)
    hook = sys.unraisablehook
    sys.unraisablehook = _quiet_about_stops(hook)
    try:
        with errors_after_a_stop_are_the_stop():
            yield
    finally:
        sys.unraisablehook = hook
        for signum in mine:
            signal.signal(signum, defaults[signum])
        _stopped_by.clear()


@contextmanager
def errors_after_a_stop_are_the_stop() -> Iterator[None]:
    """Within this block, an error raised after a stop signal arrived ends as that stop
    (``Interrupted``, the error as its cause).

    The signal's own exception can be lost inside a callback from C, and the library it broke then
    fails in its own words (numba compiling when Ctrl-C came: "no compiled object yet"); the cause
    is the stop the user asked for, so that is what ends the job."""
    try:
        yield
    except Exception as exc:
        if _stopped_by:
            raise Interrupted(_stopped_by[0]) from exc
        raise


def _quiet_about_stops(hook):
    """``sys.unraisablehook`` that drops the ``Interrupted`` a callback from C swallowed (it is
    recorded in ``_stopped_by`` and raised again) and hands everything else to ``hook``."""

    def quiet(unraisable) -> None:
        if not isinstance(unraisable.exc_value, Interrupted):
            hook(unraisable)

    return quiet


@contextmanager
def exit_on_terminate() -> Iterator[None]:
    """Within this block SIGTERM ends the process as an exception (``Interrupted``, a
    ``SystemExit(143)``), so ``finally`` blocks and ``staged_output`` clean up; the default action
    comes back after it. Only from the main thread and only over the default action: a program
    embedding the job keeps its own handler. A second SIGTERM while the first one's clean-up runs
    is ignored."""
    with _stopping_on([signal.SIGTERM]):
        yield


@contextmanager
def stop_on_signals() -> Iterator[None]:
    """``exit_on_terminate`` for SIGINT (Ctrl-C, exit 130) and SIGTERM (exit 143) alike: the
    first one raises ``Interrupted``, the next ones are ignored while it cleans up."""
    with _stopping_on([signal.SIGINT, signal.SIGTERM]):
        yield


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
        _remove_made(made)
        raise
    _replace_items(stage, out)
    shutil.rmtree(stage, ignore_errors=True)


def _replace_items(stage: Path, out: Path) -> None:
    """Move every file and folder of ``stage`` into ``out`` (made if missing), replacing its
    namesakes there one by one."""
    out.mkdir(parents=True, exist_ok=True)
    for item in stage.iterdir():
        target = out / item.name
        if target.is_dir() and not target.is_symlink():
            shutil.rmtree(target)
        item.replace(target)


def _move_aside_and_in(stage: Path, out: Path, aside: Path) -> None:
    """Put the finished folder ``stage`` at ``out``: an earlier ``out`` is renamed to ``aside``
    first (it stays whole until then), then ``stage`` is renamed into place. Signals wait
    meanwhile, so the two renames happen both or neither."""
    blocked = {signal.SIGINT, signal.SIGTERM}
    old_mask = signal.pthread_sigmask(signal.SIG_BLOCK, blocked)
    try:
        if out.is_dir() and not out.is_symlink():
            out.rename(aside)
        stage.rename(out)
    except OSError:  # out a mount point or a symlink: its files are replaced one by one
        if aside.exists() and not out.exists():
            aside.rename(out)
        _replace_items(stage, out)
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old_mask)


@contextmanager
def staged_folder(out_dir: str | Path) -> Iterator[Path]:
    """Yield an empty folder named like ``out_dir`` inside a hidden staging folder beside it; on
    success it replaces ``out_dir`` whole (an earlier ``out_dir`` stays intact until then), on any
    error or stop signal it goes and ``out_dir`` is left as it was.

    Unlike ``staged_output`` (which moves files into a folder that may hold others), the result is
    the complete folder: use it for an output folder that ``check_output_dir`` accepted."""
    out = Path(out_dir)
    made = [p for p in (out.parent, *out.parent.parents) if not p.exists()]  # deepest first
    out.parent.mkdir(parents=True, exist_ok=True)
    remove_orphan_stages(out)
    root = Path(tempfile.mkdtemp(prefix=f"{_stage_prefix(out)}{os.getpid()}-", dir=out.parent))
    stage = root / out.name
    try:
        stage.mkdir()
        yield stage
        raise_if_terminated()
        _move_aside_and_in(stage, out, root / f"{out.name}.replaced")
    except BaseException:
        shutil.rmtree(root, ignore_errors=True)
        _remove_made(made)
        raise
    shutil.rmtree(root, ignore_errors=True)


def _remove_made(made: Sequence[Path]) -> None:
    """Remove the parent folders a job created (deepest first), if still empty."""
    for folder in made:
        try:
            folder.rmdir()
        except OSError:
            break
