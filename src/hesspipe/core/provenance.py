"""Provenance: versions, hashes and manifests written beside every output."""

from __future__ import annotations

import hashlib
import platform
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from .. import __version__

_PACKAGES = ("jsbsim", "numpy", "scipy", "control", "pandas", "matplotlib")


def versions() -> dict[str, str]:
    """Versions of hesspipe, Python and the numerical dependencies."""
    out = {"hesspipe": __version__, "python": platform.python_version()}
    for name in _PACKAGES:
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = "not installed"
    return out


def file_hash(path: str | Path) -> str:
    """SHA-256 of a file's bytes, as ``"sha256:<hex>"``.

    Parameters
    ----------
    path : str or Path
        The file (read in 1 MiB chunks).
    """
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return "sha256:" + h.hexdigest()
