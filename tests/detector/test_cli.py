"""`python -m detector VIDEO --camera CAM --out DIR` on videos made here, and its user errors."""

import csv
import json
import math
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from detector.__main__ import CSV_HEADER, main
from detector.camera import CameraModel
from detector.train.shapes import pedestrian_shape, silhouette_mask
from tests.folders import unwritable_folder

SCENE_B = dict(height_m=3.1, tilt_deg=22.0, focal_mm=0.73, sensor_w_mm=0.7, sensor_h_mm=0.52, width_px=320,
               height_px=240, fps=15.0)
FORWARD_M = 10.0
REPO = Path(__file__).resolve().parents[2]


def write_walker_video(path: Path, camera: CameraModel, forward_m: float, n_frames: int = 90) -> None:
    """A 1.75 m walker crossing the view at a fixed forward distance, on a dark noisy ground."""
    rng = np.random.default_rng(3)
    base = np.full((camera.height_px, camera.width_px), 40, np.uint8)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), camera.fps, (camera.width_px, camera.height_px))
    assert writer.isOpened()
    speed_mps, step_m = 1.4, 0.7
    for k in range(n_frames):
        lateral_m = 3.0 - speed_mps * k / camera.fps  # walks from left (+y) to right
        phase = 2 * math.pi * (speed_mps * k / camera.fps) / (2 * step_m)
        frame = base.copy()
        shape = pedestrian_shape(forward_m, lateral_m, -math.pi / 2, 0.5, 1.75, step_m, phase)
        sil = silhouette_mask(camera, shape)
        if sil is not None:
            x0, y0 = sil.offset_px
            h, w = sil.mask.shape
            frame[y0 : y0 + h, x0 : x0 + w][sil.mask > 0] = 190
        noisy = np.clip(frame + rng.normal(0, 2.5, frame.shape), 0, 255).astype(np.uint8)
        writer.write(cv2.cvtColor(noisy, cv2.COLOR_GRAY2BGR))
    writer.release()


@pytest.fixture(scope="module")
def scene_b_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cli")
    camera = CameraModel(**SCENE_B)
    (folder / "cam.yaml").write_text(yaml.safe_dump(SCENE_B))
    write_walker_video(folder / "walker.mp4", camera, FORWARD_M)
    return folder


def read_rows(path: Path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_cli_detects_a_walker_at_its_distance_as_a_pedestrian(scene_b_files):
    out = scene_b_files / "out"
    assert main([str(scene_b_files / "walker.mp4"), "--camera", str(scene_b_files / "cam.yaml"), "--out", str(out),
                 "--no-progress"]) == 0
    with open(out / "detections.csv") as fh:
        assert fh.readline().strip().split(",") == CSV_HEADER
    rows = read_rows(out / "detections.csv")
    targets = [r for r in rows if r["frame_cls"] != "noise"]
    frames_with_target = {int(r["frame"]) for r in targets}
    # the walker is whole in view for most of the clip; MOG2 needs a few frames to learn the ground
    in_view = 0
    camera = CameraModel(**SCENE_B)
    for k in range(90):
        shape = pedestrian_shape(FORWARD_M, 3.0 - 1.4 * k / 15, -math.pi / 2, 0.5, 1.75, 0.7, 0.0)
        sil = silhouette_mask(camera, shape)
        in_view += sil is not None and not sil.touches_border and k >= 5
    assert len(frames_with_target) >= 0.8 * in_view, (len(frames_with_target), in_view)
    distance = np.array([float(r["distance_m"]) for r in targets])
    assert np.median(np.abs(distance - FORWARD_M) / FORWARD_M) < 0.10
    assert np.mean(np.abs(distance - FORWARD_M) / FORWARD_M < 0.10) > 0.8
    classes = [r["frame_cls"] for r in targets]
    assert classes.count("pedestrian") / len(classes) > 0.7, classes
    cap = cv2.VideoCapture(str(out / "annotated.mp4"))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 90
    # one track for the one walker, a pedestrian crossing at 1.4 m/s 10 m ahead of the pole
    tracked = [r for r in targets if r["target_cls"] == "pedestrian"]
    assert len(tracked) >= 0.8 * len(targets) and len({r["track_id"] for r in tracked}) == 1
    assert np.median([float(r["speed_mps"]) for r in tracked if r["speed_mps"]]) == pytest.approx(1.4, abs=0.2)
    assert np.median([float(r["ground_x_m"]) for r in tracked]) == pytest.approx(FORWARD_M, rel=0.1)
    tracks = read_rows(out / "tracks.csv")
    walker = [t for t in tracks if t["cls"] == "pedestrian"]
    assert len(walker) == 1 and walker[0]["reject_reason"] == ""
    assert int(walker[0]["frames_seen"]) >= 0.8 * in_view
    assert float(walker[0]["mean_speed_mps"]) == pytest.approx(1.4, abs=0.2)
    assert all(t["reject_reason"] for t in tracks if t["cls"] == "noise")
    # one answer: the target column is the track's decision, and summary.json counts the CSV's rows
    assert all(r["target"] == ("0" if r["target_cls"] == "noise" else "1") for r in rows)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["frames_with_target"] == len({r["frame"] for r in rows if r["target"] == "1"}) > 0
    per_class: dict[str, int] = {}
    for r in rows:
        if r["target"] == "1":
            per_class[r["target_cls"]] = per_class.get(r["target_cls"], 0) + 1
    assert summary["target_rows_per_class"] == per_class



def test_no_video_writes_the_same_results_without_the_annotated_video(scene_b_files, capsys):
    with_video, without = scene_b_files / "with", scene_b_files / "without"
    common = ["--camera", str(scene_b_files / "cam.yaml"), "--no-progress"]
    assert main([str(scene_b_files / "walker.mp4"), *common, "--out", str(with_video)]) == 0
    assert main([str(scene_b_files / "walker.mp4"), *common, "--out", str(without), "--no-video"]) == 0
    assert "annotated.mp4" not in capsys.readouterr().out.splitlines()[-1]
    assert (with_video / "annotated.mp4").exists() and not (without / "annotated.mp4").exists()
    for name in ("detections.csv", "tracks.csv"):
        assert (without / name).read_text() == (with_video / name).read_text()
    assert json.loads((without / "summary.json").read_text())["annotated_video"] is None

def test_full_frame_segments_everything_and_says_so(scene_b_files):
    """Scene B's band is the whole frame already (its range covers every row): --full-frame gives
    the same detections and tracks, and summary.json says what was segmented."""
    band, whole = scene_b_files / "band", scene_b_files / "whole"
    common = ["--camera", str(scene_b_files / "cam.yaml"), "--no-progress", "--no-video"]
    assert main([str(scene_b_files / "walker.mp4"), *common, "--out", str(band)]) == 0
    assert main([str(scene_b_files / "walker.mp4"), *common, "--out", str(whole), "--full-frame"]) == 0
    for name in ("detections.csv", "tracks.csv"):
        assert (whole / name).read_text() == (band / name).read_text()
    summaries = [json.loads((d / "summary.json").read_text()) for d in (band, whole)]
    assert [s["full_frame"] for s in summaries] == [False, True]
    assert summaries[1]["segmented_px"] == {"rows": [0, SCENE_B["height_px"]], "columns": [0, SCENE_B["width_px"]]}


def run_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "detector", *args], capture_output=True, text=True)


def assert_clean_failure(res: subprocess.CompletedProcess, out: Path, *needles: str) -> None:
    assert res.returncode == 2, res.stderr
    line = res.stderr.strip()
    assert "Traceback" not in line and line.count("\n") == 0, line
    for needle in needles:
        assert needle in line, line
    assert not out.exists()
    assert not list(out.parent.glob(f".{out.name}.partial-*"))


def test_missing_video_is_one_clear_error_and_writes_nothing(scene_b_files, tmp_path):
    out = tmp_path / "out"
    res = run_cli(str(tmp_path / "nope.mp4"), "--camera", str(scene_b_files / "cam.yaml"), "--out", str(out))
    assert_clean_failure(res, out, "nope.mp4", "not found")


def test_corrupt_video_is_one_clear_error(scene_b_files, tmp_path):
    bad = tmp_path / "corrupt.mp4"
    bad.write_bytes(np.random.default_rng(0).integers(0, 256, 20000, dtype=np.uint8).tobytes())
    out = tmp_path / "out"
    res = run_cli(str(bad), "--camera", str(scene_b_files / "cam.yaml"), "--out", str(out))
    assert_clean_failure(res, out, "corrupt.mp4")


def test_camera_file_with_a_wrong_field_names_it(scene_b_files, tmp_path):
    cam = tmp_path / "typo.yaml"
    cam.write_text(yaml.safe_dump({**{k: v for k, v in SCENE_B.items() if k != "tilt_deg"}, "tilt": 22}))
    out = tmp_path / "out"
    res = run_cli(str(scene_b_files / "walker.mp4"), "--camera", str(cam), "--out", str(out))
    assert_clean_failure(res, out, "typo.yaml", "tilt: unknown field", "tilt_deg")


def test_camera_that_cannot_see_the_ground_is_refused(scene_b_files, tmp_path):
    cam = tmp_path / "sky.yaml"
    cam.write_text(yaml.safe_dump({**SCENE_B, "tilt_deg": -25.0}))
    out = tmp_path / "out"
    res = run_cli(str(scene_b_files / "walker.mp4"), "--camera", str(cam), "--out", str(out))
    assert_clean_failure(res, out, "sky.yaml", "cannot see the ground", "tilt_deg")


def test_camera_for_another_aspect_ratio_is_refused(scene_b_files, tmp_path):
    cam = tmp_path / "wide.yaml"
    cam.write_text(yaml.safe_dump({**SCENE_B, "width_px": 424}))
    out = tmp_path / "out"
    res = run_cli(str(scene_b_files / "walker.mp4"), "--camera", str(cam), "--out", str(out))
    assert_clean_failure(res, out, "wide.yaml", "aspect ratio")


# ----------------------------------------------------------------- boxes in the video's own pixels
BOX_CAMERA = {**SCENE_B, "width_px": 480, "height_px": 360}  # scene B's lens on a 480 x 360 sensor grid
BOX_WARM_UP = 30  # empty frames first, so the background model has settled before the box comes
BOX_FRAMES = 90


def box_at(k: int) -> tuple[int, int, int, int] | None:
    """Where the bright walker-sized box is in frame k (x, y, w, h in video pixels; None before it comes)."""
    return (30 + 6 * (k - BOX_WARM_UP), 201, 31, 97) if k >= BOX_WARM_UP else None


def write_box_video(path: Path) -> None:
    """A static textured background and a bright box crossing it; lossless (FFV1), so the box is exact."""
    rng = np.random.default_rng(1)
    w, h = BOX_CAMERA["width_px"], BOX_CAMERA["height_px"]
    texture = cv2.GaussianBlur(rng.integers(20, 110, (h // 8, w // 8), dtype=np.uint8), (3, 3), 0)
    background = cv2.resize(texture, (w, h), interpolation=cv2.INTER_NEAREST)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"FFV1"), 15.0, (w, h))
    assert writer.isOpened()
    for k in range(BOX_FRAMES):
        frame = background.copy()
        if (box := box_at(k)) is not None:
            x, y, bw, bh = box
            frame[y : y + bh, x : x + bw] = 220
        writer.write(cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR))
    writer.release()


@pytest.fixture(scope="module")
def box_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("box")
    (folder / "cam480.yaml").write_text(yaml.safe_dump(BOX_CAMERA))
    write_box_video(folder / "box.avi")
    return folder


def edge_errors_px(row: dict, box: tuple[int, int, int, int]) -> tuple[int, int, int, int]:
    """(left, top, right, bottom) edge of the row's box minus the true box's, px."""
    x, y, w, h = (int(row[c]) for c in "xywh")
    bx, by, bw, bh = box
    return x - bx, y - by, (x + w) - (bx + bw), (y + h) - (by + bh)


def test_boxes_are_in_the_videos_own_pixels_at_the_default_max_width(box_files, capsys):
    out = box_files / "out"
    assert main([str(box_files / "box.avi"), "--camera", str(box_files / "cam480.yaml"), "--out", str(out),
                 "--no-progress"]) == 0
    printed = capsys.readouterr().out
    assert "processed at 424x318 px" in printed and "480x360" in printed, printed
    summary = json.loads((out / "summary.json").read_text())
    assert summary["processing"]["processing_width_px"] == 424
    assert summary["processing"]["processing_height_px"] == 318
    assert summary["processing"]["source_px_per_processing_px_x"] == pytest.approx(480 / 424, abs=1e-5)
    assert summary["frames"] == BOX_FRAMES
    errors = []
    for row in read_rows(out / "detections.csv"):
        box = box_at(int(row["frame"]))
        assert box is not None, f"a region in the empty warm-up: {row}"
        errors.append(edge_errors_px(row, box))
    # one region per frame with the box, at the box: each edge within 2 px in video pixels (the
    # segmenter's 1 px dilation, x 1.13, and the partly covered processing pixels at each edge)
    assert len(errors) == BOX_FRAMES - BOX_WARM_UP
    assert np.abs(errors).max() <= 2, errors
    cap = cv2.VideoCapture(str(out / "annotated.mp4"))
    assert (int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT))) == (480, 360)
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == BOX_FRAMES
    cap.release()
    # an earlier output of this command may be replaced
    assert main([str(box_files / "box.avi"), "--camera", str(box_files / "cam480.yaml"), "--out", str(out),
                 "--no-progress"]) == 0


def test_the_processing_scale_maps_boxes_back_exactly():
    from detector.video import FrameScale

    assert FrameScale((640, 480), (320, 240)).to_source_box((10, 20, 5, 6)) == (20, 40, 10, 12)
    assert FrameScale((320, 240), (320, 240)).to_source_box((7, 8, 9, 10)) == (7, 8, 9, 10)
    # 480 -> 424: edges scale by 480/424 and round to the nearest video pixel edge
    assert FrameScale((480, 360), (424, 318)).to_source_box((100, 50, 30, 80)) == (113, 57, 34, 90)


def test_draw_puts_each_box_where_it_is_given():
    from detector.detector import Detection
    from detector.draw import CLASS_COLOURS_BGR, draw_detections

    det = Detection((10, 10, 5, 5), np.array([0.5, 1.7, 0.8, 9.0, 22.0, 3.1]), "pedestrian", np.zeros(5), 0.9, None)
    img = draw_detections(np.zeros((360, 480), np.uint8), [det], boxes_px=[(200, 100, 40, 90)])
    assert img.shape == (360, 480, 3)
    colour = CLASS_COLOURS_BGR["pedestrian"]
    assert tuple(img[150, 200]) == colour and tuple(img[150, 239]) == colour  # left and right sides
    assert tuple(img[189, 220]) == colour  # bottom
    assert not img[12, 12].any()  # nothing at the detection's own (processing) box


# ------------------------------------------------------- arguments and --out checked before any work
def run_main(capsys, argv: list[str]) -> tuple[int, str]:
    """main(argv) in this process: (exit code, stderr)."""
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse refuses while reading the command line
        code = exc.code
    return code, capsys.readouterr().err.strip()


def assert_one_line_error(code: int, err: str, *needles: str) -> None:
    assert code == 2, err
    assert err.count("\n") == 0 and "Traceback" not in err, err
    for needle in needles:
        assert needle in err, err


@pytest.fixture
def no_work(monkeypatch):
    """Fail the test if the detector opens a camera file or starts detecting."""
    import detector.__main__ as cli

    def boom(*args, **kwargs):
        raise AssertionError("work started before the arguments were checked")

    monkeypatch.setattr(cli.CameraModel, "from_yaml", boom)
    monkeypatch.setattr(cli, "probe_video", boom)
    return cli


@pytest.mark.parametrize(
    ("args", "needles"),
    [
        (["--max-width", "63"], ["argument --max-width", ">= 64 px", "63"]),
        (["--max-width", "wide"], ["argument --max-width", "whole number", "wide"]),
        (["--max-distance-m", "0"], ["argument --max-distance-m", "> 0 m"]),
        (["--max-distance-m", "-3"], ["argument --max-distance-m", "> 0 m"]),
        (["--max-distance-m", "nan"], ["argument --max-distance-m", "> 0 m"]),
    ],
)
def test_bad_numbers_are_refused_before_any_work(tmp_path, capsys, monkeypatch, args, needles):
    import detector.__main__ as cli

    monkeypatch.setattr(cli, "detect_video", lambda *a, **k: pytest.fail("detect_video ran"))
    out = tmp_path / "out"
    code, err = run_main(capsys, ["v.mp4", "--camera", "c.yaml", "--out", str(out), *args])
    assert_one_line_error(code, err, *needles)
    assert list(tmp_path.iterdir()) == []


def test_train_seed_must_be_whole_and_not_negative(tmp_path, capsys):
    code, err = run_main(capsys, ["train", "--out", str(tmp_path / "m.joblib"), "--seed", "-1"])
    assert_one_line_error(code, err, "argument --seed", ">= 0")
    code, err = run_main(capsys, ["train", "--out", str(tmp_path), "--seed", "0"])
    assert_one_line_error(code, err, "--out", "is a folder")
    assert list(tmp_path.iterdir()) == []


def bad_out(kind: str, tmp_path: Path) -> Path:
    """An --out the detector must refuse, of the given kind."""
    if kind == "file":
        (tmp_path / "out.csv").write_text("x\n")
        return tmp_path / "out.csv"
    if kind == "under a file":
        (tmp_path / "notes").write_text("x\n")
        return tmp_path / "notes" / "out"
    if kind == "random files":
        (tmp_path / "mine").mkdir()
        (tmp_path / "mine" / "thesis.tex").write_text("x\n")
        return tmp_path / "mine"
    if kind == "a citysim run folder":
        run = tmp_path / "run"
        run.mkdir()
        for name in ("summary.json", "objects.csv", "lamps.csv"):
            (run / name).write_text("{}\n")
        return run
    return unwritable_folder(tmp_path) / "out"


def tree(folder: Path) -> dict[str, bytes | None]:
    return {str(p.relative_to(folder)): p.read_bytes() if p.is_file() else None for p in folder.rglob("*")}


@pytest.mark.parametrize(
    ("kind", "needles"),
    [
        ("file", ["--out", "is a file", "valid: a new or empty folder"]),
        ("under a file", ["--out", "cannot be created", "is a file"]),
        ("random files", ["--out", "not from a python -m detector", "thesis.tex", "detections.csv"]),
        ("a citysim run folder", ["--out", "not from a python -m detector", "lamps.csv"]),
        ("unwritable", ["--out", "cannot write in"]),
    ],
)
def test_an_out_that_cannot_be_used_is_refused_before_any_work(tmp_path, capsys, no_work, kind, needles):
    out = bad_out(kind, tmp_path)
    before = tree(tmp_path)
    code, err = run_main(capsys, ["v.mp4", "--camera", "c.yaml", "--out", str(out), "--no-progress"])
    assert_one_line_error(code, err, *needles)
    assert tree(tmp_path) == before  # nothing written, no hidden .partial folder


# ------------------------------------------------------------------- cameras unlike the general model's
def test_note_says_why_a_low_camera_gets_its_own_model(tmp_path, capsys, monkeypatch):
    from detector.general_model import default_model

    trained = []
    monkeypatch.setattr("detector.train.fit.train_camera_model", lambda cam: trained.append(cam) or default_model())
    video = tmp_path / "walk.avi"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"FFV1"), 30.0, (320, 180))
    for _ in range(5):
        writer.write(np.full((180, 320, 3), 40, np.uint8))
    writer.release()
    camera = REPO / "scenarios" / "cameras" / "realclip_night_walk.yaml"  # 1.6 m high, looking level
    assert main([str(video), "--camera", str(camera), "--out", str(tmp_path / "out"), "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert "camera 1.6 m high: the general model covers 2-10 m; training a model for this camera (~7 s" in err
    assert "inf" not in err and "sees only" not in err, err
    assert len(trained) == 1
    assert json.loads((tmp_path / "out" / "summary.json").read_text())["model"].startswith("trained for")
    # the second run reuses the cached model and says so; another camera is trained anew
    assert main([str(video), "--camera", str(camera), "--out", str(tmp_path / "out"), "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert "reusing the model trained for this camera" in err and "training" not in err, err
    assert len(trained) == 1
    higher = tmp_path / "higher.yaml"
    higher.write_text(camera.read_text().replace("height_m: 1.6", "height_m: 1.7"))
    assert main([str(video), "--camera", str(higher), "--out", str(tmp_path / "out"), "--no-progress"]) == 0
    assert "training a model for this camera" in capsys.readouterr().err
    assert len(trained) == 2


def test_the_model_cache_key_follows_what_the_model_depends_on(monkeypatch):
    import sklearn

    from detector import model_cache

    cam = CameraModel(**SCENE_B)
    key = model_cache.model_key(cam, 0, 800)
    assert model_cache.model_key(cam.placed(name="renamed"), 0, 800) == key  # a name changes no pixel
    assert model_cache.model_key(cam.placed(tilt_deg=23.0), 0, 800) != key
    assert model_cache.model_key(cam.placed(k1=-0.1), 0, 800) != key
    assert model_cache.model_key(cam, 1, 800) != key
    assert model_cache.model_key(cam, 0, 400) != key
    monkeypatch.setattr(sklearn, "__version__", "0.0")
    assert model_cache.model_key(cam, 0, 800) != key
    monkeypatch.undo()
    monkeypatch.setattr(model_cache, "training_code_digest", lambda: "another training code")
    assert model_cache.model_key(cam, 0, 800) != key


@pytest.mark.parametrize(
    ("camera", "reason"),
    [
        (dict(height_m=1.6, tilt_deg=1.0), "camera 1.6 m high: the general model covers 2-10 m"),
        (dict(height_m=12.0), "camera 12 m high: the general model covers 2-10 m"),
        (dict(height_m=6.0, tilt_deg=85.0), "camera tilted 85 deg below the horizon: the general model covers 0-80 deg"),
        (dict(tilt_deg=60.0), "camera sees the ground only 3.6 m ahead: the general model's cameras see at least 25 m"),
    ],
)
def test_the_general_models_range_is_told_in_words(camera, reason):
    from detector.__main__ import general_model_covers, general_model_gap

    cam = CameraModel(**{**SCENE_B, **camera})
    assert general_model_gap(cam).startswith(reason)
    assert not general_model_covers(cam)
    assert general_model_gap(CameraModel(**SCENE_B)) is None


def test_camera_file_typo_suggests_the_field(tmp_path):
    cam = tmp_path / "typo.yaml"
    cam.write_text(yaml.safe_dump({**{k: v for k, v in SCENE_B.items() if k != "focal_mm"}, "focal_mn": 0.73}))
    with pytest.raises(Exception, match=r"focal_mn: unknown field; did you mean focal_mm\?"):
        CameraModel.from_yaml(cam)


def test_a_walker_cut_by_the_frames_side_is_kept_with_keep_edge_regions(tmp_path, capsys):
    """A walker crossing out of the frame's side: with --keep-edge-regions his regions cut by the
    edge are classified from their visible part (bottom row in view: distance known) and stay on
    his track; by default they are dropped as the paper does."""
    camera = CameraModel(**SCENE_B)
    (tmp_path / "cam.yaml").write_text(yaml.safe_dump(SCENE_B))
    write_walker_video(tmp_path / "walker.mp4", camera, FORWARD_M, n_frames=120)  # walks out at the right
    outs = {flag: tmp_path / flag for flag in ("kept", "filtered")}
    for flag, out in outs.items():
        extra = ["--keep-edge-regions"] if flag == "kept" else []
        assert main([str(tmp_path / "walker.mp4"), "--camera", str(tmp_path / "cam.yaml"), "--out", str(out),
                     "--no-video", "--no-progress", *extra]) == 0
    kept, filtered = (read_rows(out / "detections.csv") for out in outs.values())
    right = SCENE_B["width_px"]
    at_edge = [r for r in kept if int(r["x"]) + int(r["w"]) >= right]
    assert at_edge, "the walker should reach the frame's right edge"
    assert not [r for r in filtered if int(r["x"]) + int(r["w"]) >= right]
    # measured from the visible part: the distance (bottom row) is right, and his track keeps him
    assert np.median([float(r["distance_m"]) for r in at_edge]) == pytest.approx(FORWARD_M, rel=0.1)
    assert sum(r["target"] == "1" for r in at_edge) >= 0.5 * len(at_edge)
    summaries = [json.loads((out / "summary.json").read_text()) for out in outs.values()]
    assert [s["border_filter"] for s in summaries] == [False, True]
