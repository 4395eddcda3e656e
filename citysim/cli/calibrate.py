"""`citysim calibrate` and `citysim validate`: fit fast mode's sensor model, and compare fast against full."""

from __future__ import annotations

from pathlib import Path

from citysim.cli.common import MAX_DURATION_S, add_cache
from detector.cliargs import number


def cmd_calibrate(args) -> int:
    from citysim.config.scenario import load_scenario
    from citysim.sim.calibration import calibrate

    scenario = load_scenario(args.scenario)
    model, path = calibrate(scenario, args.cache, duration_s=args.duration, runs=args.runs,
                            progress=not args.no_progress, workers=args.workers)  # fmt: skip
    print(f"sensor model of {scenario.name}: fitted on {model.frames} judged camera frames, "
          f"{model.candidate_frames} candidate sightings; false alarms started "
          f"{model.fa_per_camera_hour:.1f} per camera-hour")
    print(f"results written to {path}")
    return 0


def cmd_validate(args) -> int:
    from citysim.config.scenario import load_scenario
    from citysim.sim.compare import controller_names, resolve_controllers
    from citysim.sim.validation import validate, validation_table

    scenario = load_scenario(args.scenario)
    names = controller_names(args.controllers)
    if names:
        resolve_controllers(scenario, names)  # unknown names fail here, before any work
    result = validate(scenario, seeds=args.seeds, duration_s=args.duration, controllers=names, cache_dir=args.cache,
                      workers=args.workers, progress=not args.no_progress)  # fmt: skip
    print(validation_table(result))
    return 0


def add(sub) -> None:
    c = sub.add_parser("calibrate", help="fit a scenario's fast-mode sensor model",
                       description="Render and detect the scenario's cameras in full fidelity on calibration seeds "
                                   "(never used for validation), busy nights and quiet nights with every lamp dim, "
                                   "fit the sensor model fast mode draws from, and "
                                   "cache it by a hash of the cameras, street, environment, traffic kinds and "
                                   "detector model.")
    c.add_argument("scenario", type=Path, help="scenario YAML file")
    add_cache(c)
    c.add_argument("--duration", type=number(float, gt=0, le=MAX_DURATION_S, unit="s"), default=120.0,
                   help="simulated seconds per calibration night")
    c.add_argument("--runs", type=number(int, ge=1), default=2,
                   help="calibration nights of each kind: busy (the lamps switched as usual) and quiet (every "
                        "lamp held dim), each on a seed of its own")
    c.add_argument("--workers", type=number(int, ge=1), default=2, help="parallel processes, one night each")
    c.add_argument("--no-progress", action="store_true", help="no progress bar")
    c.set_defaults(func=cmd_calibrate)

    v = sub.add_parser("validate", help="compare fast mode against full fidelity, per controller",
                       description="Run the scenario's controllers in full fidelity and in fast mode on the "
                                   "scenario's seed and the next ones (never calibration seeds) and print "
                                   "savings, lit on entry, lag p95 and false on-time side by side, each marked "
                                   "PASS or MISS against its tolerance.")
    v.add_argument("scenario", type=Path, help="scenario YAML file")
    v.add_argument("--duration", type=number(float, gt=0, le=MAX_DURATION_S, unit="s"), default=120.0,
                   help="simulated seconds per seed (longer: steadier figures, minutes more)")
    v.add_argument("--seeds", type=number(int, ge=1), default=2, help="validation seeds")
    v.add_argument("--controllers", help="comma-separated controller names (default: the scenario's list)")
    v.add_argument("--workers", type=number(int, ge=1), default=2, help="parallel processes for the full runs")
    add_cache(v)
    v.add_argument("--no-progress", action="store_true", help="no progress bar")
    v.set_defaults(func=cmd_validate)


