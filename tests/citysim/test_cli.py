"""`citysim run | render | plot` as a user meets them: outputs, and one clear error (exit 2) for bad input."""

import csv
import json
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from citysim.cli import main
from tests.citysim.streets import two_way_street
from tests.folders import unwritable_folder

REPO = Path(__file__).resolve().parents[2]


def tiny(tmp_path: Path, **changes) -> Path:
    """Three lamps on a 100 m street with some traffic; written next to a copy of the scene-B camera."""
    data = {
        "name": "tiny",
        "seed": 3,
        "duration_s": 20.0,
        "street": two_way_street(100),
        "lamps": {"count": 3, "spacing_m": 30, "first_x_m": 20, "y_m": 6.2, "pole_height_m": 4.0,
                  "camera": {"file": "scene_b.yaml", "heading_deg": -10, "tilt_deg": 15}},
        "traffic": {"classes": {"pedestrian": {"rate_per_hour": 600}, "vehicle": {"rate_per_hour": 300}}},
        "controllers": ["always_on", "pir", "detector"],
    }
    for dotted, value in changes.items():
        node = data
        *head, last = dotted.split(".")
        for key in head:
            node = node.setdefault(key, {})
        node[last] = value
    (tmp_path / "scene_b.yaml").write_text((REPO / "scenarios" / "cameras" / "scene_b.yaml").read_text())
    path = tmp_path / "tiny.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "citysim", *args], capture_output=True, text=True, cwd=REPO)


def is_real_plot(path: Path) -> bool:
    img = cv2.imread(str(path))
    return img is not None and img.shape[0] > 100 and np.unique(img.reshape(-1, 3), axis=0).shape[0] > 20


@pytest.mark.slow
def test_run_writes_summary_tables_and_plots(tmp_path):
    out = tmp_path / "run"
    assert main(["run", str(tiny(tmp_path)), "--out", str(out), "--no-progress", "--workers", "1"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["seed"] == 3 and summary["duration_s"] == 20.0
    # always_on and the oracle join every comparison, first
    assert list(summary["controllers"]) == ["always_on", "oracle", "pir", "detector"]
    for name, c in summary["controllers"].items():
        for key in ("energy_kwh", "savings_vs_always_on", "savings_vs_oracle", "lit_on_entry_rate", "lag_p50_s", "lag_p95_s", "lag_max_s", "dark_exposure_s",
                    "unlit_crossings", "switches", "detection"):
            assert key in c, (name, key)
    assert summary["controllers"]["always_on"]["savings_vs_always_on"] == pytest.approx(0.0, abs=1e-12)
    assert summary["controllers"]["detector"]["detection"]["frames"] > 0
    with open(out / "lamps.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0]) == ["controller", "t_s", "lamp", "level", "power_w"]
    assert len(rows) == 4 * 3 * 20  # four controllers, three lamps, one row per simulated second
    with open(out / "objects.csv") as fh:
        assert fh.readline().strip().split(",")[:4] == ["controller", "object_id", "cls", "lamp"]
    plots = sorted((out / "plots").glob("*.png"))
    assert len(plots) >= 3 and all(is_real_plot(p) for p in plots)
    assert not list(tmp_path.glob(".run.partial-*"))


def test_render_writes_video_truth_and_topdown(tmp_path):
    out = tmp_path / "cam"
    assert main(["render", str(tiny(tmp_path)), "--lamp", "1", "--duration", "4", "--out", str(out), "--detect",
                 "--no-progress"]) == 0
    cap = cv2.VideoCapture(str(out / "camera.mp4"))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 60
    with open(out / "truth.csv") as fh:
        assert fh.readline().strip() == "frame,t_s,object_id,cls,x,y,w,h,touches_border"
    assert is_real_plot(out / "topdown.png")


def test_render_films_a_poles_backward_camera(tmp_path):
    # the camera looks along -x (heading 170 deg): the truth boxes are those of another view
    scenario = tiny(tmp_path, **{"lamps.camera.back_heading_deg": 170})
    outs = {side: tmp_path / side for side in ("forward", "backward")}
    for side, out in outs.items():
        assert main(["render", str(scenario), "--lamp", "2", "--duration", "10", "--camera", side, "--out", str(out),
                     "--no-progress"]) == 0
    truth = {side: (out / "truth.csv").read_text().splitlines()[1:] for side, out in outs.items()}
    assert truth["forward"] and truth["backward"] and truth["forward"] != truth["backward"]


@pytest.mark.parametrize(
    ("change", "needles"),
    [
        ({"lamps.luminaire.rated_power_w": -60}, ["lamps.luminaire.rated_power_w", "greater than 0"]),
        ({"lamps.luminaire.hold_s": 0.01}, ["lamps.luminaire.hold_s", "one camera frame"]),
        ({"lamps.colour": "red"}, ["lamps.colour", "unknown field"]),
        ({"traffic.classes.vehicle.speed_kmh": {"min": -5, "max": 40}}, ["traffic.classes.vehicle.speed_kmh.min"]),
        ({"controllers": ["always_on", "magic"]}, ["controllers", "magic", "detector_network"]),
        ({"lamps.camera.tilt_deg": -40}, ["lamps.camera", "tilt_deg"]),
    ],
)
def test_bad_scenario_is_one_clear_error_and_exit_2(tmp_path, change, needles):
    out = tmp_path / "run"
    res = cli("run", str(tiny(tmp_path, **change)), "--out", str(out), "--no-progress")
    assert res.returncode == 2, res.stderr
    message = res.stderr.strip()
    assert message.count("\n") == 0 and "Traceback" not in message, message
    assert "tiny.yaml" in message or "controllers" in message
    for needle in needles:
        assert needle in message, message
    assert not out.exists()


def test_unknown_controller_on_the_command_line(tmp_path):
    res = cli("run", str(tiny(tmp_path)), "--out", str(tmp_path / "o"), "--controllers", "always_on,nope")
    assert res.returncode == 2 and "controllers: unknown 'nope'; valid: always_on, oracle" in res.stderr


@pytest.mark.parametrize(("argv", "needles"), [
    (["run", "{tiny}", "--out", "{out}", "--controllers", "detector_locatd"],
     ["controllers: unknown 'detector_locatd'; did you mean detector_located"]),
    (["run", "{tmp}/tiny.yml", "--out", "{out}"], ["tiny.yml: scenario file not found; did you mean {tmp}/tiny.yaml?"]),
    (["sweep", "{tiny}", "--out", "{out}", "--fidelity", "fas"], ["invalid choice: 'fas'", "did you mean 'fast'?"]),
    (["rn", "{tiny}"], ["invalid choice: 'rn'", "did you mean 'run'?"]),
])  # fmt: skip
def test_a_near_miss_is_named(tmp_path, capsys, argv, needles):
    """A misspelt controller, scenario file, choice or command: one line, exit 2, the nearest valid name."""
    fill = {"tiny": str(tiny(tmp_path)), "out": str(tmp_path / "o"), "tmp": str(tmp_path)}
    with pytest.raises(SystemExit) as stop:
        code = main([a.format(**fill) for a in argv])
        raise SystemExit(code)
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    for needle in needles:
        assert needle.format(**fill) in err, err
    assert not (tmp_path / "o").exists()


# ------------------------------------------------- arguments and --out checked before any simulation
def run_main(capsys, argv: list[str]) -> tuple[int, str]:
    """citysim's main(argv) in this process: (exit code, stderr)."""
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse refuses while reading the command line
        code = exc.code
    return code, capsys.readouterr().err.strip()


def tree(folder: Path) -> dict[str, bytes | None]:
    return {str(p.relative_to(folder)): p.read_bytes() if p.is_file() else None for p in folder.rglob("*")}


@pytest.fixture
def no_simulation(monkeypatch):
    """Fail the test if a night is built, a run or sweep starts, or the detector opens a video."""

    def boom(*args, **kwargs):
        raise AssertionError("work started before the arguments were checked")

    for target in ("citysim.sim.compare.run_comparison", "citysim.report.clip.build_night",
                   "citysim.sweep.runner.run_sweep", "detector.__main__.detect_video"):
        monkeypatch.setattr(target, boom)


BAD_NUMBERS = [
    (["run", "{scenario}", "--workers", "0"], ["argument --workers", "must be >= 1, got 0"]),
    (["run", "{scenario}", "--duration", "0"], ["argument --duration", "> 0"]),
    (["run", "{scenario}", "--duration", "-5"], ["argument --duration", "> 0"]),
    (["run", "{scenario}", "--duration", "1e9"], ["argument --duration", "<= 604800 s"]),
    (["run", "{scenario}", "--seed", "-1"], ["argument --seed", "must be >= 0"]),
    (["run", "{scenario}", "--seed", "1.5"], ["argument --seed", "whole number"]),
    (["render", "{scenario}", "--lamp", "-1"], ["argument --lamp", ">= 0"]),
    (["render", "{scenario}", "--lamp", "3"], ["--lamp", "must be in 0..2"]),  # tiny has 3 lamps
    (["render", "{scenario}", "--duration", "0"], ["argument --duration", "> 0"]),
    (["render", "{scenario}", "--camera", "left"], ["argument --camera", "forward", "backward"]),
    (["render", "{scenario}", "--camera", "backward"], ["--camera", "no backward cameras", "back_heading_deg"]),
    (["render", "{scenario}", "--start", "-1"], ["argument --start", ">= 0"]),
    (["render", "{scenario}", "--start", "20"], ["--start", "< 20 s"]),  # tiny's night is 20 s
    (["sweep", "{scenario}", "--workers", "0"], ["argument --workers", ">= 1"]),
    (["detect", "v.mp4", "--camera", "c.yaml", "--max-width", "10"], ["argument --max-width", ">= 64"]),
    (["detect", "v.mp4", "--camera", "c.yaml", "--max-distance-m", "0"], ["argument --max-distance-m", "> 0"]),
]


@pytest.mark.parametrize(("argv", "needles"), BAD_NUMBERS, ids=[" ".join(a[0:1] + a[2:]) for a, _ in BAD_NUMBERS])
def test_bad_numbers_are_one_line_before_any_simulation(tmp_path, capsys, no_simulation, argv, needles):
    scenario = tiny(tmp_path)
    before = tree(tmp_path)
    out = tmp_path / "out"
    code, err = run_main(capsys, [a.format(scenario=scenario) for a in argv] + ["--out", str(out)])
    assert code == 2, err
    assert err.count("\n") == 0 and "Traceback" not in err, err
    for needle in needles:
        assert needle in err, err
    assert tree(tmp_path) == before  # no output, no hidden .partial folder


def folder_with(path: Path, *names: str) -> Path:
    path.mkdir()
    for name in names:
        if name.endswith("/"):
            (path / name).mkdir()
        else:
            (path / name).write_text("x\n")
    return path


BAD_OUTS = {
    "a file": lambda tmp: (tmp / "o.txt").write_text("x\n") and tmp / "o.txt",
    "random files": lambda tmp: folder_with(tmp / "mine", "thesis.tex", "data/"),
    "a sweep folder": lambda tmp: folder_with(tmp / "sw", "sweep.json", "results.csv", "points/"),
    "a run folder": lambda tmp: folder_with(tmp / "run", "summary.json", "objects.csv", "lamps.csv", "plots/"),
    "a render folder": lambda tmp: folder_with(tmp / "cam", "camera.mp4", "truth.csv", "topdown.png"),
    "unwritable": lambda tmp: unwritable_folder(tmp) / "out",
}
OUT_CASES = [
    ("run", "a file", "is a file"), ("run", "random files", "thesis.tex"), ("run", "a sweep folder", "sweep.json"),
    ("run", "a render folder", "camera.mp4"), ("run", "unwritable", "cannot write in"),
    ("render", "a file", "is a file"), ("render", "a run folder", "summary.json"),
    ("render", "unwritable", "cannot write in"),
    ("sweep", "random files", "thesis.tex"), ("sweep", "a run folder", "lamps.csv"), ("sweep", "a file", "is a file"),
    ("detect", "a run folder", "lamps.csv"),
]


@pytest.mark.parametrize(("command", "out_kind", "says"), OUT_CASES, ids=[f"{c}-{k}" for c, k, _ in OUT_CASES])
def test_an_out_that_cannot_be_used_is_refused_before_any_simulation(tmp_path, capsys, no_simulation, command,
                                                                     out_kind, says):
    scenario = tiny(tmp_path)
    out = BAD_OUTS[out_kind](tmp_path)
    before = tree(tmp_path)
    first = ["v.mp4", "--camera", "c.yaml"] if command == "detect" else [str(scenario)]
    code, err = run_main(capsys, [command, *first, "--out", str(out)])
    assert code == 2, err
    assert err.count("\n") == 0 and "Traceback" not in err, err
    assert err.startswith("error: --out: ") and says in err, err
    assert "valid:" in err, err
    assert tree(tmp_path) == before  # nothing written, no hidden .partial folder


def test_an_earlier_folder_of_the_same_kind_is_accepted(tmp_path, capsys, monkeypatch):
    """A run folder may be run into again (replaced); a sweep folder resumes."""
    calls = []
    summary = {"scenario": "tiny", "duration_s": 20.0, "seed": 3, "controllers": {"always_on": {
        "energy_kwh": 1.0, "savings_vs_always_on": 0.0, "lag_p50_s": None, "lag_p95_s": None, "lag_max_s": None,
        "dark_exposure_s": 0.0, "unlit_crossings": 0, "switches": 0, "false_on_time_s": 0.0}}}
    monkeypatch.setattr("citysim.sim.compare.run_comparison", lambda *a, **k: calls.append(k["out_dir"]) or summary)
    monkeypatch.setattr("citysim.report.run_plots.plot_run", lambda folder: [])
    monkeypatch.setattr("citysim.report.topdown.plot_coverage_map", lambda street, path: path)
    run = folder_with(tmp_path / "run", "summary.json", "objects.csv", "lamps.csv", "plots/", "report.html")
    assert main(["run", str(tiny(tmp_path)), "--out", str(run), "--no-progress"]) == 0
    counts = {"points": 4, "ran": 2, "ok": 2, "failed": 0, "skipped": 2, "results": tmp_path / "sw" / "results.csv"}
    monkeypatch.setattr("citysim.sweep.runner.run_sweep", lambda sweep, out, **k: calls.append(out) or counts)
    sweep = folder_with(tmp_path / "sw", "sweep.json", "results.csv", "points/", "plots/", "report.html")
    assert main(["sweep", "s.yaml", "--out", str(sweep), "--no-progress"]) == 0
    # the run is built under its own name in a hidden folder beside it, then renamed into place
    assert calls[0].name == run.name and calls[0].parent.name.startswith(".run.partial-") and calls[1] == sweep
    assert run.is_dir() and sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".run")) == []
    assert "2 already done" in capsys.readouterr().out


def test_render_starts_where_asked(tmp_path):
    out = tmp_path / "cam"
    assert main(["render", str(tiny(tmp_path)), "--lamp", "1", "--start", "5", "--duration", "1", "--out", str(out),
                 "--no-progress"]) == 0
    with open(out / "truth.csv") as fh:
        times = [float(r["t_s"]) for r in csv.DictReader(fh)]
    cap = cv2.VideoCapture(str(out / "camera.mp4"))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 15
    assert times and min(times) >= 5.0 and max(times) < 6.0


def test_run_help_explains_the_arguments_and_lists_the_controllers(capsys):
    from citysim.control.registry import CONTROLLERS

    with pytest.raises(SystemExit) as info:
        main(["run", "--help"])
    assert info.value.code == 0
    text = capsys.readouterr().out
    for needle in ("scenario YAML file", "--out", "run folder", "--seed", "random seed", "--controllers",
                   "comma-separated", "--workers", "(default: 2"):
        assert needle in text, needle
    for name in CONTROLLERS:
        assert f"\n  {name} " in text, name


def test_every_argument_of_every_command_has_help(capsys):
    import argparse

    from citysim.cli import build_parser
    from detector.__main__ import _detect_parser, _train_parser

    commands = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)).choices
    for name, parser in {**commands, "detector": _detect_parser(), "detector train": _train_parser()}.items():
        for action in parser._actions:
            assert action.help, (name, action.dest)
    with pytest.raises(SystemExit):
        main(["render", "--help"])
    text = capsys.readouterr().out
    assert "--start START" in text and "(default: 0.0)" in text and "(default: 20.0)" in text


def test_detector_help_shows_train_and_defaults():
    res = subprocess.run([sys.executable, "-m", "detector", "--help"], capture_output=True, text=True, cwd=REPO)
    assert res.returncode == 0
    usage = res.stdout.split("\n\n")[0]
    assert "python -m detector train" in usage, usage
    assert "(default: 424)" in res.stdout and "(default: 25.0)" in res.stdout


def test_scenario_typo_on_the_command_line_suggests_the_field(tmp_path):
    res = cli("run", str(tiny(tmp_path, **{"lamps.luminaire.dim_levle": 0.2})), "--out", str(tmp_path / "o"))
    assert res.returncode == 2
    assert "lamps.luminaire.dim_levle: unknown field; did you mean dim_level?" in res.stderr, res.stderr
    assert not (tmp_path / "o").exists()


def test_a_run_stopped_by_sigterm_leaves_no_half_written_output(tmp_path):
    """`kill` (SIGTERM) mid-run: the process ends with 143 and removes its staging folder, as Ctrl-C does."""
    import signal
    import time

    out = tmp_path / "run"
    proc = subprocess.Popen(
        [sys.executable, "-m", "citysim", "run", str(tiny(tmp_path, duration_s=3600.0)), "--out", str(out),
         "--no-progress", "--workers", "1", "--controllers", "always_on"],
        cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        deadline = time.monotonic() + 60.0
        while not list(tmp_path.glob(".run.partial-*")) and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.05)
        assert list(tmp_path.glob(".run.partial-*")), "the run never started writing"
        time.sleep(0.5)  # well into the simulation
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=60) == 143, proc.stderr.read()
    finally:
        proc.kill()
    assert not out.exists()
    assert not list(tmp_path.glob(".run.partial-*"))
