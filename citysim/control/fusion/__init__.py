"""Street-level fusion: every camera's ground detections fused into one set of street tracks.

Owns the street frame (s, d), the views, the Kalman filter, association, existence and the tracker.
"""
