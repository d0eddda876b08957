"""A user's measured record: reading and checking it, measuring its own model (sensor noise,
load colour, drift) and the diagnostics that say what may be wrong with it."""

__all__: list[str] = []
