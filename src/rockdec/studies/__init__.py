"""The studies beyond the paper: speed against accuracy, sensitivity to unstated choices,
the amplitude sweep, and how well the interval, the warnings and the record model hold."""

__all__: list[str] = []
