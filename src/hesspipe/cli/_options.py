"""Options shared by several commands, and the mapping of library wording to them.

The library names its own settings in messages ("set resample to interpolate",
"map other names with columns control=NAME", "free: ..."), never a
command-line flag. Each command declares, with :func:`add_terms`, how those
settings are spelled on its command line; :func:`cli_message` rewrites a
message accordingly, so no message suggests an option the command lacks.
"""

from __future__ import annotations

import argparse
import re
import sys

from ..core.choices import DEFAULT_DISPLAY, DISPLAYS
from ..core.errors import HesspipeError
from ..core.seeds import check_seed

#: ``--forcing``'s choices: the names of :data:`hesspipe.flight.target.FORCINGS`, spelled here
#: so that building ``--help`` imports no stage (tests/test_cli.py checks they are the same).
FORCING_CHOICES = ("paper", "two_input")

#: Library wording → command-line wording of the options added by :func:`add_run_options`.
RUN_TERMS = {
    r"\bset resample\b": "pass --resample",
    r"\bwith columns\b": "with --columns",
    r"(^|: )columns: ": r"\1--columns: ",
    r"\(sample_rate\)": "(--sample-rate HZ)",
    r"(^|: )sample_rate: ": r"\1--sample-rate: ",
}


def add_terms(parser: argparse.ArgumentParser, terms: dict[str, str]) -> None:
    """Declare that `parser`'s command spells library settings as in `terms` (regex → text)."""
    parser.set_defaults(_terms={**(parser.get_default("_terms") or {}), **terms})


def field_terms(settings: str, flags: dict[str, str]) -> dict[str, str]:
    """Terms for a settings class's own errors (``DiagnoseConfig: field 'alpha': ...``,
    :class:`hesspipe.core.config.Settings`), each field spelled as its flag (``--alpha: ...``)."""
    return {rf"(^|: ){settings}: field '{field}': ": rf"\1{flag}: " for field, flag in flags.items()}


def cli_message(message: str, args: argparse.Namespace | None) -> str:
    """`message` with the library's setting names replaced by the command's options."""
    for pattern, text in (getattr(args, "_terms", None) or {}).items():
        message = re.sub(pattern, text, message)
    return message


def add_run_options(parser: argparse.ArgumentParser) -> None:
    """``--columns``, ``--resample`` and ``--sample-rate`` for a command that reads measured runs.

    Pass them on with ``read_file_runs(path, **run_options(args))``.
    """
    parser.add_argument("--columns", metavar="ROLE=NAME,...",
                        help="map other column names, e.g. control=stick,output=p (a file without a "
                             "header row: by position, time=1,control=4; a .mat file: by variable, "
                             "time=t,control=u; a file of several runs, a column each: '*' for the "
                             "run's number, output=x:*,control=u:*; runs one after another in a long "
                             "table: the columns that tell them apart, person=Subject,run=Trial; "
                             "-NAME flips a sign; a signal column A|B: whichever of A and B a file "
                             "has)")
    parser.add_argument("--resample", action="store_true",
                        help="interpolate a non-uniform time column onto a uniform grid, and a "
                             "missed sample (an empty or NaN cell) (default: refuse them)")
    parser.add_argument("--sample-rate", type=float, metavar="HZ",
                        help="sample rate of files without a time column (sample k at k/HZ s); "
                             "a file with times must agree with it")
    add_terms(parser, RUN_TERMS)


def run_options(args: argparse.Namespace) -> dict:
    """Keyword arguments of :func:`hesspipe.core.formats.read_run` from :func:`add_run_options`."""
    return {"columns": args.columns, "resample": bool(args.resample), "sample_rate": args.sample_rate}


def reading_lines(reading) -> list[str]:
    """What reading the runs did beyond the plain format (file → notes), one line per note.

    A note that several files share (a laboratory writes every run alike: the same
    units, the same separator) is said once with their count and first and last file,
    so that a folder of 100 runs gives a few lines, not 500, and a note that only
    some file has is not lost among them.
    """
    files: dict[str, list[str]] = {}
    for source, notes in reading.items():
        for note in dict.fromkeys(notes):
            files.setdefault(note, []).append(str(source))
    lines = []
    for note, sources in files.items():
        if len(sources) == 1:
            where = sources[0]
        else:
            noun = "runs" if any("#" in s for s in sources) else "files"   # PATH#k: a file's run k
            where = f"{len(sources)} {noun} ({sources[0]} … {sources[-1]})"
        lines.append(f"hesspipe: note: {where}: {note}")
    return lines


def print_reading(reading) -> None:
    """On stderr, :func:`reading_lines` of `reading` (file → notes)."""
    for line in reading_lines(reading):
        print(line, file=sys.stderr)


def read_cli_plants(path):
    """:func:`hesspipe.core.formats.read_plants` of `path`, with a note on stderr where its
    motion path is likely wrong for the motion test (:func:`hesspipe.pilot.motion.motion_path_note`)."""
    from ..core.formats import read_plants
    from ..pilot.motion import motion_path_note

    plants = read_plants(path)
    note = motion_path_note(plants)
    if note:
        print(f"hesspipe: note: {path}: {note}", file=sys.stderr)
    return plants


def read_cli_runs(paths, args: argparse.Namespace, **kwargs) -> list:
    """:func:`hesspipe.core.formats.read_file_runs` of each path with the command's run
    options (`kwargs` over them), the runs in file order; the notes of all of them on stderr once they are read
    (:func:`reading_lines`)."""
    from ..core.formats import read_file_runs

    runs = [run for path in paths for run in read_file_runs(path, **{**run_options(args), **kwargs})]
    print_reading({run.source: run.notes for run in runs})
    return runs


def check_aircraft(name: str | None) -> None:
    """``--aircraft NAME`` (None: not given) checked before a configuration takes it over, so
    that a bad one is blamed on the flag, not on the configuration's file."""
    if name is None:
        return
    from ..flight.aircraft import load_aircraft

    try:
        load_aircraft(name)
    except HesspipeError as exc:
        raise HesspipeError(f"--aircraft: {exc}") from None


def read_cli_flight(args: argparse.Namespace) -> tuple:
    """The aircraft, :class:`~hesspipe.flight.approach.FlightConfig` and seed of ``--aircraft``,
    ``--config FILE`` and ``--seed``.

    The file is read as ``hesspipe run --config`` reads it
    (:func:`hesspipe.pipeline.stages.load_config` and :func:`~hesspipe.pipeline.stages.flight_settings`:
    its sections, seed and ``[flight]`` table checked), so that a copy of the default
    configuration serves every command and flies what ``hesspipe run`` flies with it;
    ``--aircraft`` wins over its ``[flight] aircraft`` and ``--seed`` over its ``seed``
    (without either: 0).
    """
    from ..flight.aircraft import DEFAULT_AIRCRAFT
    from ..flight.approach import FlightConfig

    if args.config is None:
        aircraft, settings, seed = DEFAULT_AIRCRAFT, FlightConfig(), 0
    else:
        from ..pipeline.stages import flight_settings, load_config

        config, source = load_config(args.config)
        (aircraft, settings), seed = flight_settings(config, source), config["seed"]
    return ((aircraft if args.aircraft is None else args.aircraft), settings,
            (seed if args.seed is None else args.seed))


def seed_arg(text: str) -> int:
    """argparse type of every ``--seed``: the one rule of :func:`hesspipe.core.seeds.check_seed`."""
    try:
        value = int(text.strip())
    except ValueError:
        value = text
    try:
        return check_seed(value, "seed")
    except HesspipeError:
        raise argparse.ArgumentTypeError(f"expected an integer 0 <= seed < 2**63, got {text!r}") from None


def add_seed(parser: argparse.ArgumentParser, default: int | None = 0, help: str = "random seed") -> None:
    """``--seed`` with the one seed rule."""
    tail = f" (default: {default})" if default is not None else ""
    parser.add_argument("--seed", type=seed_arg, default=default, metavar="N",
                        help=f"{help}, an integer 0 <= N < 2**63{tail}")


def add_display(parser: argparse.ArgumentParser, seen_by: str = "the pilot") -> None:
    """``--display``, what the pilot saw (:data:`hesspipe.core.choices.DISPLAYS`)."""
    parser.add_argument("--display", choices=DISPLAYS, default=DEFAULT_DISPLAY,
                        help=f"what {seen_by} saw (default {DEFAULT_DISPLAY}): compensatory (the error "
                             "alone), pursuit (target and output apart: the motion test fits the "
                             "feedforward humans add) or either (not known: motion only if the test "
                             "finds it for both, where the record shows that feedforward; else for "
                             "compensatory)")
