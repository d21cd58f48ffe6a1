"""placeholder: filled in by its own work."""
SensorSelection = None  # type: ignore
select_sensors = None  # type: ignore
