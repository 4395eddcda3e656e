"""Command-line plumbing shared by ``python -m detector`` and ``citysim``: range-checked numbers,
help that shows every default, and argument errors on one line (exit code 2).

Numbers are checked by argparse itself (``type=number(...)``), so a bad value is refused while
the command line is read, before any file is opened or any frame is simulated.
"""

from __future__ import annotations

import argparse
import difflib
import re
import sys
from collections.abc import Callable, Sequence
from typing import NoReturn

USAGE_EXIT = 2
# argparse's words for a value outside ``choices``: "invalid choice: 'fas' (choose from 'full', 'fast')"
_INVALID_CHOICE = re.compile(r"invalid choice: '(?P<given>[^']*)' \(choose from (?P<choices>.*)\)$")


def nearest_names(name: str, valid: Sequence[str], n: int = 2) -> list[str]:
    """Up to ``n`` of ``valid`` close enough to ``name`` to be what was meant, closest first."""
    return difflib.get_close_matches(name, list(valid), n=n, cutoff=0.6)


def did_you_mean(name: str, valid: Sequence[str]) -> str:
    """'; did you mean x?' for a near miss of one of ``valid``, else '; valid: a, b, c' (empty
    without names): what every bad-name message ends with."""
    if not valid:
        return ""
    near = nearest_names(name, valid)
    if near:
        return f"; did you mean {' or '.join(near)}?"
    return f"; valid: {', '.join(valid)}"


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """Appends "(default: X)" where there is a default worth stating: not for flags (off unless
    given), required arguments, or a None default whose help already says what happens."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        # identity, not ==: a default of 0 is worth stating, False (a flag's) is not
        if "default" in text or any(action.default is v for v in (None, False, argparse.SUPPRESS)) \
                or action.required:  # fmt: skip
            return text
        return super()._get_help_string(action)


class Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line, and whose help may end with text computed
    when help is shown and printed as is (``epilog_fn``: e.g. a list from a slow import)."""

    def __init__(self, *args, epilog_fn: Callable[[], str] | None = None, **kwargs) -> None:
        kwargs.setdefault("formatter_class", HelpFormatter)
        super().__init__(*args, **kwargs)
        self._epilog_fn = epilog_fn

    def format_help(self) -> str:
        text = super().format_help()
        return text if self._epilog_fn is None else f"{text}\n{self._epilog_fn()}\n"

    def error(self, message: str) -> NoReturn:
        # argparse prints the usage block first; a user reads one line naming the argument better
        choice = _INVALID_CHOICE.search(message)
        if choice:  # argparse lists the choices; a near miss is worth naming (Python 3.14 does too)
            valid = [c.strip().strip("'") for c in choice["choices"].split(",")]
            near = nearest_names(choice["given"], valid, n=1)
            if near:
                message += f"; did you mean '{near[0]}'?"
        print(f"error: {message} (see {self.prog} --help)", file=sys.stderr)
        self.exit(USAGE_EXIT)


def number(kind: type = float, *, ge: float | None = None, gt: float | None = None,
           le: float | None = None, unit: str = "") -> Callable[[str], float | int]:
    """An argparse ``type``: ``kind(text)`` within the bounds, else an error saying what is valid."""
    bounds = [f">= {ge:g}" if ge is not None else "", f"> {gt:g}" if gt is not None else "",
              f"<= {le:g}" if le is not None else ""]
    valid = " and ".join(b for b in bounds if b) + (f" {unit}" if unit else "")
    what = "a whole number" if kind is int else "a number"

    def parse(text: str) -> float | int:
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be {what} {valid}, got {text!r}") from None
        if (ge is not None and not value >= ge) or (gt is not None and not value > gt) \
                or (le is not None and not value <= le):  # fmt: skip
            raise argparse.ArgumentTypeError(f"must be {valid}, got {text}")
        return value

    parse.__name__ = kind.__name__  # argparse names the type in its own messages
    return parse
