"""Training of the classifier: synthetic training sets, Table 1 samplers, 3D shapes and silhouettes.
The detector's runtime never imports it (only ``detector.general_model``'s retraining fallback does)."""
