"""The results figures: the year's and the night's frontier, drawn from the committed result files.

Both use the run report's own frontier drawing (`citysim.report.frontier`), so the README's
headline picture is the one every report.html opens with. PNGs are written without the
matplotlib version in their metadata, so the same data and library give the same bytes.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from citysim.report.frontier import frontier_figure

#: Dots per inch of the committed figures (small files, sharp enough on a code host's page).
FIGURE_DPI = 110


def _with_kind(controllers: Mapping[str, Mapping]) -> dict[str, dict]:
    """Controllers as `frontier_figure` reads them: a year.json's lack the ``controller`` key."""
    return {name: {"controller": name, **c} for name, c in controllers.items()}


def frontier_png(controllers: Mapping[str, Mapping], title: str, path: Path) -> Path:
    """Draw the frontier of ``controllers`` (summary.json's or year.json's) to ``path`` (PNG)."""
    fig = frontier_figure(_with_kind(controllers), title=title)
    if fig is None:
        raise ValueError(f"{path.name}: no controller has both a saving and a lit-on-entry rate")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=FIGURE_DPI, bbox_inches="tight", metadata={"Software": None})
    import matplotlib.pyplot as plt

    plt.close(fig)
    return path
