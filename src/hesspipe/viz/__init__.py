"""Figures, one module per concept (flight, plants, pilots, diagnose).

Plotting is kept out of the numerical modules; every figure is saved
atomically with :func:`save_figure`. Figures are built with matplotlib's object
API (:class:`matplotlib.figure.Figure`, no pyplot): importing hesspipe never
switches the backend of a notebook or an application that uses it.
"""

from __future__ import annotations

from pathlib import Path

from matplotlib.figure import Figure

from ..core.io import atomic_path

SYNTHETIC_LABEL = "SYNTHETIC DATA"


def subplots(*args, figsize=None, **kwargs):
    """``(figure, axes)`` like ``pyplot.subplots``, outside pyplot's global state.

    Parameters
    ----------
    *args, **kwargs
        As :meth:`matplotlib.figure.Figure.subplots` (rows, columns, sharex ...).
    figsize : (float, float), optional
        Figure size, inches.
    """
    fig = Figure(figsize=figsize)
    return fig, fig.subplots(*args, **kwargs)


def check_figure_path(path: str | Path) -> Path:
    """Raise unless `path` names an image format matplotlib writes and can be written
    (checked before computing); no suffix means PNG.

    Parameters
    ----------
    path : str or Path
        The image file.
    """
    from ..core.errors import HesspipeError
    from ..core.io import check_output_file

    path = Path(path)
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    formats = FigureCanvasAgg.get_supported_filetypes()
    suffix = path.suffix.lstrip(".").lower()
    if suffix and suffix not in formats:
        raise HesspipeError(f"{path}: unknown image format '.{suffix}'; expected one of "
                            f"{', '.join('.' + f for f in sorted(formats))}")
    return check_output_file(path)


def save_figure(fig, path: str | Path, *, synthetic: bool = False, dpi: int = 110) -> Path:
    """Save `fig` to `path` atomically.

    If `synthetic`, the figure is stamped "SYNTHETIC DATA" so it can never be
    mistaken for measured data.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path : str or Path
        The image file (format by suffix; none: PNG).
    synthetic : bool
        Stamp "SYNTHETIC DATA".
    dpi : int
        Resolution, dots per inch.
    """
    if synthetic:
        fig.text(0.995, 0.005, SYNTHETIC_LABEL, ha="right", va="bottom", color="crimson",
                 fontsize=9, fontweight="bold")
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format=Path(path).suffix.lstrip(".").lower() or "png")
    return Path(path)
