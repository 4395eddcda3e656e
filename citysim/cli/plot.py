"""`citysim plot DIR`: the plots and report.html of a run or sweep folder, drawn again from its files."""

from __future__ import annotations

from pathlib import Path


def cmd_plot(args) -> int:
    from citysim.report.html import write_report
    from citysim.report.run_plots import plot_run
    from citysim.report.sweep_plots import plot_sweep

    folder = Path(args.dir)
    if (folder / "results.csv").exists():
        paths = plot_sweep(folder)
    elif (folder / "summary.json").exists():
        paths = plot_run(folder)
    else:
        from citysim.sim.loop import RunError

        raise RunError(f"{folder}: neither a run folder (summary.json) nor a sweep folder (results.csv)")
    report = write_report(folder, plots=paths)  # the plots just drawn: not drawn twice
    print(f"{len(paths)} plots written to {folder}/plots/; report: {report}")
    return 0


def add(sub) -> None:
    pl = sub.add_parser("plot", help="plots and report.html for a run or sweep folder",
                        description="Draw the plots and report.html of a run or sweep folder.")
    pl.add_argument("dir", type=Path, help="a run folder (summary.json) or sweep folder (results.csv)")
    pl.set_defaults(func=cmd_plot)
