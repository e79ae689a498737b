"""Output paths of the commands, checked before any work so a bad path loses no result."""

from __future__ import annotations

# Imports sit inside the functions: `hesspipe --help` and argument errors load no numpy
# (tests/test_api.py), and each command loads only its own stage.


def check_file_outputs(*, json: str | None = None, figure: str | None = None) -> None:
    """Raise HesspipeError unless `json` (a file) and `figure` (an image file) can be written."""
    from ..core.io import check_output_file

    if json:
        check_output_file(json)
    if figure:
        from ..viz import check_figure_path

        check_figure_path(figure)


def write_result_json(path: str, result, **inputs) -> None:
    """Write ``result.to_dict()`` to `path`, with the input files it came from (`inputs`: key →
    path, or a list of paths; a list of one is written as that path)."""
    from ..core.io import write_json

    def one_or_list(value):
        if not isinstance(value, (list, tuple)):
            return str(value)
        return str(value[0]) if len(value) == 1 else [str(v) for v in value]

    obj = result.to_dict()
    obj.update({key: one_or_list(value) for key, value in inputs.items()})
    write_json(path, obj)
