"""`python -m experiments.results.city_timing DIR...`: a city run's wall and CPU time and its workers' memory.

Each DIR is a `citysim city` output folder whose command was run under `/usr/bin/time -v` with
the report saved beside it as DIR.time.log and the load average before it as DIR.uptime.txt
(beside, not inside: the city refuses an output folder holding other files), e.g.::

    uptime > DIR.uptime.txt
    /usr/bin/time -v -o DIR.time.log citysim city CITY.yaml --workers 2 --out DIR

The JSON written (one entry per folder, in the order given) holds the workers asked for (read
from the log's command line), the wall seconds and the CPU seconds (user + system, the command and
every process it waited for: the Dask scheduler's and workers' processes included), the command's
peak RSS, and per worker process (from DIR/streets/*/task.json) the streets it ran in the order
finished with their wall and CPU seconds and the worker's peak RSS after each, MB.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

from experiments.results.sources import CITY_TIMING, RESULTS_DIR

_WALL = re.compile(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (?:(\d+):)?(\d+):([\d.]+)")
_FIELDS = {"user_s": "User time (seconds)", "system_s": "System time (seconds)",
           "max_rss_kb": "Maximum resident set size (kbytes)", "command": "Command being timed"}  # fmt: skip


def parse_time_log(text: str) -> dict:
    """The figures of a GNU time -v report: wall_s, user_s, system_s, max_rss_kb, command, workers."""
    facts: dict = {}
    for line in text.splitlines():
        line = line.strip()
        for key, label in _FIELDS.items():
            if line.startswith(label + ":"):
                value = line.split(":", 1)[1].strip()
                facts[key] = value.strip('"') if key == "command" else float(value)
        match = _WALL.search(line)
        if match:
            hours, minutes, seconds = match.groups()
            facts["wall_s"] = 3600.0 * int(hours or 0) + 60.0 * int(minutes) + float(seconds)
    missing = [k for k in ("wall_s", "user_s", "system_s", "command") if k not in facts]
    if missing:
        raise ValueError(f"not a `/usr/bin/time -v` report: no {', '.join(missing)}")
    workers = re.search(r"--workers[ =](\d+)", facts["command"])
    facts["workers"] = int(workers.group(1)) if workers else None
    return facts


def worker_facts(folder: Path) -> list[dict]:
    """Per worker process (by pid, in the order each first finished a street): its streets in order."""
    tasks = sorted((json.loads(p.read_text()) for p in Path(folder).glob("streets/*/task.json")),
                   key=lambda t: t["finished_unix_s"])  # fmt: skip
    by_pid: dict[int, list[dict]] = {}
    for t in tasks:
        by_pid.setdefault(t["pid"], []).append({"street": t["street"], "wall_s": round(t["wall_s"], 1),
                                                "cpu_s": round(t["cpu_s"], 1),
                                                "peak_rss_mb": round(t["worker_peak_rss_mb"], 1)})  # fmt: skip
    return [{"worker": i + 1, "streets": streets} for i, streets in enumerate(by_pid.values())]


def side_file(folder: Path, suffix: str) -> Path:
    """DIR.<suffix> beside the folder DIR."""
    return folder.with_name(f"{folder.name}.{suffix}")


def run_facts(folder: Path) -> dict:
    """One city run's figures (see the module docstring)."""
    folder = Path(folder)
    log = parse_time_log(side_file(folder, "time.log").read_text())
    uptime = side_file(folder, "uptime.txt")
    load = re.search(r"load average: ([\d.]+), ([\d.]+), ([\d.]+)", uptime.read_text()) if uptime.exists() else None
    return {"workers": log["workers"], "wall_s": round(log["wall_s"], 1),
            "cpu_s": round(log["user_s"] + log["system_s"], 1),
            "command_peak_rss_mb": round(log.get("max_rss_kb", 0.0) / 1024.0, 1),
            "load_average_1_5_15_min_before": [float(x) for x in load.groups()] if load else None,
            "per_worker": worker_facts(folder)}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    """Write the timing JSON of the city folders given; the exit code (2: a folder without its log)."""
    p = argparse.ArgumentParser(prog="python -m experiments.results.city_timing", description=__doc__.splitlines()[0])
    p.add_argument("folders", nargs="+", type=Path, help="citysim city output folders, each with DIR.time.log beside it")
    p.add_argument("--out", type=Path, default=RESULTS_DIR / CITY_TIMING.file, help="the JSON to write")
    args = p.parse_args(argv)
    for folder in args.folders:
        if not side_file(folder, "time.log").is_file():
            print(f"folders: no {side_file(folder, 'time.log')} (run the city under /usr/bin/time -v -o that file)",
                  file=sys.stderr)  # fmt: skip
            return 2
    runs = [run_facts(folder) for folder in args.folders]
    args.out.write_text(json.dumps({"runs": runs}, indent=2) + "\n")
    print(f"written: {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
