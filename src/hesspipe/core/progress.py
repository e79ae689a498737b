"""Progress bars for batches: shown on a terminal, silent otherwise.

A batch run from a script, a pipeline or a test must not fill logs with
carriage-return animations, so the bar is enabled only when stderr is a
terminal (tqdm draws on stderr).
"""

from __future__ import annotations

import sys

from tqdm import tqdm


class _Bar(tqdm):
    # No monitor thread: batches fork worker processes, and forking a process that runs
    # threads is unsafe (hesspipe.pilots.batch falls back to the slower forkserver then).
    monitor_interval = 0


def progress_enabled(stream=None) -> bool:
    """True if `stream` (default ``sys.stderr``) is an interactive terminal.

    Parameters
    ----------
    stream : file-like, optional
        The stream progress would be written to.
    """
    stream = sys.stderr if stream is None else stream
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # closed or replaced streams
        return False


def progress_bar(total: int, desc: str, *, enable: bool | None = None, unit: str = "it") -> tqdm:
    """Return a tqdm bar over `total` items; disabled unless `enable` or a tty.

    Parameters
    ----------
    total : int
        Number of items the batch will report with ``bar.update(1)``.
    desc : str
        Short label shown before the bar.
    enable : bool, optional
        Force the bar on or off; default: on only when stderr is a terminal.
    unit : str
        Name of one item ("pilot", "run"...).
    """
    if enable is None:
        enable = progress_enabled()
    return _Bar(total=total, desc=desc, unit=unit, disable=not enable, file=sys.stderr,
                dynamic_ncols=True, leave=False)
