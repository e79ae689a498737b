"""Lazy re-exports for packages (the pattern of scientific Python's SPEC 1).

A stage package lists the names it offers and the module defining each; a name's
module is imported on first use. ``import hesspipe.flight.aircraft`` then costs only
that module, and the command line starts without numpy.
"""

from __future__ import annotations

import sys
from importlib import import_module
from typing import Callable, Mapping


def attach(package: str, names: Mapping[str, str]) -> tuple[Callable, Callable, list[str]]:
    """``(__getattr__, __dir__, __all__)`` for `package` re-exporting `names`.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    names : mapping
        Exported name -> module (relative to `package`, e.g. ``"hess"``) that defines it.
    """
    def __getattr__(name: str):
        module = names.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(import_module(f".{module}", package), name)

        setattr(sys.modules[package], name, value)  # later look-ups skip this function
        return value

    def __dir__():

        return sorted(set(vars(sys.modules[package])) | set(names))

    return __getattr__, __dir__, list(names)
