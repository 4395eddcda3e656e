"""`citysim run SCENARIO --out DIR`: every controller on one scenario's night, the run folder and its table."""

from __future__ import annotations

from pathlib import Path

from citysim.cli.common import MAX_DURATION_S, add_fidelity, controller_list
from detector.cliargs import number
from detector.outdir import check_output_dir

#: What a run folder holds ("plots/" a folder); an earlier one may be replaced, a folder holding
#: anything else is refused.
RUN_OUTPUTS = ("summary.json", "objects.csv", "lamps.csv", "plots/", "report.html")


def cmd_run(args) -> int:
    from citysim.config.scenario import load_scenario, override
    from citysim.sim.compare import controller_names, default_workers, run_comparison

    scenario = load_scenario(args.scenario)
    updates = {}
    if args.duration is not None:
        updates["duration_s"] = args.duration
    if args.seed is not None:
        updates["seed"] = args.seed
    if updates:
        scenario = override(scenario, updates)
    names = controller_names(args.controllers)
    check_output_dir(args.out, "citysim run", RUN_OUTPUTS)
    workers = args.workers or default_workers()
    summary = run_comparison(scenario, names, progress=not args.no_progress, out_dir=args.out, workers=workers,
                             scenario_file=str(args.scenario), fidelity=args.fidelity, cache_dir=args.cache)
    from citysim.report.run_plots import plot_run
    from citysim.report.table import comparison_table
    from citysim.report.topdown import plot_coverage_map
    from citysim.world.street import build_street

    # the run folder's data is written; its pictures are drawn here, outside the simulation (the
    # coverage map from the scenario's street, the rest from the run folder alone)
    plot_coverage_map(build_street(scenario), Path(args.out) / "plots" / "coverage.png")
    plot_run(args.out)
    print(comparison_table(summary))
    print("\n" + "\n".join(run_outputs(Path(args.out))))
    return 0


def run_outputs(out: Path) -> list[str]:
    """Write report.html beside the plots the run drew; the lines saying where everything is."""
    from citysim.report.html import write_report
    from citysim.report.run_plots import RUN_PLOTS

    plots = [out / "plots" / name for name in RUN_PLOTS if (out / "plots" / name).exists()]
    where = [("figures per controller", f"{out / 'summary.json'}"),
             ("per object and lamp", f"{out / 'objects.csv'}, {out / 'lamps.csv'}")]  # fmt: skip
    if plots:
        report = write_report(out, plots=plots)  # the plots run_comparison drew, not drawn again
        where += [(f"plots ({len(plots)} PNGs)", f"{out / 'plots'}/"),
                  ("report (open in a browser)", str(report))]  # fmt: skip
    width = max(len(label) for label, _ in where)
    return [f"results written to {out}/:"] + [f"  {label:<{width}}  {path}" for label, path in where]


def add(sub) -> None:
    r = sub.add_parser("run", help="compare controllers on one scenario's night", epilog_fn=controller_list,
                       description="Simulate the scenario's night once per controller, on the same traffic, and "
                                   "write a run folder: summary.json, objects.csv, lamps.csv, plots/.")
    r.add_argument("scenario", type=Path, help="scenario YAML file (see scenarios/suburban_night.yaml)")
    r.add_argument("--out", type=Path, required=True,
                   help="run folder to write: new, empty, or an earlier run folder (replaced)")
    r.add_argument("--controllers", help="comma-separated controller names, listed below; always_on is added "
                                         "for the savings (default: the scenario's list)")
    r.add_argument("--duration", type=number(float, gt=0, le=MAX_DURATION_S, unit="s"),
                   help="simulated seconds (default: the scenario's duration_s)")
    r.add_argument("--seed", type=number(int, ge=0),
                   help="random seed of the traffic, scenery and sensor noise (default: the scenario's seed)")
    r.add_argument("--workers", type=number(int, ge=1), default=None,
                   help="parallel processes, one controller each (default: 2, or 1 on a one-core machine)")
    add_fidelity(r, "full")
    r.add_argument("--no-progress", action="store_true", help="no progress bar")
    r.set_defaults(func=cmd_run)


