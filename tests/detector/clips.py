"""Synthetic camera clips for the detector tests: a static IR-like background (brighter toward
the bottom, where the emitter lights the ground) plus bright 3D shapes drawn through the camera."""

import numpy as np

from detector.camera import CameraModel
from detector.detector import Detector
from detector.train.silhouette import silhouette_mask


class Clip:
    """Frames of ``camera``: the background, its noise and the shapes, from one seeded generator."""

    def __init__(self, camera: CameraModel, seed: int = 0) -> None:
        self.camera = camera
        self.rng = np.random.default_rng(seed)
        h, w = camera.height_px, camera.width_px
        self.background = 25.0 + 30.0 * np.linspace(0.0, 1.0, h)[:, None] + self.rng.normal(0, 2, (h, w))

    def frame(self, shapes=(), level_dn: float = 150.0, levels_dn=None) -> np.ndarray:
        """A frame with ``shapes`` drawn at ``level_dn`` (``levels_dn``: one level per shape)."""
        img = self.background + self.rng.normal(0, 3.0, self.background.shape)
        levels = [level_dn] * len(shapes) if levels_dn is None else levels_dn
        for shape, level_dn in zip(shapes, levels, strict=True):
            sil = silhouette_mask(self.camera, shape)
            if sil is None:
                continue
            x0, y0 = sil.offset_px
            h, w = sil.mask.shape
            roi = img[y0 : y0 + h, x0 : x0 + w]
            roi[sil.mask > 0] = level_dn + self.rng.normal(0, 3.0, int(np.count_nonzero(sil.mask)))
        return np.clip(img, 0, 255).astype(np.uint8)

    def warm_up(self, detector: Detector, n: int = 120) -> None:
        for _ in range(n):
            assert detector.process(self.frame()) == []
