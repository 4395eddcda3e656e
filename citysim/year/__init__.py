"""A year of a scenario (`citysim year`): dark hours from the site's twilight, traffic by day,
an hourly response table from simulated samples, and the annual figures (kWh, cost, CO2, AECI)."""
