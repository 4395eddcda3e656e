"""`citysim run | render | year | sweep | calibrate | validate | detect | plot`: the planner's command line.

One module per command, each with its ``add(sub)`` (the subcommand and its arguments) and its
``cmd_*`` (the work). Errors a user can cause print one line naming the argument, file or field
and what is valid, and exit with code 2; nothing half-written is left behind. Every number and
the --out folder are checked before any simulation starts.
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path

from citysim.cli import calibrate, city, detect, import_, plot, render, run, sweep, year
from citysim.cli.common import controller_list, user_errors
from citysim.cli.stops import FAULT_EXIT, interrupted_line, no_room_line, writer_lock
from citysim.sim.workers import WorkerLost
from detector.cliargs import USAGE_EXIT, Parser
from detector.outdir import Interrupted, errors_after_a_stop_are_the_stop, stop_on_signals

#: The commands in the order `citysim --help` lists them.
COMMANDS = (run, render, year, city, sweep, calibrate, detect, plot, import_)


def build_parser() -> argparse.ArgumentParser:
    """The `citysim` parser with every command's subparser."""
    p = Parser(prog="citysim", description="Street-lighting scenarios with camera-driven lamps. "
                                           "'citysim COMMAND --help' describes each command.")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser, metavar="COMMAND")
    for command in COMMANDS:
        command.add(sub)
    return p


def main(argv: list[str] | None = None) -> int:
    """Run `citysim` with ``argv`` (default: the process's arguments); the exit code (see
    ``citysim.cli.stops`` for each one's meaning)."""
    args = build_parser().parse_args(argv)
    out = getattr(args, "out", None)
    existed = out is not None and Path(out).exists()
    # Ctrl-C and SIGTERM end the job as an exception: workers stop, half-written output goes
    with stop_on_signals():
        try:
            with writer_lock(args), errors_after_a_stop_are_the_stop():
                return args.func(args)
        except Interrupted as stop:
            print(f"\n{interrupted_line(args, existed)}", file=sys.stderr)
            return stop.code
        except user_errors() as exc:
            print(f"error: {exc}", file=sys.stderr)
            return USAGE_EXIT
        except (WorkerLost, BrokenProcessPool) as exc:
            print(f"error: {exc or 'a worker process ended mid-run'}", file=sys.stderr)
            return FAULT_EXIT
        except OSError as exc:
            line = no_room_line(exc, args, existed)
            if line is None:
                raise
            print(line, file=sys.stderr)
            return FAULT_EXIT


__all__ = ["build_parser", "controller_list", "main"]
