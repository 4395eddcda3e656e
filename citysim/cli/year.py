"""`citysim year SCENARIO --out DIR`: a year of a scenario's street (see ``citysim.year``).

Like every command, bad input exits with code 2 naming the argument before any run starts.
"""

from __future__ import annotations

import sys
from pathlib import Path

from citysim.cli.common import controller_list
from detector.cliargs import USAGE_EXIT, nearest_names, number
from detector.outdir import check_output_dir, staged_folder

#: What a year folder holds; an earlier one may be replaced.
YEAR_OUTPUTS = ("year.json", "plots/", "report.html")


def cmd_year(args) -> int:
    from citysim.config.scenario import load_scenario
    from citysim.sim.compare import controller_names, default_workers, resolve_controllers
    from citysim.year.counts_csv import CountsError
    from citysim.year.plan import prepare_year, table_runs, year_spec
    from citysim.year.run import run_year

    if args.timezone is not None and (bad := timezone_error(args.timezone)):
        print(f"error: --timezone: {bad}", file=sys.stderr)
        return USAGE_EXIT
    scenario = load_scenario(args.scenario)
    year = year_spec(scenario, str(args.scenario), latitude_deg=args.lat, longitude_deg=args.lon,
                     timezone=args.timezone, year=args.year, sample_s=args.sample_s)
    names = controller_names(args.controllers)
    resolve_controllers(scenario, names)  # unknown names fail here, before any work
    check_output_dir(args.out, "citysim year", YEAR_OUTPUTS)
    # fast by default: light controllers run alike in both; camera controllers use the sensor model
    fidelity = args.fidelity or "fast"
    try:
        plan = prepare_year(scenario, year, args.counts)
    except CountsError as exc:
        print(f"error: --counts: {exc}", file=sys.stderr)
        return USAGE_EXIT
    runs, sim_s = table_runs(plan)
    print(f"{scenario.name} at {year.latitude_deg:g}, {year.longitude_deg:g} ({year.timezone}), {year.year}: "
          f"{len(plan.spans)} nights, {sum(p.hours for p, _, _ in plan.pieces):,.0f} dark hours; "
          f"table: {runs} hour-runs at {fidelity} fidelity, {sim_s:,.0f} simulated s per controller")
    from citysim.report.html import write_report
    from citysim.report.year_section import plot_year, year_table

    with staged_folder(args.out) as stage:  # complete or absent: built aside, renamed into place
        result = run_year(plan, stage, names, workers=args.workers or default_workers(), fidelity=fidelity,
                          check_nights=args.check_nights, progress=not args.no_progress,
                          scenario_file=str(args.scenario))
        plots = plot_year(stage)
        write_report(stage, plots=plots)
    print(year_table(result))
    print(f"\nresults written to {args.out}/:\n  annual figures and the table  {args.out / 'year.json'}\n"
          f"  monthly energy plot          {args.out / 'plots' / plots[0].name}\n"
          f"  report (open in a browser)   {args.out / 'report.html'}")
    return 0


def timezone_error(name: str) -> str | None:
    """What is wrong with the IANA time zone ``name`` (with the nearest valid names), or None."""
    import zoneinfo

    try:
        zoneinfo.ZoneInfo(name)
        return None
    except (zoneinfo.ZoneInfoNotFoundError, ValueError):
        pass
    near = nearest_names(name, sorted(zoneinfo.available_timezones()), n=3)
    hint = f"did you mean {' or '.join(near)}?" if near else "valid: an IANA name such as Europe/Berlin or America/New_York"
    return f"unknown IANA time zone {name!r}; {hint}"


def add(sub) -> None:
    """The `year` subcommand on ``sub``."""
    y = sub.add_parser("year", help="annual energy, cost, CO2 and AECI of a scenario's street",
                       epilog_fn=controller_list,
                       description="Sum every night of a year (civil dusk to dawn at the site) from an hourly "
                                   "response table of short simulated samples; write year.json, a monthly "
                                   "energy plot and report.html.")
    y.add_argument("scenario", type=Path, help="scenario YAML file with a `year:` section "
                                               "(see scenarios/suburban_night.yaml)")
    y.add_argument("--out", type=Path, required=True,
                   help="folder to write: new, empty, or an earlier year folder (replaced)")
    y.add_argument("--lat", type=number(float, ge=-90, le=90, unit="deg"), help="site latitude, north positive")
    y.add_argument("--lon", type=number(float, ge=-180, le=180, unit="deg"), help="site longitude, east positive")
    y.add_argument("--timezone", help="IANA time zone of the site, e.g. Europe/Berlin")
    y.add_argument("--year", type=number(int, ge=1900, le=2200), help="calendar year (default: the scenario's)")
    y.add_argument("--sample-s", type=number(float, ge=30, le=14400, unit="s"),
                   help="simulated seconds measured per traffic level (default: the scenario's year.sample_s); "
                        "longer is steadier and slower")
    y.add_argument("--counts", type=Path, help="hourly traffic counts CSV: date_or_weekday,hour,class,count")
    y.add_argument("--controllers", help="comma-separated controller names (default: the scenario's list); "
                                         "always_on and oracle are added")
    y.add_argument("--fidelity", choices=("full", "fast"), default=None,
                   help="camera controllers: every frame judged (full) or the calibrated sensor model "
                        "(fast, the default; calibrated on first use, see citysim calibrate)")
    y.add_argument("--check-nights", type=number(int, ge=0, le=366), default=0,
                   help="also simulate this many whole nights at full fidelity and compare (minutes per hour)")
    y.add_argument("--workers", type=number(int, ge=1), default=None,
                   help="parallel processes, one table run each (default: 2, or 1 on a one-core machine)")
    y.add_argument("--no-progress", action="store_true", help="no progress bar")
    y.set_defaults(func=cmd_year, out_lock=True)
