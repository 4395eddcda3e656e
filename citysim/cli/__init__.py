"""`citysim run | render | year | sweep | calibrate | validate | detect | plot`: the planner's command line.

One module per command, each with its ``add(sub)`` (the subcommand and its arguments) and its
``cmd_*`` (the work). Errors a user can cause print one line naming the argument, file or field
and what is valid, and exit with code 2; nothing half-written is left behind. Every number and
the --out folder are checked before any simulation starts.
"""

from __future__ import annotations

import argparse
import sys

from citysim.cli import calibrate, city, detect, import_, plot, render, run, sweep, year
from citysim.cli.common import controller_list, user_errors
from detector.cliargs import USAGE_EXIT, Parser
from detector.outdir import exit_on_terminate

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
    """Run `citysim` with ``argv`` (default: the process's arguments); the exit code."""
    args = build_parser().parse_args(argv)
    # killed from outside (SIGTERM), a job still removes its half-written output
    with exit_on_terminate():
        try:
            return args.func(args)
        except user_errors() as exc:
            print(f"error: {exc}", file=sys.stderr)
            return USAGE_EXIT


__all__ = ["build_parser", "controller_list", "main"]
