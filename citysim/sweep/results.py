"""The sweep's results table: DIR/results.csv, one row per point and controller, written as points finish.

Only the sweep's client process writes the file (no concurrent writers). A
finished point's rows are appended and flushed at once; when a row brings a
column the header lacks (e.g. the first camera controller's ``detection.tpr``
after a run of failed points), the file is rewritten with the wider header
through a temporary file and an atomic rename, so an interrupted sweep never
leaves a half-written table behind. On opening, rows of points that are not
complete (a crash between two rows) are dropped so the point runs again.

Summary figures are flattened into dotted columns (``per_class.vehicle.lag_p95_s``,
``detection.tpr``); lists and matrices are stored as JSON text; missing values
(None, or a figure a controller does not have) are empty cells. Floats are
written with ``repr`` so a value read back is bit-identical.
"""

from __future__ import annotations

import csv
import json
import os
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

__all__ = ["ResultsFile", "flatten_summary", "format_cell"]

#: Columns every row has, first; the sweep's axis columns follow ``point_id``.
LEAD_COLUMNS = ("point_id",)
TAIL_ID_COLUMNS = ("seed", "controller", "status", "error", "finished_at", "wall_s")
#: The headline figures first, in this order; other figures follow sorted by name.
PREFERRED_METRICS = (
    "energy_kwh",
    "savings_vs_always_on",
    "lag_p50_s",
    "lag_p95_s",
    "lag_max_s",
    "dark_exposure_s",
    "unlit_crossings",
    "switches",
    "on_time_s",
    "false_on_time_s",
    "energy_per_hour_kwh",
)
STATUSES = ("ok", "failed")


def format_cell(value: Any) -> str:
    """One CSV cell: repr for floats (round-trips exactly), JSON for lists/dicts, '' for None."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return str(int(value))
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (list, tuple, dict)):
        return json.dumps(value, sort_keys=True)
    return str(value)


def flatten_summary(figures: Mapping[str, Any], reserved: Iterable[str] = ()) -> dict[str, Any]:
    """One controller's summary.json entry as flat dotted columns; lists stay whole (JSON cells).

    A key that collides with an identity column (``reserved``, e.g. the summary's
    own ``controller``) is kept as ``summary.<key>``.
    """
    reserved = set(reserved)
    out: dict[str, Any] = {}

    def walk(prefix: str, node: Mapping[str, Any]) -> None:
        for key, value in node.items():
            name = f"{prefix}{key}"
            if isinstance(value, Mapping) and value:
                walk(f"{name}.", value)
            elif isinstance(value, Mapping):
                continue  # an empty section (e.g. detection of a camera-less controller)
            else:
                out[f"summary.{name}" if name in reserved else name] = value

    walk("", figures)
    return out


class ResultsFile:
    """DIR/results.csv: read what is there, report finished points, append rows."""

    def __init__(self, path: str | Path, axis_columns: Sequence[str]):
        self.path = Path(path)
        self.axis_columns = tuple(axis_columns)
        self.header: list[str] = [*LEAD_COLUMNS, *self.axis_columns, *TAIL_ID_COLUMNS]
        self.rows: list[dict[str, str]] = []
        if self.path.exists():
            self._load()

    def _load(self) -> None:
        with open(self.path, newline="") as f:
            reader = csv.DictReader(f)
            header = list(reader.fieldnames or [])
            rows = list(reader)
        # a row cut short by a crash has missing cells (None) or an unknown status
        self.rows = [
            r
            for r in rows
            if None not in r.values() and None not in r and r.get("status") in STATUSES
        ]
        self.header = self._merged_header(header)
        if len(self.rows) != len(rows) or header != self.header:
            self._rewrite()

    def _merged_header(self, extra: Iterable[str]) -> list[str]:
        """Identity columns first, then metrics (preferred order, then by name)."""
        fixed = [*LEAD_COLUMNS, *self.axis_columns, *TAIL_ID_COLUMNS]
        known = set(fixed)
        metrics = {c for c in [*self.header, *extra] if c not in known}
        ordered = [m for m in PREFERRED_METRICS if m in metrics]
        ordered += sorted(metrics - set(ordered))
        return fixed + ordered

    def finished_points(self, controllers: Sequence[str]) -> dict[str, str]:
        """point_id -> 'ok' or 'failed' for points with a row for every controller."""
        seen: dict[str, dict[str, str]] = {}
        for r in self.rows:
            seen.setdefault(r["point_id"], {})[r["controller"]] = r["status"]
        wanted = set(controllers)
        out = {}
        for pid, by_controller in seen.items():
            if wanted <= set(by_controller):
                statuses = {by_controller[c] for c in wanted}
                out[pid] = "ok" if statuses == {"ok"} else "failed"
        return out

    def drop_points(self, point_ids: Iterable[str]) -> None:
        """Forget the rows of these points (incomplete ones, or failed ones to retry)."""
        drop = set(point_ids)
        if not drop:
            return
        kept = [r for r in self.rows if r["point_id"] not in drop]
        if len(kept) != len(self.rows):
            self.rows = kept
            self._rewrite()

    def append(self, rows: Sequence[Mapping[str, Any]]) -> None:
        """Write a finished point's rows now (flushed and fsynced before returning)."""
        cells = [{k: format_cell(v) for k, v in r.items()} for r in rows]
        new_columns = {k for r in cells for k in r} - set(self.header)
        self.rows.extend(cells)
        if new_columns or not self.path.exists():
            self.header = self._merged_header(new_columns)
            self._rewrite()
            return
        with open(self.path, "a", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=self.header, restval="")
            writer.writerows(cells)
            f.flush()
            os.fsync(f.fileno())

    def _rewrite(self) -> None:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.path.with_name(self.path.name + ".tmp")
        with open(tmp, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=self.header, restval="")
            writer.writeheader()
            writer.writerows(self.rows)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, self.path)
