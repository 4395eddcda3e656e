"""What a lamp camera sees: near-infrared frames and their ground truth, through detector.camera.

Reads world snapshots (imports world, config, detector); camera effects live in render/effects."""
