"""Sweeps on Dask: validation, one row per point and controller, resume, failed points, a real scheduler.

Tiny scenarios (2-3 lamps on a 90 m street, 20-30 simulated seconds, cheap
controllers) keep every sweep to a few seconds; the local cluster and the
separately started scheduler + worker run on loopback.
"""

from __future__ import annotations

import base64
import csv
import re
import socket
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from citysim.report.html import write_report
from citysim.sweep.runner import SweepError, load_sweep, run_sweep
from citysim.sweep.spec import point_id
from tests.citysim.streets import two_way_street

REPO = Path(__file__).resolve().parents[3]
CAMERA = REPO / "scenarios" / "cameras" / "scene_a.yaml"
TIMING_COLUMNS = ("finished_at", "wall_s")

BASE = {
    "name": "tiny",
    "seed": 7,
    "duration_s": 20,
    "street": two_way_street(90, crossings_x_m=[45]),
    "lamps": {
        "count": 3, "spacing_m": 30, "first_x_m": 15, "y_m": 6.2, "pole_height_m": 5.5,
        "camera": {"file": str(CAMERA), "tilt_deg": 15, "heading_deg": -8},
    },
    "traffic": {"classes": {"pedestrian": {"rate_per_hour": 300}, "vehicle": {"rate_per_hour": 150},
                            "cyclist": {"rate_per_hour": 40}}},
    "controllers": ["always_on", "pir"],
}  # fmt: skip

SWEEP_2X2 = {
    "name": "spacing_density",
    "base": "tiny.yaml",
    "seeds": [3],
    "controllers": ["always_on", {"name": "pir", "label": "pir_hold5", "hold_s": 5}],
    "axes": {"lamps.spacing_m": [25, 30], "traffic_density": [0.5, 2]},
    "save_objects": True,
}


def write_sweep(folder: Path, sweep: dict, base: dict = BASE) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "tiny.yaml").write_text(yaml.safe_dump(base))
    path = folder / "sweep.yaml"
    path.write_text(yaml.safe_dump(sweep))
    return path


def read_rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def without_timing(rows: list[dict[str, str]]) -> dict[tuple[str, str], dict[str, str]]:
    return {
        (r["point_id"], r["controller"]): {k: v for k, v in r.items() if k not in TIMING_COLUMNS}
        for r in rows
    }


@pytest.fixture(scope="module")
def local_sweep(tmp_path_factory):
    """The 2x2 sweep run half-way (max_points=2), then resumed, then run once more: what each run did."""
    folder = tmp_path_factory.mktemp("sweep_local")
    sweep_file = write_sweep(folder / "in", SWEEP_2X2)
    out = folder / "out"
    first = run_sweep(sweep_file, out, workers=2, progress=False, max_points=2)
    rows_first = read_rows(out / "results.csv")
    second = run_sweep(sweep_file, out, workers=2, progress=False)
    rows_second = read_rows(out / "results.csv")
    text_second = (out / "results.csv").read_bytes()
    third = run_sweep(sweep_file, out, workers=2, progress=False)
    return {
        "sweep_file": sweep_file, "out": out, "runs": (first, second, third),
        "rows_first": rows_first, "rows_second": rows_second, "text_second": text_second,
    }  # fmt: skip


def test_two_by_two_sweep_has_one_row_per_point_and_controller(local_sweep):
    rows = local_sweep["rows_second"]
    resolved = load_sweep(local_sweep["sweep_file"])
    points = resolved.points()
    assert len(points) == 4
    assert sorted((r["point_id"], r["controller"]) for r in rows) == sorted(
        (p.point_id, c) for p in points for c in ("always_on", "pir_hold5")
    )
    by_id = {p.point_id: p for p in points}
    for r in rows:
        point = by_id[r["point_id"]]
        assert r["point_id"] == point_id(point.axes, int(r["seed"]))
        assert float(r["lamps.spacing_m"]) == point.axes["lamps.spacing_m"]
        assert float(r["traffic_density"]) == point.axes["traffic_density"]
        assert r["status"] == "ok", r["error"]
        assert float(r["duration_s"]) == 20.0
        if r["controller"] == "always_on":
            assert float(r["savings_vs_always_on"]) == 0.0
            # 3 lamps x 60 W x 20 s, nothing else: the always-on reference
            assert float(r["energy_kwh"]) == pytest.approx(3 * 60 * 20 / 3.6e6, rel=1e-9)
        else:
            assert 0.0 < float(r["savings_vs_always_on"]) < 1.0
    # denser traffic keeps PIR lamps lit longer: less saved, on every spacing
    savings = {(float(r["lamps.spacing_m"]), float(r["traffic_density"])): float(r["savings_vs_always_on"])
               for r in rows if r["controller"] == "pir_hold5"}  # fmt: skip
    for spacing in (25.0, 30.0):
        assert savings[(spacing, 2.0)] < savings[(spacing, 0.5)]
    sweep_json = (local_sweep["out"] / "sweep.json").read_text()
    assert '"traffic_density"' in sweep_json and '"points": 4' in sweep_json


def test_interrupted_sweep_resumes_without_recomputing(local_sweep):
    first, second, third = local_sweep["runs"]
    assert (first["ran"], first["skipped"]) == (2, 0)
    assert (second["ran"], second["skipped"]) == (2, 2)
    assert (third["ran"], third["skipped"]) == (0, 4)
    rows_first, rows_second = local_sweep["rows_first"], local_sweep["rows_second"]
    assert len(rows_first) == 2 * 2 and len(rows_second) == 4 * 2
    # append-only file: the rows of the first run are untouched (same timestamps, same figures)
    # and each (point, controller) appears once, so no finished point ran again
    assert rows_second[: len(rows_first)] == rows_first
    assert len({(r["point_id"], r["controller"]) for r in rows_second}) == len(rows_second)
    later = {r["finished_at"] for r in rows_second[len(rows_first) :]}
    assert min(later) > max(r["finished_at"] for r in rows_first)
    assert (local_sweep["out"] / "results.csv").read_bytes() == local_sweep["text_second"]


def test_invalid_point_is_recorded_as_failed_and_the_rest_finish(tmp_path):
    sweep = {
        "name": "lamp_count", "base": "tiny.yaml", "duration_s": 10, "controllers": ["always_on", "pir"],
        "set": {"lamps.count": 2},
        # 5 lamps 30 m apart from x = 15 m do not fit on a 90 m street
        "axes": {"lamps.count": [2, 5]}, "save_objects": False,
    }  # fmt: skip
    out = tmp_path / "out"
    counts = run_sweep(write_sweep(tmp_path / "in", sweep), out, workers=1, progress=False)
    assert (counts["ok"], counts["failed"], counts["ran"]) == (1, 1, 2)
    rows = read_rows(out / "results.csv")
    assert len(rows) == 4
    by_count = {}
    for r in rows:
        by_count.setdefault(r["lamps.count"], []).append(r)
    assert {r["status"] for r in by_count["2"]} == {"ok"}
    assert {r["status"] for r in by_count["5"]} == {"failed"}
    for r in by_count["5"]:
        assert "lamps.count" in r["error"] and "outside the street" in r["error"]
        assert r["energy_kwh"] == ""
    assert all(float(r["energy_kwh"]) > 0 for r in by_count["2"])


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _dask_cli(*args: str) -> list[str]:
    exe = Path(sys.executable).parent / "dask"
    return [str(exe), *args] if exe.exists() else [sys.executable, "-m", "dask", *args]


@pytest.fixture
def loopback_cluster(tmp_path):
    """A `dask scheduler` and one `dask worker` started as subprocesses on 127.0.0.1; torn down after."""
    from distributed import Client

    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    logs = [open(tmp_path / name, "w") for name in ("scheduler.log", "worker.log")]  # noqa: SIM115
    procs = [subprocess.Popen(_dask_cli("scheduler", "--host", "127.0.0.1", "--port", str(port),
                                        "--no-dashboard", "--dashboard-address", "127.0.0.1:0"), stdout=logs[0], stderr=subprocess.STDOUT, cwd=REPO)]  # fmt: skip
    try:
        procs.append(subprocess.Popen(_dask_cli("worker", address, "--nthreads", "1", "--nworkers", "1",
                                                "--host", "127.0.0.1", "--no-dashboard", "--dashboard-address", "127.0.0.1:0"),
                                      stdout=logs[1], stderr=subprocess.STDOUT, cwd=REPO))  # fmt: skip
        deadline = time.monotonic() + 60
        while True:
            try:
                with Client(address, timeout="5s") as client:
                    client.wait_for_workers(1, timeout=max(1.0, deadline - time.monotonic()))
                break
            except OSError:
                if time.monotonic() > deadline or any(p.poll() is not None for p in procs):
                    raise
                time.sleep(0.5)
        yield address
    finally:
        try:  # a scheduler shutdown stops its workers too, faster than signals
            with Client(address, timeout="5s") as client:
                client.shutdown()
        except OSError:
            pass
        for p in reversed(procs):
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.terminate()
        for p in reversed(procs):
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
        for f in logs:
            f.close()


def test_scheduler_address_gives_the_same_rows_as_the_local_cluster(
    local_sweep, loopback_cluster, tmp_path
):
    out = tmp_path / "out"
    # the same sweep without the per-point run files: the rows must not change
    sweep_file = write_sweep(tmp_path / "in", {**SWEEP_2X2, "save_objects": False})
    counts = run_sweep(sweep_file, out, scheduler=loopback_cluster, progress=False)
    assert (counts["ran"], counts["ok"]) == (4, 4)
    remote = without_timing(read_rows(out / "results.csv"))
    local = without_timing(local_sweep["rows_second"])
    assert remote == local


def test_sweep_plots_and_report(local_sweep):
    out = local_sweep["out"]
    report = write_report(out)
    plots = sorted((out / "plots").glob("*.png"))
    names = {p.name for p in plots}
    assert {"vs_lamps_spacing_m.png", "vs_traffic_density.png", "heatmap_savings.png",
            "heatmap_lag_p95.png", "energy_per_hour.png", "lag_cdf.png"} <= names  # fmt: skip
    # pir reports no detection figures: those heatmaps are skipped with a note, not drawn empty
    assert "heatmap_false_negative_rate.png" not in names
    assert "false negative" in (out / "plots" / "notes.txt").read_text()
    html = report.read_text()
    uris = re.findall(r'<img alt="([^"]+)" src="data:image/png;base64,([^"]+)"', html)
    assert sorted(name for name, _ in uris) == sorted(names)
    for name, data in uris:
        image = cv2.imdecode(np.frombuffer(base64.b64decode(data), np.uint8), cv2.IMREAD_GRAYSCALE)
        on_disk = cv2.imread(str(out / "plots" / name), cv2.IMREAD_GRAYSCALE)
        assert image is not None and np.array_equal(image, on_disk)
        assert (image < 200).mean() > 0.02 and len(np.unique(image)) > 20
    assert "Best settings" in html and "pir_hold5" in html


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        (
            {"axes": {"lamps.camera.heigth_m": [2, 4]}},
            "axes.lamps.camera.heigth_m: 'heigth_m' is not a field of lamps.camera; did you mean height_m",
        ),
        (
            {"axes": {"lamps.spacing_m": []}},
            "axes: axis 'lamps.spacing_m' needs at least one value",
        ),
        ({"seeds": [1, 1]}, "seeds: seeds must be distinct"),
        ({"controllers": ["always_on", "lighthouse"]}, "controllers.1.name: unknown 'lighthouse'"),
        ({"colour": "red"}, "colour: unknown field"),
        ({"controlers": ["always_on"]}, "controlers: unknown field; did you mean controllers?"),
        ({"axes": {"seed": [1, 2]}}, "axes.seed: use the sweep's own `seeds` key"),
        ({"base": "missing.yaml"}, "scenario file not found"),
        ({"set": {"lamps.count": 0}}, "lamps.count"),
    ],
)
def test_bad_sweep_file_names_the_file_and_field(tmp_path, change, expected):
    sweep = {**SWEEP_2X2, **change}
    path = write_sweep(tmp_path, sweep)
    with pytest.raises(SweepError) as info:
        run_sweep(path, tmp_path / "out", progress=False)
    message = str(info.value)
    assert message.startswith(str(path)) and expected in message, message
    assert isinstance(info.value, ValueError)
    assert not (tmp_path / "out" / "results.csv").exists()


def test_results_of_a_different_sweep_are_not_mixed(local_sweep, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "sweep.json").write_text((local_sweep["out"] / "sweep.json").read_text())
    changed = write_sweep(tmp_path / "in", {**SWEEP_2X2, "duration_s": 15})
    with pytest.raises(SweepError, match="different sweep"):
        run_sweep(changed, out, progress=False)


def test_point_ids_depend_on_values_and_seed_only():
    a = point_id({"lamps.camera.height_m": 4, "traffic_density": 1.5}, 1)
    assert a == point_id({"traffic_density": 1.5, "lamps.camera.height_m": 4}, 1)
    assert a != point_id({"lamps.camera.height_m": 4, "traffic_density": 1.5}, 2)
    assert a != point_id({"lamps.camera.height_m": 6, "traffic_density": 1.5}, 1)
    assert re.fullmatch(r"[0-9a-f]{12}", a)


def test_results_file_drops_rows_cut_short_by_a_crash(tmp_path):
    from citysim.sweep.results import ResultsFile

    path = tmp_path / "results.csv"
    table = ResultsFile(path, ["traffic_density"])
    done = [{"point_id": "a", "traffic_density": 1, "seed": 1, "controller": c, "status": "ok",
             "error": "", "energy_kwh": 0.25 + i} for i, c in enumerate(("always_on", "pir"))]  # fmt: skip
    table.append(done)
    half = {**done[0], "point_id": "b"}  # the crash came before the point's second row
    table.append([half])
    with open(path, "a") as f:
        f.write("c,2,1,always_on,o")  # and a row cut in the middle of a cell
    reopened = ResultsFile(path, ["traffic_density"])
    assert reopened.finished_points(["always_on", "pir"]) == {"a": "ok"}
    assert [r["energy_kwh"] for r in reopened.rows] == ["0.25", "1.25", "0.25"]
    reopened.drop_points({"b"})
    assert [r["point_id"] for r in read_rows(path)] == ["a", "a"]


def test_bad_worker_count_and_unreachable_scheduler_are_user_errors(tmp_path, monkeypatch):
    import citysim.sweep.runner

    sweep_file = write_sweep(tmp_path / "in", SWEEP_2X2)
    with pytest.raises(SweepError, match="workers: a whole number >= 1, got 0"):
        run_sweep(sweep_file, tmp_path / "a", workers=0, progress=False)
    monkeypatch.setattr(citysim.sweep.runner, "SCHEDULER_TIMEOUT_S", 1.0)
    nobody = f"tcp://127.0.0.1:{_free_port()}"
    with pytest.raises(SweepError, match=f"scheduler '{nobody}': cannot connect"):
        run_sweep(sweep_file, tmp_path / "b", scheduler=nobody, progress=False)
    assert not (tmp_path / "b" / "results.csv").exists()
