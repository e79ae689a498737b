"""Command-line interface: a thin layer over the library.

Each sub-command lives in :mod:`hesspipe.cli` as a module with
``register(subparsers)``, which adds its parser and sets ``func(args) -> int``.
User mistakes (:class:`~hesspipe.core.errors.HesspipeError`) become one line on
stderr and exit status 1; argparse usage errors exit with status 2.
"""

from __future__ import annotations

# Imports sit inside the functions: `hesspipe --help` and argument errors load no numpy
# (tests/test_api.py), and each command loads only its own stage.
import argparse
import contextlib
import os
import signal
import sys
import threading

from .. import __version__
from ..core import stops
from ..core.errors import HesspipeError
from ._outputs import check_outputs_apart
from .commands import COMMANDS


class _Parser(argparse.ArgumentParser):
    _argv: list = []

    def parse_known_args(self, args=None, namespace=None):
        self._argv = list(sys.argv[1:] if args is None else args)
        return super().parse_known_args(args, namespace)

    def _command_parser(self) -> argparse.ArgumentParser:
        """The parser of the command given (argparse reports a command's unknown options
        from the top-level parser), or this one."""
        for action in self._actions:
            if isinstance(action, argparse._SubParsersAction):
                for token in self._argv:
                    if token in action.choices:
                        return action.choices[token]
        return self

    def _unknown(self) -> str | None:
        """The first option given that this parser does not know, with the nearest it does."""
        import difflib

        known = [o for o in self._command_parser()._option_string_actions if o.startswith("--")]
        for token in self._argv:
            flag = token.split("=", 1)[0]
            if flag.startswith("--") and not any(o.startswith(flag) for o in known):
                near = difflib.get_close_matches(flag, known, n=1, cutoff=0.75)
                return f"unrecognized option {flag}" + (f" (did you mean {near[0]}?)" if near else "")
        return None

    def error(self, message):  # one line, not the whole usage block
        # A misspelt option leaves its option "required": name the misspelling instead
        # ("--plnats" read "the following arguments are required: --plants").
        if message.startswith(("the following arguments are required", "unrecognized arguments")):
            message = self._unknown() or message
        prog = self._command_parser().prog
        self.exit(2, f"{prog}: error: {message} (see '{prog} --help')\n")


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


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread so it unwinds like Ctrl-C: worker pools are
    stopped, staging folders removed, nothing half-published."""


def _on_sigterm(signum, frame):
    stops.request(signum)   # acted on again if the exception is swallowed (core.stops)
    raise Terminated


def _on_sigint(signum, frame):
    stops.request(signum)
    raise KeyboardInterrupt


#: matplotlib's folder of a command's own (:func:`_matplotlib_folder_of_its_own`), with the
#: process id after it.
MATPLOTLIB_PREFIX = "hesspipe-matplotlib-"


@contextlib.contextmanager
def _matplotlib_folder_of_its_own():
    """Give matplotlib a configuration folder of this command's own, removed when it ends.

    Loaded (by python-control, so by nearly every command), matplotlib creates
    ``~/.config/matplotlib`` and writes its font list to ``~/.cache/matplotlib``: outside the
    output folder the user chose. A folder the user chose (``MPLCONFIGDIR``) is kept, and so
    is a matplotlib already loaded (a caller's process). Building the font list again costs
    about 0.2 s per command.
    """
    if "MPLCONFIGDIR" in os.environ or "matplotlib" in sys.modules:
        yield
        return
    import shutil
    import tempfile

    from ..core.io import remove_leftovers

    # A command killed outright (SIGKILL) left its folder; the next one removes it.
    remove_leftovers(tempfile.gettempdir(), prefix=MATPLOTLIB_PREFIX)
    folder = tempfile.mkdtemp(prefix=f"{MATPLOTLIB_PREFIX}{os.getpid()}-")
    os.environ["MPLCONFIGDIR"] = folder
    try:
        yield
    finally:
        os.environ.pop("MPLCONFIGDIR", None)
        if "matplotlib" in sys.modules:
            # Loaded, it keeps the folder as its own for the process's life (main() called
            # from Python): removed when the process ends.
            import atexit

            atexit.register(shutil.rmtree, folder, True)
        else:
            shutil.rmtree(folder, ignore_errors=True)


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    in_main_thread = threading.current_thread() is threading.main_thread()
    stops.clear()
    previous = ({sig: signal.signal(sig, handler) for sig, handler in
                 ((signal.SIGTERM, _on_sigterm), (signal.SIGINT, _on_sigint))} if in_main_thread else {})
    try:
        # Before anything loads python-control, which loads matplotlib.
        with _matplotlib_folder_of_its_own():
            check_outputs_apart(args)  # before any work, for every command
            code = int(args.func(args) or 0)
            stops.act()   # a stop whose exception was swallowed ends the command as it would have
            return code
    except HesspipeError as exc:
        from ._options import cli_message  # library setting names -> this command's options

        print(f"hesspipe: error: {cli_message(str(exc), args)}", file=sys.stderr)
        return 1
    except Terminated:
        print("hesspipe: terminated", file=sys.stderr)
        return 128 + signal.SIGTERM
    except KeyboardInterrupt:
        print("hesspipe: interrupted", file=sys.stderr)
        return 130
    except OSError as exc:
        # Last resort: the file system refused something no check foresaw (a disk that
        # filled up, a folder made read-only mid-run). One line naming the path.
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"hesspipe: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return 1
    finally:
        stops.clear()
        stops.restore(previous)


