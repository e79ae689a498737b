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
    path, or a list of paths)."""
    from ..core.io import write_json

    obj = result.to_dict()
    obj.update({key: [str(v) for v in value] if isinstance(value, (list, tuple)) else str(value)
                for key, value in inputs.items()})
    write_json(path, obj)
