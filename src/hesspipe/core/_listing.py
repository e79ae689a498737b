"""Which files of a folder are runs: the listing the pilots stage, its inputs' fingerprint
and the command line share.

Free of numpy, pandas and python-control, so that an up-to-date ``hesspipe run`` lists a data
folder's files without importing the readers (the pipeline's fingerprints, issue 7's < 3 s
re-run).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Iterable

from .errors import HesspipeError

#: File endings of measured runs when a folder is a set of pilots (tab-separated files and
#: LabVIEW's measurement files are the same table, MATLAB files and NumPy archives its columns
#: as variables, a workbook's first sheet of numbers, LabVIEW's TDMS files channels, HDF5
#: files datasets;
#: :func:`~hesspipe.core.formats.read_run` reads each).
RUN_SUFFIXES = (".csv", ".tsv", ".lvm", ".mat", ".npz", ".xlsx", ".xlsm", ".tdms", ".h5", ".hdf5")
#: A folder's run files where it has none of RUN_SUFFIXES (exporters' other text tables).
TEXT_SUFFIXES = (".txt", ".dat")


def _natural(path: Path) -> list:
    # s2 before s10, as a lab numbers its subjects (a plain sort put s10 first).
    # The name last: s01 and s1 tie on the numbers, and the folder's listing order is the
    # file system's.
    return [(0, int(t), "") if t.isdigit() else (1, 0, t) for t in re.split(r"(\d+)", path.name)] + [(2, 0, path.name)]


def list_runs(paths_or_dir: str | Path | Iterable[str | Path]) -> list[Path]:
    """The run files of a folder (``*.csv``, ``*.tsv``, ``*.lvm``, ``*.mat``, ``*.xlsx`` and
    ``*.xlsm``, in natural order: s2 before s10; in a folder without them ``*.txt`` and ``*.dat``) or of an explicit list.

    ``*.truth.json`` and other files beside the runs are ignored.

    Parameters
    ----------
    paths_or_dir : path or iterable of paths
        A folder, one run file, or a list of files (taken as given); an empty folder or
        list, or a missing path, raises HesspipeError.
    """
    if isinstance(paths_or_dir, (str, Path)):
        path = Path(paths_or_dir)
        if path.is_dir():
            files = sorted((p for p in path.iterdir() if p.is_file() and p.suffix.lower() in RUN_SUFFIXES),
                           key=_natural)
            # Exporters also write .txt and .dat; beside CSV runs such a file is a README or a
            # log, in a folder of them they are the runs.
            files = files or sorted((p for p in path.iterdir() if p.is_file() and p.suffix.lower() in TEXT_SUFFIXES),
                                    key=_natural)
            if not files:
                raise HesspipeError(f"{path}: no run files (*.csv, *.tsv, *.lvm, *.mat, *.xlsx; else *.txt, *.dat) in this folder")
            return files
        if not path.exists():
            raise HesspipeError(f"{path}: not found; expected a folder of run files or a run file (CSV, MAT, XLSX)")
        return [path]
    if not isinstance(paths_or_dir, Iterable):   # a Run given alone lands here: it is not iterable
        raise HesspipeError(f"paths_or_dir: expected a folder, run files or Runs, got {type(paths_or_dir).__name__}")
    given = list(paths_or_dir)
    odd = next((p for p in given if not isinstance(p, (str, Path))), None)
    if odd is not None:
        raise HesspipeError(f"paths_or_dir: expected a folder, run files or Runs, got a list holding "
                            f"{type(odd).__name__}")
    files = [Path(p) for p in given]
    if not files:
        raise HesspipeError("paths_or_dir: no run files given; expected a folder or a list of run files")
    return files
