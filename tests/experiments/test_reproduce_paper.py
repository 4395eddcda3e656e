"""The paper reproduction: frame scoring on hand-made frames, the metrics' invariants, and the
quick mode end to end (outputs exist, matrices are row-normalised, curves are real images)."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from citysim.render.camera import TruthObject
from detector.classes import CLASSES
from detector.detector import Detection
from detector.segment import Regions
from experiments.paper.metrics import (
    VARIANTS,
    Rows,
    confusions,
    row_normalised,
    threshold_baseline,
    tpr_by_distance,
    window_detection,
)
from experiments.paper.reproduce import QUICK_BUDGET, main, reproduce  # noqa: E402
from experiments.paper.scenes import (  # noqa: E402
    PAPER_SCENES,
    Budget,
    SceneRecords,
    film_scene,
    score_frame,
)

pytestmark = pytest.mark.slow  # real simulation or footage: tens of seconds

FRAME_PX = 320 * 240


def _truth(oid, cls, box, *, visible=True, distance_m=10.0):
    return TruthObject(
        oid, cls, *box, touches_border=False, fully_visible=visible, distance_m=distance_m
    )


def _det(box, cls, p_target):
    probs = np.full(len(CLASSES), p_target / (len(CLASSES) - 1))
    probs[0] = 1.0 - p_target
    return Detection(tuple(box), np.zeros(6), cls, probs, p_target, None)


def _regions(boxes, areas):
    boxes = np.asarray(boxes, dtype=np.int32).reshape(-1, 4)
    return Regions(boxes, np.asarray(areas, dtype=float), [], np.zeros(len(boxes), bool), 0.0,
                   np.zeros((240, 320), np.uint8))  # fmt: skip


def test_score_frame_rows_misses_fragments_and_baseline():
    truth = [
        _truth(1, "pedestrian", (10, 10, 20, 50)),  # detected as a target
        _truth(2, "cyclist", (100, 10, 20, 40)),  # only its top found: missed, in range
        _truth(3, "group", (200, 10, 40, 40), distance_m=40.0),  # missed but out of range
        _truth(4, "vehicle", (250, 100, 60, 30), visible=False),  # missed but half hidden
        _truth(5, "animal", (150, 150, 20, 10)),  # detected: a noise row
    ]
    dets = [
        _det((11, 12, 20, 48), "pedestrian", 0.9),
        _det((150, 151, 20, 10), "vehicle", 0.7),
        _det((300, 200, 10, 10), "noise", 0.1),  # matches nothing: noise
        _det((100, 10, 20, 8), "pedestrian", 0.8),  # IoU 0.2 with the cyclist: a fragment
    ]
    regions = _regions(
        [(10, 10, 20, 50), (300, 200, 10, 10), (100, 12, 20, 36)], [800.0, 60.0, 2000.0]
    )
    rec = SceneRecords()
    score_frame(rec, truth, dets, regions, 25.0, FRAME_PX, ("X", 0), 7)
    assert rec.truth_cls == ["pedestrian", "noise", "noise", "noise", "cyclist"]
    assert rec.detected == [True, True, True, True, False]
    assert rec.fragment == [False, False, False, True, False]
    np.testing.assert_array_equal(rec.probabilities[-1], np.eye(len(CLASSES))[0])
    assert rec.distance_m[0] == 10.0 and math.isnan(rec.distance_m[2])
    assert dict(rec.truth_instances) == {"pedestrian": 1, "cyclist": 1}
    assert rec.hits == {("X", 0, 1): [(7, True)], ("X", 0, 2): [(7, False)]}
    # baseline: the pedestrian's region and the cyclist's region, by area; one noise region
    assert rec.target_area_frac == pytest.approx([800 / FRAME_PX, 2000 / FRAME_PX])
    assert rec.noise_area_frac == pytest.approx([60 / FRAME_PX])
    assert rec.frame_max_frac == pytest.approx([2000 / FRAME_PX])
    assert rec.frame_has_target == [True] and rec.frame_target_free == [False]

    counts = {v: confusions(Rows.of(rec, v)).binary_counts.tolist() for v in VARIANTS}
    assert counts["objects"] == [[1, 2], [1, 1]]  # the miss is a false negative
    assert counts["regions"] == [[1, 2], [0, 1]]
    assert counts["clean"] == [[1, 1], [0, 1]]  # the fragment is left out
    objects = confusions(Rows.of(rec, "objects"))
    assert objects.rate("pedestrian", "pedestrian") == 1.0
    assert objects.rate("cyclist", "noise") == 1.0
    band = tpr_by_distance(rec)[1]  # 10-20 m
    assert (band.targets, band.tpr, band.missed) == (2, 0.5, 0.5)


def test_row_normalised_keeps_empty_rows_zero():
    rates = row_normalised(np.array([[2, 2], [0, 0], [1, 3]]))
    np.testing.assert_allclose(rates, [[0.5, 0.5], [0.0, 0.0], [0.25, 0.75]])


def test_threshold_baseline_rates_and_monotone():
    rec = SceneRecords(
        target_area_frac=[0.0, 0.004, 0.01, 0.06],
        noise_area_frac=[0.001, 0.006, 0.2],
        frame_max_frac=[0.06, 0.01, 0.002, 0.007],
        frame_has_target=[True, True, False, False],
        frame_target_free=[False, False, True, True],
    )
    high, low = threshold_baseline(rec, 0.05), threshold_baseline(rec, 0.005)
    assert (high.tpr, high.fpr, high.frame_tpr, high.frame_fpr) == (0.25, 1 / 3, 0.5, 0.0)
    assert (low.tpr, low.fpr, low.frame_tpr, low.frame_fpr) == (0.5, 2 / 3, 1.0, 0.5)
    with pytest.raises(ValueError, match="threshold_fraction"):
        threshold_baseline(rec, 0.0)


def test_window_detection_counts_only_contiguous_windows():
    rec = SceneRecords()
    # object 1: 6 consecutive frames, hits except the 3rd -> 2 windows, both majority
    rec.hits[("A", 0, 1)] = [(f, f != 2) for f in range(6)]
    # object 2: a gap splits its frames -> no 5-frame contiguous window
    rec.hits[("A", 0, 2)] = [(f, False) for f in (0, 1, 2, 10, 11, 12)]
    check = window_detection(rec, n=5)
    assert check.windows == 2 and check.measured == 1.0
    assert check.p_frame == pytest.approx(5 / 12)
    # eq. 12 at the paper's figure: 0.76 per frame -> 0.90 over five frames
    rec2 = SceneRecords(hits={("A", 0, 1): [(f, f % 25 < 19) for f in range(100)]})
    assert window_detection(rec2).p_frame == pytest.approx(0.76)
    assert window_detection(rec2).predicted == pytest.approx(0.9068, abs=1e-4)


def test_budget_and_scene_errors_name_the_field(tmp_path):
    with pytest.raises(ValueError, match="Budget.scored_s"):
        Budget(scored_s=0.0)
    with pytest.raises(ValueError, match="Budget.preroll_s"):
        Budget(preroll_s=-1.0)
    assert main(["--quick", "--out", str(tmp_path), "--scenes", "A", "--no-progress"]) == 2
    assert main(["--quick", "--out", str(tmp_path), "--scenes", "Z", "--no-progress"]) == 2
    assert not (tmp_path / "paper_comparison.md").exists()


def test_film_scene_is_repeatable():
    budget = Budget(preroll_s=20.0, warmup_s=0.4, scored_s=0.8)
    a, b = (film_scene(PAPER_SCENES["B"], budget) for _ in range(2))
    assert a.frames == b.frames == 12
    assert a.truth_cls == b.truth_cls
    np.testing.assert_array_equal(a.probability_matrix, b.probability_matrix)
    assert a.noise_area_frac == b.noise_area_frac


def test_full_frame_scores_the_targets_the_band_scores():
    """The detector's band (``detector.roi``) loses no target within range: scene A's rows of road
    users, detected or missed and with which probabilities, are the same on whole frames."""
    budget = Budget(preroll_s=20.0, warmup_s=0.4, scored_s=1.6)
    band, whole = (film_scene(PAPER_SCENES["A"], budget, full_frame=f) for f in (False, True))

    def target_rows(records):
        return [(c, d, p.tolist()) for c, d, p in zip(records.truth_cls, records.detected, records.probabilities, strict=True)
                if c != "noise"]  # fmt: skip

    assert target_rows(band) and target_rows(band) == target_rows(whole)


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    return reproduce(out, QUICK_BUDGET, quick=True, progress=False), out


def test_quick_mode_writes_every_output(quick):
    result, out = quick
    report = (out / "paper_comparison.md").read_text()
    assert "Quick mode" in report
    for needle in ("0.24", "0.93", "0.67", "Raspberry Pi 3 Model B+", "| night FNR"):
        assert needle in report
    assert set(result.scenes) == set(PAPER_SCENES)
    assert result.conditions["night"].scenes == ("A", "B", "C")
    assert result.conditions["day"].scenes == ("D",)
    for scene in result.scenes.values():
        assert scene.records.frames == round((QUICK_BUDGET.scored_s) * 15)
        assert scene.detector_fps_cpu is None or scene.detector_fps_cpu > 0


def test_confusion_rows_sum_to_one(quick):
    result, _ = quick
    for cond in result.conditions.values():
        for variant in VARIANTS:
            c = cond.confusions[variant]
            for rates, counts in ((c.binary, c.binary_counts), (c.five, c.five_counts)):
                support = counts.sum(axis=1) > 0
                # every scene has targets in view; a tiny budget may leave the region sets empty
                assert support.any() or variant != "objects"
                np.testing.assert_allclose(rates[support].sum(axis=1), 1.0)
                assert not rates[~support].any()


def test_precision_recall_curves_are_real_images(quick):
    result, out = quick
    for name in ("paper_confusion.png", "paper_precision_recall.png"):
        path = Path(out / name)
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        img = cv2.imread(str(path))
        assert img is not None and img.shape[0] > 200 and img.shape[1] > 400
        assert img.std() > 10  # drawn, not blank
    for cond in result.conditions.values():
        pr = cond.precision_recall["objects"]
        for curve in (pr.binary, pr.micro, *pr.per_class.values()):
            if curve.ap is not None:
                assert 0.0 <= curve.ap <= 1.0
            if curve.recall.size:
                assert np.all(
                    np.diff(curve.recall) <= 0
                )  # sklearn: recall falls as threshold rises
                assert curve.precision.min() >= 0 and curve.precision.max() <= 1


def test_threshold_baseline_lower_threshold_catches_more(quick):
    result, _ = quick
    for cond in result.conditions.values():
        high, low = cond.baseline[0.05], cond.baseline[0.005]
        for name in ("tpr", "fpr", "frame_tpr", "frame_fpr"):
            a, b = getattr(high, name), getattr(low, name)
            if a is not None:
                assert b >= a, (cond.name, name)
