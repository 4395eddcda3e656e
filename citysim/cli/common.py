"""What every command shares: the user errors it turns into one line, the fidelity and cache options,
the controller list under --help, the longest night."""

from __future__ import annotations

import inspect
from pathlib import Path

from detector.outdir import OutputDirError

#: The longest night a scenario may have (its duration_s limit), s.
MAX_DURATION_S = 7 * 86400


def user_errors() -> tuple[type[BaseException], ...]:
    from citysim.config.scenario import ScenarioError
    from citysim.sim.loop import RunError
    from detector.camera import CameraError
    from detector.video import VideoError

    errors = [ScenarioError, RunError, CameraError, VideoError, OutputDirError]
    try:
        from citysim.sweep.runner import SweepError

        errors.append(SweepError)
    except ImportError:
        pass
    return tuple(errors)


def controller_list() -> str:
    """The registered controllers, one line each (for ``citysim run --help``)."""
    from citysim.control.registry import CONTROLLERS

    lines = ["controllers (--controllers, or the scenario's `controllers` list):"]
    for name, cls in CONTROLLERS.items():
        doc = (inspect.getdoc(cls) or "").splitlines()[0]
        fraction = getattr(cls, "fraction", None)
        if fraction is not None:  # the threshold baselines differ only in it
            doc = f"{doc.rstrip('.')}: {fraction:.1%}"
        lines.append(f"  {name:<19} {doc}")
    return "\n".join(lines)


def add_fidelity(parser, default: str) -> None:
    from citysim.fast import FIDELITIES

    parser.add_argument("--fidelity", choices=FIDELITIES, default=default,
                        help=f"full: render every judged camera frame for the real detector; fast: a sensor model "
                             f"calibrated on full-fidelity frames of this scenario's cameras (calibrated on first use; "
                             f"see citysim calibrate). Default: {default}")  # fmt: skip
    add_cache(parser)


def add_cache(parser) -> None:
    parser.add_argument("--cache", type=Path, default=None,
                        help="folder of calibrated sensor models (default: .cache/sensor_models in the project)")


