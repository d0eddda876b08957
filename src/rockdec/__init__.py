"""rockdec: the coefficient of restitution of a rocking block by the Random Decrement technique."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("rockdec")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"
