"""Sub-commands of the ``hesspipe`` CLI, one module each.

A module here defines ``register(subparsers)``; add it to :data:`COMMANDS`.
"""

from importlib import import_module

_NAMES = [
    # one line per command module, in the order of `hesspipe --help`
    "run",
    "status",
    "flight",
    "plants",
    "identify",
    "frf",
    "synth_pilots", "pilots", "conditions",
    "fly_pilot",
    "diagnose",
]

COMMANDS = [import_module(f".{name}", __package__) for name in _NAMES]
