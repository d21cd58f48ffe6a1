"""placeholder: filled in by its own work."""
AGORegressor = None  # type: ignore
MinMaxAGO = None  # type: ignore
spread_search = None  # type: ignore
