"""A stop the user asked for, kept until a safe point acts on it.

The command line turns SIGTERM and Ctrl-C into an exception raised wherever the main thread
happens to be. Raised inside an at-fork handler (the logging module's, which runs in the
parent each time a worker pool forks a process) or a finaliser, Python only prints it as
"Exception ignored" and goes on: a SIGTERM sent while ``hesspipe run`` started its pilots
stage's workers let the run finish and publish every stage (a CI run on a loaded machine).
So the command's handlers also record the signal here, and the points where a stage is about
to be published (:func:`hesspipe.core.io.staged_output`) and where the command ends raise it
again, now where nothing swallows it. Library use installs no handler and records nothing.
"""

from __future__ import annotations

import signal
from typing import Mapping

_REQUESTED: list[int] = []


def request(signum: int) -> None:
    """Record a stop signal; its handler calls this before it raises.

    Parameters
    ----------
    signum : int
        The signal (``signal.SIGTERM``, ``signal.SIGINT``).
    """
    _REQUESTED.append(int(signum))


def clear() -> None:
    """Forget recorded stops (a command's start and end)."""
    _REQUESTED.clear()


def act() -> None:
    """Raise a recorded stop again through its handler (``signal.raise_signal``), which
    raises its exception here; nothing where no stop was recorded."""
    if _REQUESTED:
        signum = _REQUESTED[0]
        _REQUESTED.clear()
        signal.raise_signal(signum)


def restore(handlers: Mapping[int, object]) -> None:
    """Put back the signal handlers a block replaced (``signal.signal``'s return values).

    Parameters
    ----------
    handlers : mapping
        Signal → the handler it had; None (a handler installed outside Python, an embedding
        host) puts back the default.
    """
    for sig, handler in handlers.items():
        signal.signal(sig, signal.SIG_DFL if handler is None else handler)
