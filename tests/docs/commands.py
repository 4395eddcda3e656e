"""The shell commands the documentation shows: found in its ```bash blocks, and checked by the real parsers.

`doc_commands` reads README.md and every page under docs/ and yields each command line of a
```bash block (comments dropped, ``\\`` continuations joined). `check_command` parses a
`citysim`, `python -m detector`, `python -m experiments.*` or `make` line with the program's own
parser (or, for make, the Makefile's targets) and raises `CommandError` naming the page and line
when it would be refused.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import io
import re
import shlex
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BASH_BLOCK = re.compile(r"^```bash\n(.*?)^```", re.S | re.M)
#: Programs whose lines are checked (and `python -m experiments.*`); any other line of a bash
#: block (cd, cp, apt-get, python -m pytest) is left alone.
CHECKED_PROGRAMS = ("make", "citysim", "python -m citysim", "python -m detector")


class CommandError(AssertionError):
    """A documented command its program would refuse."""


@dataclass(frozen=True)
class DocCommand:
    """One command line of a page's bash block: the page, the line as shown, its words."""

    page: str
    line: str
    argv: tuple[str, ...]

    @property
    def program(self) -> str:
        """'make', 'citysim' or 'python -m MODULE' (a .venv/bin/ prefix dropped), else the first word."""
        first = self.argv[0].removeprefix(".venv/bin/")
        if first == "python" and len(self.argv) > 2 and self.argv[1] == "-m":
            return f"python -m {self.argv[2]}"
        return first

    @property
    def args(self) -> list[str]:
        """The words after the program."""
        return list(self.argv[3:] if self.program.startswith("python -m") else self.argv[1:])


def doc_pages(root: Path = ROOT) -> list[Path]:
    """README.md and every Markdown page of the docs site."""
    return [root / "README.md", *sorted((root / "docs").rglob("*.md"))]


def bash_lines(text: str) -> Iterator[str]:
    """Each command line of the text's ```bash blocks: comments dropped, continuations joined."""
    for block in BASH_BLOCK.findall(text):
        joined = block.replace("\\\n", " ")
        for raw in joined.splitlines():
            line = raw.split(" #", 1)[0].strip()
            if line and not line.startswith("#"):
                yield line


def doc_commands(root: Path = ROOT) -> list[DocCommand]:
    """Every checked command line shown in the documentation."""
    found = []
    for page in doc_pages(root):
        for line in bash_lines(page.read_text()):
            command = DocCommand(str(page.relative_to(root)), line, tuple(shlex.split(line)))
            if command.program in CHECKED_PROGRAMS or command.program.startswith("python -m experiments."):
                found.append(command)
    return found


def makefile_targets(root: Path = ROOT) -> set[str]:
    """The targets the Makefile defines."""
    text = (root / "Makefile").read_text()
    return {m.group(1) for m in re.finditer(r"^([A-Za-z][\w.-]*):", text, re.M)}


def module_parser(module: str) -> argparse.ArgumentParser:
    """The argparse parser of a `python -m MODULE` command (its ``build_parser`` or ``_parser``)."""
    if module == "detector":
        raise ValueError("python -m detector has two parsers; see parser_for")
    mod = importlib.import_module(module)
    if hasattr(mod, "__path__"):  # a package: its command line is its __main__
        mod = importlib.import_module(f"{module}.__main__")
    for name in ("build_parser", "_parser"):
        if hasattr(mod, name):
            return getattr(mod, name)()
    raise CommandError(f"{module} has no build_parser() or _parser() to check its documented commands with")


def parser_for(command: DocCommand) -> argparse.ArgumentParser:
    """The real parser that reads ``command``'s arguments."""
    program = command.program
    if program in ("citysim", "python -m citysim"):
        from citysim.cli import build_parser

        return build_parser()
    if program == "python -m detector":
        from detector.__main__ import _detect_parser, _train_parser

        return _train_parser() if command.args[:1] == ["train"] else _detect_parser()
    return module_parser(program.removeprefix("python -m "))


def check_command(command: DocCommand, root: Path = ROOT) -> None:
    """Raise CommandError when ``command``'s program would refuse its arguments."""
    where = f"{command.page}: `{command.line}`"
    if command.program == "make":
        missing = [t for t in command.args if not t.startswith("-") and t not in makefile_targets(root)]
        if missing:
            raise CommandError(f"{where}: no Makefile target {missing}")
        return
    args = command.args
    if command.program == "python -m detector" and args[:1] == ["train"]:
        args = args[1:]
    if "--help" in args or "-h" in args:
        return  # run, not parsed: see test_commands.py
    stderr = io.StringIO()
    try:
        with contextlib.redirect_stderr(stderr):
            parser_for(command).parse_args(args)
    except SystemExit as exc:
        raise CommandError(f"{where}: refused by its parser: {stderr.getvalue().strip()}") from exc
