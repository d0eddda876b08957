"""Process-wide locks shared by the steps that run side by side in one process."""

from __future__ import annotations

import threading

__all__ = ["HDF5"]

#: One user of HDF5 files at a time in a process: the HDF5 library under netCDF4 is not safe
#: to use from two threads at once (the workflow's in-process steps and the campaign's, the
#: calibration cache's reads and writes, the inputs' history a product's provenance reads).
#: Re-entrant: a step that holds it may call a function that takes it again.
HDF5 = threading.RLock()
