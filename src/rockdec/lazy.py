"""Packages whose public names are imported on first use (``rockdec``, ``rockdec.physics``,
``rockdec.rdd``): ``import rockdec`` stays fast, and no numba kernel compiles until a name
that needs it is read."""

from __future__ import annotations

import sys
from importlib import import_module

__all__ = ["lazy_names"]


def lazy_names(package: str, homes: dict[str, str]):
    """The module-level ``__getattr__`` and ``__dir__`` of ``package`` whose names ``homes``
    (name -> the module that defines it) are imported from their module on first use and
    kept in the package's namespace.

    Examples
    --------
    >>> __getattr__, __dir__ = lazy_names("rockdec", {"InputError": "rockdec.validate"})
    >>> __getattr__("InputError").__name__
    'InputError'
    """

    def __getattr__(name: str):
        if name in homes:
            value = getattr(import_module(homes[name]), name)
            setattr(sys.modules[package], name, value)
            return value
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(homes))

    return __getattr__, __dir__
