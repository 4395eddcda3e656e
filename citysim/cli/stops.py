"""How a command ends when it does not finish: stopped by a signal, its folder locked by another
run, a worker killed, the disk full. Each ends with one line and an exit code, no traceback.

=========  ===========================================================================
exit code  meaning
=========  ===========================================================================
0          done; the output folder is complete
1          a fault outside the user's input: a worker process killed, the disk full
2          bad input (argument, scenario field, file), or the output folder is locked
130        stopped by Ctrl-C (SIGINT)
143        stopped by SIGTERM (``kill``, ``timeout``, a batch system, a container stop)
=========  ===========================================================================
"""

from __future__ import annotations

import errno
import sys
from collections.abc import Iterator
from contextlib import contextmanager, nullcontext
from pathlib import Path

from detector.outlock import output_lock

#: Exit code of a fault that is not the user's input (a worker killed, a full disk).
FAULT_EXIT = 1
#: The errno values of a write that found no room: no space, a file-size limit, a quota.
NO_ROOM = (errno.ENOSPC, errno.EFBIG, errno.EDQUOT)


def interrupted_line(args, existed: bool) -> str:
    """The one line a stopped command prints: what it left (``args.out``; ``existed``: whether
    the folder was there before the command began). A command may say more itself
    (``args.on_interrupt(args)``, e.g. how many sweep points were kept)."""
    own = getattr(args, "on_interrupt", None)
    if own is not None:
        return own(args)
    out = getattr(args, "out", None)
    if out is not None and existed:
        return f"interrupted: {out} left as it was"
    return "interrupted: nothing written"


def no_room_line(exc: OSError, args, existed: bool) -> str | None:
    """The one line for a write that found the disk full or a file-size limit (None for another
    OSError); ``existed`` as for ``interrupted_line``."""
    if exc.errno not in NO_ROOM:
        return None
    out = getattr(args, "out", None)
    where = exc.filename or out or "the output"
    left = f"{out} left as it was" if out is not None and existed else "nothing written"
    return f"error: no room to write {where} ({exc.strerror}); {left}; free some space and run the same command again"


@contextmanager
def writer_lock(args) -> Iterator[None]:
    """Hold the lock of ``args.out`` for commands that write a folder (``args.out_lock``); say so
    when a lock left by a killed process was taken over."""
    out: Path | None = getattr(args, "out", None) if getattr(args, "out_lock", False) else None
    with output_lock(out) if out is not None else nullcontext() as stale:
        if stale:
            print(f"note: {out}: took over the lock of process {stale}, which is no longer running", file=sys.stderr)
        yield


