"""The one error a bad GIS input raises, and the "did you mean" helper its messages use."""

from __future__ import annotations

import difflib


class GisInputError(ValueError):
    """A GIS file or import argument that cannot be turned into a street; the message names it and
    what would be valid. The `citysim import` command prints it on one line and exits with code 2."""


def nearest_names(name: str, names: list[str], count: int = 3) -> str:
    """The names most like ``name`` (difflib, case-insensitive), quoted and comma-separated, or ''."""
    folded = {n.casefold(): n for n in names}
    close = difflib.get_close_matches(name.casefold(), list(folded), n=count, cutoff=0.5)
    return ", ".join(repr(folded[c]) for c in close)
