"""hesspipe: does the pilot need motion cues?

A pipeline that flies a JSBSim transport on the landing approach, identifies
ARX plants from the records, and closes the Hess structural pilot model
(original, and expanded with motion feedback) around them, reproducing and
extending AIAA 2009-6032 (Zaychik, Cardullo, George, Kelly).
"""

from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _version

try:
    __version__ = _version("hesspipe")
except PackageNotFoundError:  # running from a source tree without install
    __version__ = "0.0.0+unknown"

from .errors import HesspipeError

#: The researcher's API: name -> module that defines it. Loaded on first use, so that
#: ``import hesspipe`` (and the command line's start-up) stays light.
_API = {
    "read_run": "formats", "write_run": "formats", "read_plants": "formats",
    "write_plants": "formats", "Run": "formats", "Plants": "formats",
    "fly": "flight", "FlightConfig": "flight",
    "fly_pilot": "pilotflight",
    "fit_plants": "plants",
    "PilotModel": "hess", "simulate": "hess",
    "identify": "identify",
    "estimate_frf": "frf",
    "compare_pilots": "compare",
    "diagnose": "discrepancy",
}

__all__ = ["HesspipeError", "__version__", *_API]


def __getattr__(name: str):
    module = _API.get(name)
    if module is None:
        raise AttributeError(f"module 'hesspipe' has no attribute {name!r}")
    from importlib import import_module

    value = getattr(import_module(f".{module}", __name__), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__():
    return sorted(set(globals()) | set(_API))
