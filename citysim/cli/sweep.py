"""`citysim sweep SWEEP --out DIR`: every point of a sweep file on Dask; a folder of the same sweep resumes."""

from __future__ import annotations

from pathlib import Path

from citysim.cli.common import add_fidelity
from detector.cliargs import number
from detector.outdir import check_output_dir

#: What a sweep folder holds; an earlier folder of the same sweep resumes.
SWEEP_OUTPUTS = ("sweep.json", "results.csv", "results.csv.tmp", "points/", "plots/", "report.html")


def cmd_sweep(args) -> int:
    from citysim.sim.validation import TOLERANCE_NOTE
    from citysim.sweep.runner import run_sweep

    check_output_dir(args.out, "citysim sweep", SWEEP_OUTPUTS)  # an earlier folder of this sweep resumes
    counts = run_sweep(args.sweep, args.out, scheduler=args.scheduler, workers=args.workers,
                       progress=not args.no_progress, fidelity=args.fidelity, full_checks=args.full_checks,
                       cache_dir=args.cache)  # fmt: skip
    print(f"{counts['points']} points ({args.fidelity} fidelity): {counts['ran']} ran ({counts['ok']} ok, "
          f"{counts['failed']} failed), {counts['skipped']} already done")
    if "check" in counts:
        check = counts["check"]
        print(f"full-fidelity check of {check['points']} points: {check['cells_pass']} of {check['cells']} figures "
              f"agree ({TOLERANCE_NOTE}); {check['file']}")
    print(f"results written to {counts['results']}; plots and report: citysim plot {args.out}")
    return 0


def interrupted_sweep(args) -> str:
    """The line a stopped sweep prints: the points kept (written as each finished) and how to resume."""
    from citysim.sweep.runner import kept_points

    if not (args.out / "sweep.json").exists():
        return "interrupted: nothing written"
    kept, total = kept_points(args.sweep, args.out)
    return f"interrupted: {kept} of {total} points kept in {args.out}; run the same command again to resume"


def add(sub) -> None:
    s = sub.add_parser("sweep", help="run a parameter sweep on Dask",
                       description="Run every point of a sweep file; a folder of the same sweep resumes.")
    s.add_argument("sweep", type=Path, help="sweep YAML file (see experiments/sweeps/)")
    s.add_argument("--out", type=Path, required=True,
                   help="sweep folder: new, empty, or an earlier folder of this sweep (resumed)")
    s.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://HOST:8786 (default: a local cluster)")
    s.add_argument("--workers", type=number(int, ge=1), default=None,
                   help="local cluster processes (default: one per CPU)")
    add_fidelity(s, "fast")
    s.add_argument("--full-checks", type=number(int, ge=0), default=2,
                   help="in fast mode, this many points (evenly spread) are re-run in full fidelity and compared")
    s.add_argument("--no-progress", action="store_true", help="no progress bar")
    s.set_defaults(func=cmd_sweep, out_lock=True, on_interrupt=interrupted_sweep)
