"""placeholder: filled in by its own work."""
FuzzyCMeans = None  # type: ignore
