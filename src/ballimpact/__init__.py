"""ballimpact: force-platform tennis ball impacts and the Goodwill & Haake (2004) ball model."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("ballimpact")
except PackageNotFoundError:  # pragma: no cover - running from a source tree without install
    __version__ = "0+unknown"

__all__ = ["__version__"]
