"""The paper's detector end to end: one grayscale frame in, classified moving objects out.

``Detector.process``: segment (``detector.segment``), features (eqs. 1-11), division of regions
merged with their light spot (section 5.2), tracks (``detector.tracks``), one classifier
evaluation, and each track's target decision; ``tracking=False`` is the paper's per-frame path.
Regions cut by the frame's edge are dropped (the paper's border filter) unless
``border_filter=False`` (``detector.edges``): a cut region continuing a track, or cut by the
left, right or top edge with a visible part that fits a class, is measured from its visible part.
Boxes are OpenCV ``(x, y, w, h)`` pixels of the full, distorted frame; distances are forward
ground distances, m (see ``detector.camera``).

Design: docs/design/modules.md (The detector pipeline)
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from detector.camera import CameraModel
from detector.confirm import Tracker
from detector.divide import MIN_SPOT_BRIGHTENING_DN, DivisionParams, divide_rows
from detector.edges import keep_cut_regions
from detector.features import SCALAR_MAX_REGIONS, RegionGeometry
from detector.ghosts import StillRegions
from detector.roi import Crop, full_frame, range_crop
from detector.segment import Regions, Segmenter, SegmenterParams
from detector.split_compiled import load as load_compiled_splits
from detector.tracks.footprint import is_steep
from detector.tracks.tracker import TrackSet

if TYPE_CHECKING:
    from detector.classifier import DimensionalClassifier

__all__ = ["Detection", "Detector"]

# frozen, so one shared default instance is safe
_DEFAULT_SEGMENTER_PARAMS = SegmenterParams()
_DEFAULT_DIVISION_PARAMS = DivisionParams()


@dataclass(frozen=True)
class Detection:
    """One classified region of one frame.

    ``features`` are ``detector.features.FEATURE_NAMES`` (width m, height m,
    area m^2, distance m, tilt deg, camera height m); ``probabilities`` follow
    the model's ``classes_`` (``detector.classes.CLASSES``); ``p_target`` is
    1 - P(noise): all of this frame alone. The ``track_*`` fields are its track's
    (``detector.tracks``; None on the per-frame path): ``track_cls`` the pooled class
    ('noise' unless the track is a target), ``track_p_target`` the pooled P(target),
    ``track_target`` the decision (plausible and pooled P(target) >= threshold),
    ``track_reason`` why it is not a target (``track_id`` None: a still region, a ghost of a steep
    camera, on no track: ``detector.ghosts``); ``ground_x_m``/``ground_y_m`` the bottom
    centre on the ground (a steep camera: the middle of the region's footprint; world x along
    the street, y across, m), ``velocity_*_mps`` and ``speed_mps`` the track's ground velocity
    (None until known).
    """

    box_px: tuple[int, int, int, int]
    features: np.ndarray
    cls: str
    probabilities: np.ndarray
    p_target: float
    track_id: int | None
    track_cls: str | None = None
    track_p_target: float | None = None
    track_target: bool = False
    track_reason: str | None = None
    ground_x_m: float | None = None
    ground_y_m: float | None = None
    velocity_x_mps: float | None = None
    velocity_y_mps: float | None = None
    speed_mps: float | None = None


# Detection's frozen-dataclass __init__ sets its 16 fields one object.__setattr__ at a time (~3 us
# per detection, measured; ~0.4 us this way): the detector builds them with all fields at once,
# the same objects (tests/detector/test_detector.py checks them against the constructor's)
_new_object = object.__new__
_set_attribute = object.__setattr__
#: a per-frame detection's track fields: Detection's defaults
NO_TRACK_FIELDS = {
    f.name: f.default for f in dataclasses.fields(Detection) if f.default is not dataclasses.MISSING
}


def detection_from_fields(fields: dict) -> Detection:
    """A Detection of all its ``fields`` (name -> value), as ``Detection(**fields)`` makes it
    (the detector's own, and fast mode's drawn ones, ``citysim.fast.drawn``)."""
    detection = _new_object(Detection)
    _set_attribute(detection, "__dict__", fields)
    return detection


class Detector:
    """Per-camera detector: owns the background model and the tracker.

    Parameters
    ----------
    camera : detector.camera.CameraModel
        The camera's intrinsics, height (m) and tilt (deg): what turns pixels into metres.
    model : detector.classifier.DimensionalClassifier, optional
        The classifier; None loads the shipped general model.
    params : detector.segment.SegmenterParams
        Background subtraction and morphology settings (px, frames).
    max_distance_m : float
        Regions whose bottom row is farther ahead than this (m on the ground) are not reported.
    target_threshold : float
        P(target) (0..1) at or above which a detection, or a track, is a target.
    division : detector.split.DivisionParams
        How a region holding several objects is divided.
    tracker : detector.confirm.Tracker, optional
        The per-frame path's light box tracker (``tracking=False``).
    crop_to_range : bool
        Segment only the band of the frame where a target within ``max_distance_m`` can appear
        (``detector.roi.range_crop``; ``self.crop``), with the same boxes, features and classes
        as on the full frame; False: the whole frame, as the paper does.
    equalise_tiles_only : bool
        OpenCV's CLAHE on just the full frame's tiles the crop needs (values 1 DN off on ~0.1 %
        of the pixels) instead of ``detector.clahe``'s exact crop equalisation.
    tracking : bool
        Decide per track (``detector.tracks``, the default) or per frame (False: the paper's
        path).
    tracks : detector.tracks.tracker.TrackSet, optional
        A configured ``TrackSet``; None builds the default one.
    border_filter : bool
        Drop every region cut by the frame's edge, as the paper does (the default). False: a cut
        region is measured from its visible part and kept when it overlaps a live track's last box
        or, cut by the left, right or top edge, its visible part fits a class (``detector.edges``).

    Notes
    -----
    Design: docs/design/tracks.md and docs/design/region-of-interest.md.
    """

    def __init__(
        self,
        camera: CameraModel,
        model: DimensionalClassifier | None = None,
        params: SegmenterParams = _DEFAULT_SEGMENTER_PARAMS,
        max_distance_m: float = 25.0,
        target_threshold: float = 0.5,
        *,
        division: DivisionParams = _DEFAULT_DIVISION_PARAMS,
        tracker: Tracker | None = None,
        crop_to_range: bool = True,
        equalise_tiles_only: bool = False,
        tracking: bool = True,
        tracks: TrackSet | None = None,
        border_filter: bool = True,
    ) -> None:
        if not isinstance(camera, CameraModel):
            raise TypeError(f"Detector camera must be a CameraModel, got {type(camera).__name__}")
        if not max_distance_m > 0:
            raise ValueError(f"Detector max_distance_m must be > 0 m, got {max_distance_m!r}")
        if not 0.0 <= target_threshold <= 1.0:
            raise ValueError(
                f"Detector target_threshold must be in [0, 1], got {target_threshold!r}"
            )
        # the classifier's modules import scikit-learn (about 2 CPU-s): loaded by the first
        # Detector, not on import, so a process that only needs ``Detection`` (fast mode's
        # workers) does not pay for it
        from detector.fast_proba import camera_rows_proba, compiled_rows_proba, numpy_predict_proba
        from detector.general_model import default_model

        self.camera = camera
        self.model = default_model() if model is None else model
        classes = np.asarray(getattr(self.model, "classes_", ()))
        if "noise" not in classes:
            raise ValueError(
                f"Detector model must be fitted with a 'noise' class, got classes {classes.tolist()}"
            )
        self._classes = classes
        self._class_names = [str(c) for c in classes]
        self._noise_col = int(np.flatnonzero(classes == "noise")[0])
        self._predict_proba = numpy_predict_proba(self.model, camera) or self._sklearn_predict_proba
        # the few regions of a usual frame: the plain Python rows' arithmetic, compiled where that
        # gives the same values bit for bit (None if the model is another kind)
        proba_rows = camera_rows_proba(self.model, camera)
        self._rows_proba = compiled_rows_proba(proba_rows, camera)
        if self._rows_proba is None and proba_rows is not None:
            self._rows_proba = lambda feats: np.array(proba_rows(feats.tolist()))
        self.max_distance_m = float(max_distance_m)
        self.border_filter = bool(border_filter)
        self.target_threshold = float(target_threshold)
        self.division = division
        load_compiled_splits(division)
        #: the band of the frame where a target within range can appear (``detector.roi``)
        self.band: Crop = range_crop(
            camera,
            self.max_distance_m,
            params.clahe_tile_px,
            params.open_kernel_px,
            params.dilate_iterations,
            equalise_tiles_only,
        )
        self.crop: Crop = self.band if crop_to_range else full_frame(camera.height_px, camera.width_px,
                                                                     params.clahe_tile_px)
        self.segmenter = Segmenter(params, camera.fps, self.crop)
        # per-camera constants, computed once rather than every frame
        self._frame_shape = (camera.height_px, camera.width_px)
        self._geometry = RegionGeometry(camera, compiled=True)
        # without lens distortion an object divided off a region beyond range is beyond it too
        # (its bottom row is at or above the region's): such regions are not tried
        self._divide_within_m = math.inf if camera.has_distortion else self.max_distance_m
        if tracking and tracks is None:
            tracks = TrackSet(camera, self._class_names, self.target_threshold, geometry=self._geometry)
        self.tracks: TrackSet | None = tracks if tracking else None
        # a camera looking steeply down: regions where nothing changed (ghosts) follow no track
        self._still = StillRegions() if self.tracks is not None and is_steep(camera) else None
        # what the controllers ask is_confirmed(track_id): the tracks, or the per-frame box tracker
        self.tracker = self.tracks if self.tracks is not None else (Tracker() if tracker is None else tracker)
        self.last_regions: Regions = Regions.empty(camera.height_px, camera.width_px)

    @property
    def motion_in_band(self) -> bool:
        """Whether the last frame held a moving region reaching into the band where a target
        within range can appear: what keeps a lamp camera at its full frame rate
        (``citysim.sim.cameras``). On the crop every region does; on whole frames, motion beyond
        range (above the band) does not, so both modes judge the same frames."""
        regions = self.last_regions
        if self.crop is self.band or not len(regions):
            return bool(regions)
        band = self.band
        return any(y + h > band.top_px and x < band.right_px and x + w > band.left_px
                   for x, y, w, h in regions.boxes_px.tolist())  # fmt: skip

    def reset_background(self) -> None:
        """Rebuild the background model (call when the lamp in view switches)."""
        self.segmenter.reset()
        if self._still is not None:
            self._still.reset()

    def is_target(self, detections: Sequence[Detection]) -> bool:
        """Whether any detection is a target: its track is one (tracking), or its own P(target)
        reaches this detector's threshold (per frame, and detections that carry no track)."""
        threshold = self.target_threshold
        if self.tracks is not None:
            return any(
                d.track_target if d.track_p_target is not None else d.p_target >= threshold for d in detections
            )
        return any(d.p_target >= threshold for d in detections)

    def _lit(self, object_box_px: list[int], spot_box_px: list[int]) -> bool:
        """Is this spot part of a region a light spot: brighter than the ground was and than the
        object part? Division only then."""
        spot, body = self.segmenter.brightness_dn(spot_box_px), self.segmenter.brightness_dn(object_box_px)
        if spot is None or body is None:
            return False
        return spot[0] - max(spot[1], body[0]) >= MIN_SPOT_BRIGHTENING_DN

    def _keep_cut(self, regions: Regions, boxes: list, rows: list, edge: list) -> None:
        """Un-flag (in ``edge``) the edge-cut regions that continue a track or fit a class (``detector.edges``)."""
        live = [] if self.tracks is None else [t.box_px for t in self.tracks.tracks]
        keep_cut_regions(regions, boxes, rows, edge, self._frame_shape, live, classify=lambda r: self._classify(
            np.array(r))[1], class_names=self._class_names, threshold=self.target_threshold)

    def _nothing(self) -> list[Detection]:
        """A frame with no region to classify: the tracks age (or the box tracker sees nothing)."""
        if self.tracks is not None:
            self.tracks.age()
        else:
            self.tracker.update_rows([], [])
        return []

    def _sklearn_predict_proba(self, feats: np.ndarray) -> np.ndarray:
        import sklearn  # loaded already: the model is scikit-learn's

        # the rows are finite by construction (valid), so skip scikit-learn's re-check
        with sklearn.config_context(assume_finite=True):
            return self.model.predict_proba(feats)

    def _check_frame(self, gray) -> None:
        if (
            not isinstance(gray, np.ndarray)
            or gray.shape != self._frame_shape
            or gray.dtype != np.uint8
        ):
            got = (
                f"{gray.dtype} {gray.shape}"
                if isinstance(gray, np.ndarray)
                else type(gray).__name__
            )
            raise ValueError(
                f"Detector.process needs a grayscale uint8 frame of shape {self._frame_shape} (the "
                f"camera's height_px x width_px), got {got}"
            )

    def _classify(self, feats: np.ndarray) -> tuple[np.ndarray, list[list[float]], list[float], list[int]]:
        """(probabilities (N, 5), the same as lists, P(target) per region, most probable class index
        per region)."""
        if self._rows_proba is not None and len(feats) <= SCALAR_MAX_REGIONS:
            proba = self._rows_proba(feats)
            lists = proba.tolist()
            noise = self._noise_col
            # the first maximum, as argmax
            return proba, lists, [1.0 - p[noise] for p in lists], [p.index(max(p)) for p in lists]
        proba = self._predict_proba(feats)
        return proba, proba.tolist(), (1.0 - proba[:, self._noise_col]).tolist(), proba.argmax(axis=1).tolist()

    def process(self, gray: np.ndarray, learning_rate: float | None = None) -> list[Detection]:
        """Detect and classify the moving objects of one frame.

        Parameters
        ----------
        gray : numpy.ndarray
            The frame, uint8 (H, W), the camera's full size.
        learning_rate : float, optional
            The background model's rate, 0..1 (default: MOG2's automatic rate).

        Returns
        -------
        list of Detection
            One per classified region (box OpenCV ``(x, y, w, h)`` px, features m and deg, track
            and ground position m, velocity m/s: see ``Detection``).
        """
        self._check_frame(gray)
        if self._still is not None:
            self._still.next_frame(gray)
        regions = self.segmenter.apply(gray, learning_rate)
        self.last_regions = regions
        # a frame holds a handful of regions: per-region work is plain Python on lists
        # (numpy's per-call cost would exceed the arithmetic), arrays only where results go out
        if not regions.contours:
            return self._nothing()
        if regions.lists is not None:  # copies: division and the edge test below change them
            boxes, areas, edge = regions.lists
            boxes, areas, edge = list(boxes), list(areas), list(edge)
        else:
            boxes, areas = regions.boxes_px.tolist(), regions.areas_px.tolist()
            edge = regions.unusable.tolist()
        rows = self._geometry.rows(boxes, areas)
        divided, _ = divide_rows(
            self._geometry, regions.contours, boxes, areas, rows, self.division, self._divide_within_m, self._lit
        )
        # a region cut by the border (or the crop) is classified only as the object divided off
        # it, when that object is clear of the edge (the light spot was the part that reached it)
        if any(edge):
            if not self.border_filter:
                self._keep_cut(regions, boxes, rows, edge)
            crop = self.crop
            left, top, right, bottom = crop.left_px, crop.top_px, crop.right_px, crop.bottom_px
            for i in divided:
                x, y, w, h = boxes[i]
                if edge[i] and x > left and y > top and x + w < right and y + h < bottom:
                    edge[i] = False
            if all(edge):
                return self._nothing()
            inner = [i for i, e in enumerate(edge) if not e]
            boxes, rows = [boxes[i] for i in inner], [rows[i] for i in inner]
            areas = [areas[i] for i in inner]
        max_distance_m = self.max_distance_m
        keep = [j for j, row in enumerate(rows) if row is not None and row[3] <= max_distance_m]
        if not keep:
            return self._nothing()
        if len(keep) < len(rows):  # (the usual frame keeps every region: nothing to pick)
            rows, boxes, areas = [rows[j] for j in keep], [boxes[j] for j in keep], [areas[j] for j in keep]
        if self.tracks is not None:
            still = None if self._still is None else self._still.flags(regions.mask, boxes)
            prepared = self.tracks.prepare(boxes, areas, rows, still)
            boxes, rows = prepared.boxes_px, prepared.rows
        feats = np.array(rows)
        proba, proba_lists, p_target, labels = self._classify(feats)
        names = self._class_names
        # the detections' rows of both arrays in one call each, not one indexing per detection
        feat_rows, probability_rows = list(feats), list(proba)
        if self.tracks is not None:
            views = self.tracks.update(prepared, proba_lists)
            return [
                detection_from_fields({
                    "box_px": tuple(box), "features": feat_rows[j], "cls": names[labels[j]], "probabilities": probability_rows[j],
                    "p_target": p_target[j], "track_id": v.track_id, "track_cls": v.cls,
                    "track_p_target": v.p_target, "track_target": v.target, "track_reason": v.reason,
                    "ground_x_m": v.ground_x_m, "ground_y_m": v.ground_y_m, "velocity_x_mps": v.velocity_x_mps,
                    "velocity_y_mps": v.velocity_y_mps, "speed_mps": v.speed_mps,
                })  # fmt: skip
                for j, (box, v) in enumerate(zip(boxes, views, strict=True))
            ]
        threshold = self.target_threshold
        ids = self.tracker.update_rows(boxes, [p >= threshold for p in p_target])
        return [
            detection_from_fields({
                "box_px": tuple(box), "features": feat_rows[j], "cls": names[labels[j]], "probabilities": probability_rows[j],
                "p_target": p_target[j], "track_id": ids[j], **NO_TRACK_FIELDS,
            })  # fmt: skip
            for j, box in enumerate(boxes)
        ]
