"""Where calibrations are stored, shared by the Python API and the command line."""

from __future__ import annotations

import os
from pathlib import Path

from rockdec.validate import InputError, path_name

__all__ = ["VARIABLE", "cache_folder", "default_cache"]

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


def cache_folder(cache=None) -> Path:
    """The folder of stored calibrations ``cache`` names (``None``: :func:`default_cache`),
    checked before any work: a folder name (a ``str`` or path), not a file, and not under a
    file or in a folder this user cannot create it in when it does not exist yet.

    Parameters
    ----------
    cache : str or path, optional
        The folder; ``None`` for :func:`default_cache`.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    InputError
        In one sentence naming ``cache``, or the variable ``$ROCKDEC_CACHE`` when the folder
        is its.

    Examples
    --------
    >>> from rockdec.cache import cache_folder
    >>> cache_folder(tmp / "calibrations") == tmp / "calibrations"
    True
    >>> cache_folder(123)
    Traceback (most recent call last):
    ...
    rockdec.validate.InputError: `cache` of type int is not a folder name; give it as a str or pathlib.Path.
    """
    if cache is None:
        folder = default_cache()
        name, fix = (f"${VARIABLE}", f"set {VARIABLE} to a folder for the stored calibrations, or unset it") \
            if os.environ.get(VARIABLE) else ("the default cache", "give `cache` a folder for the stored calibrations")
    else:
        try:
            text = os.fspath(cache)
        except TypeError:
            text = None
        if not isinstance(text, str):
            raise InputError(f"`cache` of type {type(cache).__name__} is not a folder name; give it as a str or pathlib.Path"
                             f"{' (os.fsdecode makes one of bytes)' if isinstance(text, bytes) or isinstance(cache, bytes) else ''}.")
        folder, name, fix = Path(text), "`cache`", "give a folder for the stored calibrations"
    path_name(folder, name)
    existing = folder
    try:
        while not (existing.exists() or existing.is_symlink()) and existing != existing.parent:
            existing = existing.parent
    except OSError as exc:
        raise InputError(f"{name} '{folder}' cannot be looked at ({exc.strerror}); {fix}.") from None
    if not existing.is_dir():
        where = "is a file, not a folder" if existing == folder else f"lies under a file ('{existing}'), not a folder"
        raise InputError(f"{name} '{folder}' {where}; {fix}.")
    if existing != folder and not os.access(existing, os.W_OK | os.X_OK):
        raise InputError(f"{name} '{folder}' cannot be made: '{existing}' is not writable by this user; {fix}.")
    return folder
