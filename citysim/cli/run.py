"""`citysim run SCENARIO --out DIR`: every controller on one scenario's night, the run folder and its table."""

from __future__ import annotations

from pathlib import Path

from citysim.cli.common import MAX_DURATION_S, add_fidelity, controller_list
from detector.cliargs import number
from detector.outdir import check_output_dir, staged_folder

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
    from citysim.report.run_plots import plot_run
    from citysim.report.table import comparison_table
    from citysim.report.topdown import plot_coverage_map
    from citysim.world.street import build_street

    out = Path(args.out)
    # the whole folder, plots and report included, is built aside and renamed into place at the end:
    # an interrupted run leaves an earlier run folder as it was, or none
    with staged_folder(out) as stage:
        summary = run_comparison(scenario, names, progress=not args.no_progress, out_dir=stage, workers=workers,
                                 scenario_file=str(args.scenario), fidelity=args.fidelity, cache_dir=args.cache)
        # the run folder's data is written; its pictures are drawn here, outside the simulation (the
        # coverage map from the scenario's street, the rest from the run folder alone)
        plot_coverage_map(build_street(scenario), stage / "plots" / "coverage.png")
        plot_run(stage)
        where = run_outputs(stage, shown_as=out)
    print(comparison_table(summary))
    print("\n" + "\n".join(where))
    return 0


def run_outputs(folder: Path, shown_as: Path | None = None) -> list[str]:
    """Write report.html beside the plots the run drew in ``folder``; the lines saying where
    everything is, under the name ``shown_as`` (default ``folder``; the staged folder's final place)."""
    from citysim.report.html import write_report
    from citysim.report.run_plots import RUN_PLOTS

    out = shown_as if shown_as is not None else folder
    plots = [folder / "plots" / name for name in RUN_PLOTS if (folder / "plots" / name).exists()]
    where = [("figures per controller", f"{out / 'summary.json'}"),
             ("per object and lamp", f"{out / 'objects.csv'}, {out / 'lamps.csv'}")]  # fmt: skip
    if plots:
        write_report(folder, plots=plots)  # the plots run_comparison drew, not drawn again
        where += [(f"plots ({len(plots)} PNGs)", f"{out / 'plots'}/"),
                  ("report (open in a browser)", str(out / "report.html"))]  # fmt: skip
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
    r.set_defaults(func=cmd_run, out_lock=True)


