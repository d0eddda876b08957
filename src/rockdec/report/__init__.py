"""The products a reader sees: the paper's tables (eq. 28) and figures, and the studies'."""

__all__: list[str] = []
