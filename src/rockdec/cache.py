"""Where calibrations are stored, shared by the Python API and the command line."""

from __future__ import annotations

import os
from pathlib import Path

#: The environment variable that names the calibration folder.
VARIABLE = "ROCKDEC_CACHE"


def default_cache() -> Path:
    """The folder of stored calibrations: ``$ROCKDEC_CACHE``, else ``calibration`` in the
    user's cache folder (``~/.cache/rockdec/calibration`` on Linux, by :mod:`platformdirs`).

    Returns
    -------
    pathlib.Path

    Examples
    --------
    >>> import os
    >>> from rockdec.cache import default_cache
    >>> os.environ["ROCKDEC_CACHE"] = str(tmp / "calibrations")
    >>> default_cache() == tmp / "calibrations"
    True
    """
    import platformdirs

    return Path(os.environ.get(VARIABLE) or Path(platformdirs.user_cache_dir("rockdec")) / "calibration")
