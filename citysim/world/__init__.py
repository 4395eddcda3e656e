"""The street world: street geometry, agents drawn from their kinds (config.kinds), traffic and
the moving (pymunk) world.

Imports config and detector; never render, control, metrics or sim (a renderer reads the world)."""
