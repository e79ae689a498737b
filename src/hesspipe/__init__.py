"""hesspipe: does the pilot need motion cues?

A pipeline that flies a JSBSim transport on the landing approach, identifies
ARX plants from the records, and closes the Hess structural pilot model
(original, and expanded with motion feedback) around them, reproducing and
extending AIAA 2009-6032 (Zaychik, Cardullo, George, Kelly).
"""

from importlib.metadata import PackageNotFoundError, version as _version

try:
    __version__ = _version("hesspipe")
except PackageNotFoundError:  # running from a source tree without install
    __version__ = "0.0.0+unknown"

from .errors import HesspipeError

__all__ = ["HesspipeError", "__version__"]
