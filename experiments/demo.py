"""`make demo`: suburban_night in fast mode, a full-fidelity check of its start, and its year.

Three ``citysim`` commands, each printing its own table (2 and 3 start with 1: 2 at its priority,
3 at the lowest, on the CPU time the others leave idle: ``experiments.idle_cores``):

1. ``citysim run --fidelity fast``: ``--controllers`` (``make demo``: ``NIGHT_CONTROLLERS``, the
   bound, the conventional schemes and the camera controller a planner would install; ``make
   demo-night``: every controller of the scenario) from 22:00 for ``--night-s`` simulated seconds
   (the whole night, 28,800 s, by default), cameras judged by the sensor model shipped in
   ``scenarios/sensor_models/`` (no calibration on a fresh clone); writes DIR/night/report.html;
2. ``citysim validate``: the first ``--check-s`` seconds of the same night (the scenario's seed)
   again at full fidelity, rendered and detected, beside fast mode, for ``CHECK_CONTROLLERS``
   (always_on and the oracle come with them), each figure PASS or MISS against its tolerance;
3. ``citysim year``: the year at the scenario's site for ``YEAR_CONTROLLERS`` from a response
   table of ``--year-sample-s`` samples; writes DIR/year/report.html.

Each step's wall and CPU seconds are printed after it, 2's and 3's output once the night is done;
the report paths come last. Bad values
stop before any work with one line naming the option and exit code 2.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from citysim.cli import main as citysim
from citysim.sim.loop import RunError, check_controllers
from experiments.bench.night import WHOLE_NIGHT_S, cpu_s
from experiments.idle_cores import LOWEST_PRIORITY_NICE, BehindTogether

REPO = Path(__file__).resolve().parents[1]
SCENARIO = REPO / "scenarios" / "suburban_night.yaml"
#: what ``make demo`` simulates of the night in fast mode: all of it (22:00-06:00)
DEMO_NIGHT_S = WHOLE_NIGHT_S
CHECK_S = 60.0
#: the night's controllers that sense something (schedule runs alike in both fidelities; always_on and
#: the oracle come with every comparison). Only detector_located renders and detects, so one worker
#: compiles the renderer's and the detector's numba kernels on a fresh clone, not both: with
#: detector_confirmed beside it the check cost 67 CPU-s there (19 once compiled)
CHECK_CONTROLLERS = "pir,detector_located"
#: the bound, the two conventional schemes (part-night schedule, PIR) and the camera controller a
#: planner would install (``detector_located``), so the night and the year answer "how much, and
#: who is left dark" (every controller's whole night costs about 3 times as much: ``--controllers all``)
NIGHT_CONTROLLERS = YEAR_CONTROLLERS = "always_on,oracle,pir,schedule,detector_located"
YEAR_SAMPLE_S = 300.0


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m experiments.demo", description=__doc__.split("\n")[0])
    p.add_argument("--out", type=Path, default=REPO / "results" / "demo",
                   help="folder for night/ and year/ (each replaced if it is an earlier demo's)")
    p.add_argument("--controllers", default=NIGHT_CONTROLLERS,
                   help="comma-separated controllers of the night, or 'all' (every controller of the scenario)")
    p.add_argument("--night-s", type=float, default=DEMO_NIGHT_S,
                   help=f"simulated seconds of the night in fast mode, from 22:00 (0 < s <= {WHOLE_NIGHT_S:.0f})")
    p.add_argument("--check-s", type=float, default=CHECK_S,
                   help="simulated seconds of the full-fidelity check (0 < s <= --night-s)")
    p.add_argument("--year-sample-s", type=float, default=YEAR_SAMPLE_S,
                   help="simulated seconds per traffic level of the year's table (30 <= s <= 14400)")
    return p


def check_args(p: argparse.ArgumentParser, args) -> None:
    """One line naming the bad option and its valid range, exit 2, before any simulation."""
    if not 0 < args.night_s <= WHOLE_NIGHT_S:
        p.error(f"--night-s: must be in (0, {WHOLE_NIGHT_S:.0f}] simulated s, got {args.night_s:g}")
    if not 0 < args.check_s <= args.night_s:
        p.error(f"--check-s: must be in (0, --night-s = {args.night_s:g}] simulated s, got {args.check_s:g}")
    if not 30 <= args.year_sample_s <= 14400:
        p.error(f"--year-sample-s: must be in [30, 14400] simulated s, got {args.year_sample_s:g}")
    if args.controllers != "all":
        try:
            check_controllers([name.strip() for name in args.controllers.split(",")])
        except RunError as bad:
            p.error(f"--{bad}")


def _step(title: str, argv: list[str], timings: list, behind: BehindTogether) -> None:
    print(f"\n=== {title} ===", flush=True)

    def own_cpu_s() -> float:  # this process's and its workers', not those of the commands behind it
        return cpu_s() - behind.reaped_cpu_s

    c0, t0 = own_cpu_s(), time.perf_counter()
    code = citysim(argv)
    wall, cpu = time.perf_counter() - t0, own_cpu_s() - c0
    timings.append((title, wall, cpu))
    print(f"({title}: {wall:.0f} s wall, {cpu:.0f} CPU-s)", flush=True)
    if code:
        raise SystemExit(code)


def start_behind(steps: list[tuple[str, list[str], int]]) -> BehindTogether:
    """The ``citysim`` commands of ``steps`` ((title, argv, nice level) triples) started now, beside
    or behind the night (``experiments.idle_cores``)."""
    return BehindTogether([(title, [sys.executable, "-m", "citysim", *argv, "--no-progress"], nice_level)
                           for title, argv, nice_level in steps])  # fmt: skip


def _print_behind(behind: BehindTogether, timings: list) -> None:
    for done in behind.finished():
        print(f"\n=== {done.title} (ran beside the night) ===")
        print(done.output.rstrip(), flush=True)
        timings.append((done.title, done.wall_s, done.cpu_s))
        print(f"({done.title}: {done.wall_s:.0f} s wall from its start, {done.cpu_s:.0f} CPU-s)", flush=True)
        if done.exit_code:
            raise SystemExit(done.exit_code)


def main(argv: list[str] | None = None) -> int:
    p = _parser()
    args = p.parse_args(argv)
    check_args(p, args)
    out, scenario = args.out, str(SCENARIO)
    night_h = args.night_s / 3600.0
    timings: list = []
    which = ["--controllers", args.controllers] if args.controllers != "all" else []
    who = "every controller" if args.controllers == "all" else args.controllers
    t0 = time.perf_counter()
    print(f"demo: writing {out}/night and {out}/year; the bars count simulated seconds (summed over the "
          "controllers) and estimate the time left once warmed up (workers started, kernels compiled)", flush=True)
    # the check and the year need nothing of the night: they start now, the check at the night's
    # priority (a serial chain that would otherwise run after the night), the year on the CPU time
    # the two leave idle (see idle_cores)
    behind = start_behind([
        (f"2. the check: its first {args.check_s:g} s at full fidelity (rendered and detected) beside fast mode",
         ["validate", scenario, "--seeds", "1", "--duration", f"{args.check_s:g}", "--controllers", CHECK_CONTROLLERS],
         0),
        (f"3. the year: {YEAR_CONTROLLERS}, {args.year_sample_s:g} s samples per traffic level",
         ["year", scenario, "--out", str(out / "year"), "--controllers", YEAR_CONTROLLERS,
          "--sample-s", f"{args.year_sample_s:g}"], LOWEST_PRIORITY_NICE),
    ])  # fmt: skip
    try:
        _step(f"1. the night in fast mode: {who}, {args.night_s:g} s from 22:00 ({night_h:.2g} h)",
              ["run", scenario, "--out", str(out / "night"), "--fidelity", "fast", "--duration", f"{args.night_s:g}",
               *which], timings, behind)  # fmt: skip
        _print_behind(behind, timings)
    finally:
        behind.stop()  # a failed or interrupted night leaves nothing running behind it
    print("\n=== demo done ===")
    for title, wall, cpu in timings:
        print(f"  {wall:5.0f} s wall {cpu:6.0f} CPU-s  {title.split(':')[0]}")
    total_wall, total_cpu = time.perf_counter() - t0, sum(t[2] for t in timings)
    print(f"  {total_wall:5.0f} s wall {total_cpu:6.0f} CPU-s  in all (2 and 3 ran beside 1)")
    print(f"open in a browser:\n  the night  {out / 'night' / 'report.html'}\n  the year   {out / 'year' / 'report.html'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
