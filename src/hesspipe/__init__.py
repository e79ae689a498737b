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

from .core.errors import HesspipeError
from .core.lazy import attach

#: The researcher's API: name -> module that defines it. Loaded on first use, so that
#: ``import hesspipe`` (and the command line's start-up) stays light. Each stage is also a
#: package of the same name (``hesspipe.flight``, ``hesspipe.plants``, ``hesspipe.pilots``,
#: ``hesspipe.diagnose``); the ``diagnose`` package is callable as the stage's function.
_API = {
    "read_run": "core.formats", "read_file_runs": "core.formats", "write_run": "core.formats", "read_plants": "core.formats",
    "write_plants": "core.formats", "Run": "core.formats", "Plants": "core.formats",
    "fly": "flight", "FlightConfig": "flight", "fly_pilot": "flight",
    "fit_plants": "plants", "PlantsConfig": "plants",
    "PilotModel": "pilot", "simulate": "pilot", "synthetic_run": "pilot", "Simulator": "pilot",
    "identify": "identification", "estimate_frf": "identification", "average_frf": "identification",
    "compare_pilots": "pilots", "PilotsConfig": "pilots", "compare_conditions": "pilots",
    "DiagnoseConfig": "diagnose", "Diagnosis": "diagnose",
    "to_json": "core.io",
}

#: The packages, each also an attribute of ``hesspipe`` (imported on first use).
#: ``diagnose`` is callable: ``hesspipe.diagnose(run, plants)`` runs the diagnosis.
PACKAGES = ("core", "pilot", "flight", "plants", "identification", "pilots", "diagnose", "pipeline",
            "viz", "humanlike")

_getattr, _dir, _exported = attach(__name__, _API)
__all__ = ["HesspipeError", "__version__", *_exported, "diagnose"]


def __getattr__(name: str):
    if name in PACKAGES:
        from importlib import import_module

        return import_module(f".{name}", __name__)  # the import binds it here too
    return _getattr(name)


def __dir__():
    return sorted(set(_dir()) | set(PACKAGES))
