"""Camera effects: things between the street and the sensor that are not targets.

Each effect is one module of this package and one line in ``registry.EFFECTS``. The renderer
(``citysim.render.camera``) builds every registered effect the scenario's ``EnvironmentSpec``
turns on, in registry order, then each frame lets each ``draw`` on the linear-radiance canvas
(before the camera response) and ``filter`` the 8-bit frame (after it). Fog or snow is one new
module here. Conventions: canvas pixels of ``citysim.render.canvas``; camera frame x right, y
down, z forward (m); radiance in linear full-scale units. All randomness comes from the
renderer's generator (or generators seeded from it), so a seed fixes every frame.
"""
