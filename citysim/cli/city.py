"""`citysim city CITY.yaml --out DIR`: every street of a city for a year on Dask, ranked by payback.

Bad input (the city file, a street's scenario, a controller name, the folder) exits with code 2
naming the field or argument before any street runs. An earlier folder of the same city resumes.
"""

from __future__ import annotations

from pathlib import Path

from citysim.cli.common import add_cache, controller_list
from detector.cliargs import number
from detector.outdir import check_output_dir


def epilog() -> str:
    """The controllers, and every cost field with its default and meaning (the city file's `costs:`)."""
    from citysim.config.costs import CostsSpec

    lines = ["costs (the city file's `costs:` section replaces every street's own; amounts in the year's currency):"]
    for name, field in CostsSpec.model_fields.items():
        default = "the year section's, else as stated" if field.default is None else field.default
        lines.append(f"  {name} (default {default}): "
                     f"{field.description}")
    return controller_list() + "\n\n" + "\n".join(lines)


def cmd_city(args) -> int:
    from citysim.city.run import CITY_OUTPUTS, CityOptions, city_jobs, run_city
    from citysim.city.spec import load_city
    from citysim.report.city_report import write_city_report

    city = load_city(args.city)
    check_output_dir(args.out, "citysim city", CITY_OUTPUTS)  # an earlier folder of this city resumes
    names = tuple(n.strip() for n in args.controllers.split(",") if n.strip()) if args.controllers else None
    options = CityOptions(controllers=names, sample_s=args.sample_s, fidelity=args.fidelity,
                          min_lit_on_entry=args.min_lit_on_entry, scheduler=args.scheduler, workers=args.workers,
                          progress=not args.no_progress, cache_dir=args.cache)  # fmt: skip
    jobs = city_jobs(city, args.city, args.out, options)  # every street checked before any runs
    print(f"{len(jobs)} streets at {city.site.latitude_deg:g}, {city.site.longitude_deg:g} ({city.site.timezone}), "
          f"{args.fidelity} fidelity, on {args.scheduler or f'a local cluster of {args.workers or 2} workers'}")
    result = run_city(city, args.city, args.out, options, jobs=jobs)
    counts = result["counts"]
    report, plots = write_city_report(args.out)
    print(f"{counts['streets']} streets: {counts['ran']} ran, {counts['skipped']} already done")
    for entry in result["ranking"]:
        payback = "never" if entry["payback_years"] is None else f"{entry['payback_years']:.1f} y"
        print(f"  {entry['rank']:>3}. {entry['street']:<28} {entry['controller'] or '(none lights enough)':<22} "
              f"payback {payback}")
    print(f"\nresults written to {args.out}/:\n  per street, per controller  {result['files'][0]}\n"
          f"  the same as a table         {result['files'][1]}\n  city map and ranking        "
          f"{', '.join(str(p) for p in plots)}\n  report (open in a browser)  {report}")
    return 0


def add(sub) -> None:
    """The `city` subcommand on ``sub``."""
    c = sub.add_parser("city", help="a city's streets for a year on Dask: energy, payback, NPV, ranking",
                       epilog_fn=epilog,
                       description="Run every street of a city file for a year (citysim year's table, one Dask "
                                   "task per street), rank the streets by the payback of their best controller, "
                                   "and write city.json, city.csv, a city map and report.html. Finished streets "
                                   "are kept in DIR/streets/: a stopped run resumes. The city's site and costs "
                                   "replace every street's own.")
    c.add_argument("city", type=Path, help="city YAML file: streets (scenario files) and/or osm, site, costs")
    c.add_argument("--out", type=Path, required=True,
                   help="city folder: new, empty, or an earlier folder of this city (resumed)")
    where = c.add_mutually_exclusive_group()
    where.add_argument("--workers", type=number(int, ge=1), default=None,
                       help="local cluster worker processes, one street each at a time (default: 2)")
    where.add_argument("--scheduler", help="Dask scheduler address of a running cluster, e.g. tcp://HOST:8786")
    c.add_argument("--controllers", help="comma-separated controller names (default: each street's list); "
                                         "always_on and oracle are added")
    c.add_argument("--sample-s", type=number(float, ge=30, le=14400, unit="s"),
                   help="simulated seconds per traffic level (default: each street's year.sample_s)")
    c.add_argument("--fidelity", choices=("full", "fast"), default="fast",
                   help="camera controllers: every frame judged (full) or the calibrated sensor model (fast)")
    c.add_argument("--min-lit-on-entry", type=number(float, ge=0, le=1), default=0.99,
                   help="the ranking's best controller must light at least this share of zone entries on entry")
    add_cache(c)
    c.add_argument("--no-progress", action="store_true", help="no progress bar")
    c.set_defaults(func=cmd_city)
