"""Running nights: the one night builder, the simpy loop and the comparison of controllers.

Imports every stage below it (config, world, render, control, metrics); drawing stays in report."""
