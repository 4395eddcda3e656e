"""`citysim detect VIDEO --camera CAMERA --out DIR`: the detector on a real video, as `python -m detector`.

The options are defined once, by ``detector.__main__.add_detect_arguments``, and run by its
``run_detect``: the two commands cannot drift apart.
"""

from __future__ import annotations


def cmd_detect(args) -> int:
    from detector.__main__ import interruptible, run_detect

    return interruptible(lambda: run_detect(args), args.out)


def add(sub) -> None:
    from detector.__main__ import add_detect_arguments

    d = sub.add_parser("detect", help="run the detector on a real video (same as python -m detector)",
                       description="Run the detector on a real video (same as python -m detector; "
                                   "'python -m detector calibrate' estimates the camera file).")
    add_detect_arguments(d)
    d.set_defaults(func=cmd_detect)
