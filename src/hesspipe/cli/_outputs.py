"""Output paths of the commands, checked before any work so a bad path loses no result."""

from __future__ import annotations

# Imports sit inside the functions: `hesspipe --help` and argument errors load no numpy
# (tests/test_api.py), and each command loads only its own stage.


#: The commands' output files, option → what it holds. (An output folder is refused already
#: when it holds anything hesspipe did not write there, an input among them.)
OUTPUT_FILES = {"json": "the JSON output", "figure": "the figure", "df_figure": "the describing-function figure"}


def add_inputs(parser, *dests: str) -> None:
    """Declare the options (argparse dests) of `parser` that name its input files or folders,
    which :func:`check_outputs_apart` keeps its output files off."""
    parser.set_defaults(_inputs=dests)


def check_outputs_apart(args) -> None:
    """Raise HesspipeError where an output file of the command (:data:`OUTPUT_FILES`) is one of
    its input files (of an input folder, one of its runs), which writing it would destroy."""
    from pathlib import Path

    from ..core.errors import HesspipeError

    outputs = [(getattr(args, dest), what) for dest, what in OUTPUT_FILES.items() if getattr(args, dest, None)]
    if not outputs:
        return
    inputs = []
    for dest in getattr(args, "_inputs", ()):
        value = getattr(args, dest, None)
        inputs.extend(Path(v) for v in (value if isinstance(value, (list, tuple)) else [value]) if v)
    for path in [p for p in inputs if p.is_dir()]:
        from ..pilots.compare import list_runs

        try:
            inputs.extend(list_runs(path))
        except HesspipeError:   # no runs: the command says so itself
            pass
    for out, what in outputs:
        if any(_same(Path(out), path) for path in inputs):
            raise HesspipeError(f"{out}: is an input of this command; expected another path for {what}")


def _same(a, b) -> bool:
    try:
        # samefile: also a hard link, or another spelling on a case-insensitive file system
        return a.resolve() == b.resolve() or (a.exists() and b.exists() and a.samefile(b))
    except OSError:
        return False


def check_file_outputs(*, json: str | None = None, figure: str | None = None) -> None:
    """Raise HesspipeError unless `json` (a file) and `figure` (an image file) can be written."""
    from ..core.io import check_output_file

    if json:
        check_output_file(json)
    if figure:
        from ..viz import check_figure_path

        check_figure_path(figure)


def write_command_json(path: str, obj: dict, **inputs) -> None:
    """Write a command's result `obj` to `path` with what it came from: `inputs` (key → a path,
    a list of paths, a list of one written as that path, or a number such as the seed) and the
    hesspipe version."""
    from .. import __version__
    from ..core.io import write_json

    def one_or_list(value):
        if isinstance(value, (int, float)):
            return value
        if not isinstance(value, (list, tuple)):
            return str(value)
        return str(value[0]) if len(value) == 1 else [str(v) for v in value]

    write_json(path, {**obj, **{key: one_or_list(value) for key, value in inputs.items()},
                      "hesspipe_version": __version__})


def write_result_json(path: str, result, **inputs) -> None:
    """Write ``result.to_dict()`` to `path` (:func:`write_command_json`)."""
    write_command_json(path, result.to_dict(), **inputs)
