"""Five known signals of a measured run (SYNTHETIC, built here), for the readers of other
file formats to write and read back: :func:`signals` and :func:`check`."""

from __future__ import annotations

import numpy as np

N, DT = 400, 0.01
"""Samples and interval, s."""


def signals() -> dict:
    """Role → values: time (s) and four smooth signals of distinct frequencies."""
    t = DT * np.arange(N)
    return {"time": t, "disturbance": np.sin(0.7 * t), "output": 0.1 * np.cos(1.3 * t),
            "control": np.sin(2.1 * t), "reference": 0.05 * np.sin(0.4 * t)}


def check(run) -> None:
    """Assert that `run` holds :func:`signals` (to 1e-9)."""
    for role, want in signals().items():
        np.testing.assert_allclose(getattr(run, role), want, rtol=1e-9, atol=1e-12)


def refused(path, content: bytes | None, pattern: str) -> None:
    """Write `content` to `path` (None: written already) and assert that reading it as a run
    raises a HesspipeError matching `pattern`."""
    import pytest

    from hesspipe.core.errors import HesspipeError
    from hesspipe.core.formats import read_run

    if content is not None:
        path.write_bytes(content)
    with pytest.raises(HesspipeError, match=pattern):
        read_run(path)
