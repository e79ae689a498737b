"""Command-line interface: a thin layer over the library.

Each sub-command lives in :mod:`hesspipe.commands` as a module with
``register(subparsers)``, which adds its parser and sets ``func(args) -> int``.
User mistakes (:class:`~hesspipe.errors.HesspipeError`) become one line on
stderr and exit status 1; argparse usage errors exit with status 2.
"""

from __future__ import annotations

import argparse
import sys

from . import __version__
from .commands import COMMANDS
from .errors import HesspipeError


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, not the whole usage block
        self.exit(2, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="hesspipe", description=(
        "Does the pilot need motion cues? Fly a JSBSim transport on the approach, identify ARX "
        "plants, fit the Hess structural pilot model (original and with motion feedback) to pilot "
        "data, compare pilots and diagnose what a model misses. Start with 'hesspipe run'."))
    parser.add_argument("--version", action="version", version=f"hesspipe {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for module in COMMANDS:
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except HesspipeError as exc:
        from .commands._options import cli_message  # library setting names -> this command's options

        print(f"hesspipe: error: {cli_message(str(exc), args)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("hesspipe: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
