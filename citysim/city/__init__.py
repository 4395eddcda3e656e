"""A city: many streets' years run as Dask tasks, resumable, ranked by the payback of their sensors.
Owns the city file schema, the street preparation, sensor-model sharing, the runner and city.json/csv."""
