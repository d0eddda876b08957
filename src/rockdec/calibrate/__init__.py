"""From an analysed record to a calibrated ``e``: the calibration by simulation, its
confidence belt and the estimate ``rockdec estimate`` reports."""

__all__: list[str] = []
