"""Write generated trials the way real loggers write files.

A trial becomes ``NAME.csv`` (SPEC measured-run format), ``NAME.truth.json``
and the folder's ``plants.json`` (what a researcher would hand hesspipe); or a MATLAB file
(:func:`mat_bytes`; a session's runs together, :func:`mat_runs_bytes`) or a workbook
(:func:`xlsx_bytes`). The
CSV's style (time format, line ends, BOM, column order) is drawn per trial
or given:

``time``
    ``"g9"`` seconds from the start with 9 significant digits (60 Hz times then
    jitter by ~1e-7 s), ``"ms"`` rounded to milliseconds, ``"epoch_ms"`` /
    ``"epoch_us"`` Unix time stamps rounded to ms / us, ``"g17"`` exact.
``values``
    printf format of the signal columns (``"%.6g"``).
``newline``
    ``"\\n"`` or ``"\\r\\n"``.
``bom``
    write a UTF-8 byte-order mark.
``columns``
    column order (names as in SPEC; ``error``, the displayed ``reference - output``, may
    stand in place of ``reference``: a laboratory that logs what the display shows).
``epoch0``
    Unix time of the first sample (epoch styles).

Never drawn, given for a laboratory's own files (:data:`LAB`):

``sep``, ``decimal``
    field separator (``","``, ``";"``, ``"\t"``, or ``"   "`` aligned as MATLAB's) and
    decimal mark (``"."`` or ``","``, not the separator).
``degrees``
    every signal in degrees (times 180/pi), its header ``NAME [deg]``.
``names``
    the header of each column by SPEC name (missing: the SPEC name).
``encoding``
    ``"utf-8"``, ``"cp1252"`` or ``"utf-16"`` (its own byte-order mark).
``time`` may also be a printf format of seconds from the start (``"%.5f"``), or
``"clock"``: the time of day ``HH:MM:SS.fff`` from ``clock0`` (s after midnight; a
record may run past midnight).
``units_row``
    units in a row of their own under the names (``s``, ``deg``; ``-`` for radians and
    the stick) instead of in brackets.
``preamble``
    lines of metadata written above everything, not marked as comments.
``repeat``
    sample indices whose row the logger writes twice.
``header``
    False: no header row (MATLAB's ``save -ascii``; :data:`MATLAB`), numbers only under
    the label's comment.
"""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.io import savemat

from ..core.errors import HesspipeError
from ..core.io import atomic_path, to_json, write_json
from .lti import series, tf_dict
from .plants import ANGLE_MOTION, PLATFORM, WASHOUT

TIME_STYLES = ("g9", "ms", "epoch_ms", "epoch_us", "g17")
COLUMNS = ("time", "disturbance", "output", "control", "reference")
LABEL = "synthetic data: independent human-like generator"
PLAIN = {"time": "g17", "values": "%.6g", "newline": "\n", "bom": False,
         "columns": list(COLUMNS), "epoch0": 0.0, "sep": ",", "decimal": ".", "degrees": False,
         "names": None, "encoding": "utf-8", "clock0": 0.0, "units_row": False, "preamble": (),
         "repeat": (), "header": True}
LAB = {"time": "%.5f", "values": "%.5f", "newline": "\r\n", "sep": ";", "decimal": ",", "degrees": True,
       "encoding": "cp1252", "columns": ["time", "reference", "disturbance", "output", "control"],
       "names": {"time": "Time [s]", "reference": "Target", "disturbance": "Disturbance", "output": "Yaw",
                 "control": "Stick"}}
"""A laboratory's logger (a style to give, never drawn): seconds and degrees with five
decimals, semicolons and decimal commas, CRLF, Windows-1252, its own column names
(``--columns reference=Target,disturbance=Disturbance,output=Yaw,control=Stick`` reads it)."""
DAQ = {**LAB, "time": "clock", "clock0": 86400.0 - 45.0, "sep": "\t", "encoding": "utf-16",
       "units_row": True, "repeat": (1234, 5678),
       "names": {**LAB["names"], "time": "Time"},
       "preamble": ("Data acquisition export", "Subject:\ts01", "Sample rate [Hz]:\t100")}
"""Another laboratory's data-acquisition export (a style to give, never drawn): the :data:`LAB`
columns, tab-separated with decimal commas in UTF-16, three lines of metadata above the
header, the units in a row under it, the time of day (the record crosses midnight) and two
frames written twice. The same ``--columns`` as :data:`LAB` read it."""
MATLAB = {**LAB, "time": "%.7e", "values": "%.7e", "sep": "   ", "decimal": ".", "newline": "\n",
          "encoding": "utf-8", "header": False}
"""A third laboratory's export (a style to give, never drawn): MATLAB's ``save -ascii``, the
:data:`LAB` columns in degrees and seconds with eight significant digits, aligned by spaces,
no header row and no units (only the label's ``#`` line above the numbers). Read by position:
``--columns time=1,reference=2,disturbance=3,output=4,control=5``."""
ENCODINGS = ("utf-8", "cp1252", "utf-16")


def draw_style(rng: np.random.Generator) -> dict:
    """Draw a logger style (time format, line ends, BOM, column order).

    Parameters
    ----------
    rng : numpy.random.Generator
    """
    cols = list(COLUMNS) if rng.uniform() < 0.7 else \
        ["time", "reference", "output", "control", "disturbance"]
    return {"time": str(rng.choice(TIME_STYLES, p=[0.35, 0.25, 0.15, 0.15, 0.10])),
            "values": "%.6g", "newline": "\r\n" if rng.uniform() < 0.4 else "\n",
            "bom": bool(rng.uniform() < 0.3), "columns": cols,
            "epoch0": float(np.round(rng.uniform(1.6e9, 1.8e9), 3))}


def _style(style) -> dict:
    if style is None:
        return dict(PLAIN)
    if isinstance(style, str):
        if style == "plain":
            return dict(PLAIN)
        if style in TIME_STYLES:
            return {**PLAIN, "time": style, "epoch0": 1.7e9}
        raise HesspipeError(f"style: expected 'plain', one of {', '.join(TIME_STYLES)} "
                            f"or a dict, got {style!r}")
    out = {**PLAIN, **dict(style)}
    if out["time"] not in (*TIME_STYLES, "clock") and not str(out["time"]).startswith("%"):
        raise HesspipeError(f"style: field 'time': expected one of {', '.join(TIME_STYLES)} "
                            f"or a printf format, got {out['time']!r}")
    if sorted(out["columns"]) not in (sorted(COLUMNS), sorted([*COLUMNS[:-1], "error"])):
        raise HesspipeError(f"style: field 'columns': expected an order of {', '.join(COLUMNS)} "
                            "(or 'error' in place of 'reference')")
    if out["sep"] not in (",", ";", "\t", "   ") or out["decimal"] not in (".", ",") or out["sep"] == out["decimal"]:
        raise HesspipeError(f"style: fields 'sep' and 'decimal': expected a separator of ',', ';', tab or three spaces "
                            f"and another decimal mark '.' or ',', got {out['sep']!r} and {out['decimal']!r}")
    if out["encoding"] not in ENCODINGS:
        raise HesspipeError(f"style: field 'encoding': expected one of {', '.join(ENCODINGS)}, "
                            f"got {out['encoding']!r}")
    return out


def _times(t: np.ndarray, st: dict) -> list[str]:
    kind = st["time"]
    if kind.startswith("%"):
        return [kind % x for x in t]
    if kind == "clock":
        ms = np.round((st["clock0"] + t) * 1000.0).astype(np.int64) % 86_400_000
        return [f"{m // 3_600_000:02d}:{m // 60_000 % 60:02d}:{m // 1000 % 60:02d}.{m % 1000:03d}" for m in ms]
    if kind == "g9":
        return [f"{x:.9g}" for x in t]
    if kind == "ms":
        return [f"{x:.3f}" for x in t]
    if kind == "epoch_ms":
        return [f"{st['epoch0'] + x:.3f}" for x in t]
    if kind == "epoch_us":
        return [f"{st['epoch0'] + x:.6f}" for x in t]
    return [f"{x:.17g}" for x in t]


def csv_bytes(trial, style=None) -> bytes:
    """The CSV file of `trial` in `style` (see module doc), as bytes.

    Parameters
    ----------
    trial : Trial
    style : dict, optional
        A style from :func:`draw_style` (None: the plain default).
    """
    st = _style(style)
    cols = {"time": _times(trial.time, st)}
    fmt, scale = st["values"], (180.0 / np.pi if st["degrees"] else 1.0)
    for name in st["columns"]:
        if name != "time":
            cols[name] = [fmt % (scale * v) for v in _signal(trial, name)]
    if st["decimal"] != ".":
        cols = {c: [v.replace(".", st["decimal"]) for v in vals] for c, vals in cols.items()}
    units = {c: ("" if st["time"] == "clock" else "s") if c == "time" else ("deg" if st["degrees"] else "-")
             for c in st["columns"]}
    names = _header_names(st)
    nl, sep = st["newline"], st["sep"]
    rows = [*st["preamble"], f"# {_label(trial)}"]
    if st["header"]:
        rows.append(sep.join(names[c] for c in st["columns"]))
    if st["units_row"] and st["header"]:
        rows.append(sep.join(units[c] for c in st["columns"]))
    twice = set(int(i) for i in st["repeat"])
    for i in range(len(trial.time)):
        rows += [sep.join(cols[c][i] for c in st["columns"])] * (2 if i in twice else 1)
    text = nl.join(rows) + nl
    bom = b"\xef\xbb\xbf" if st["bom"] and st["encoding"] == "utf-8" else b""
    return bom + text.encode(st["encoding"])


def _signal(trial, name: str) -> np.ndarray:
    """Column `name` of `trial` (``error``: the displayed ``reference - output``)."""
    return trial.reference - trial.output if name == "error" else getattr(trial, name)


def _label(trial) -> str:
    """The line that marks a file of `trial` synthetic, naming the generator and the trial."""
    return f"{LABEL} ({trial.truth['generator']}); trial {trial.spec.name}"


def _header_names(st: dict) -> dict:
    """SPEC column name → the header `st` writes: its own name, `` [deg]`` after each signal in
    degrees unless a units row holds the units."""
    unit = " [deg]" if st["degrees"] and not st["units_row"] else ""
    return {c: (st["names"] or {}).get(c, c) + ("" if c == "time" else unit) for c in (*COLUMNS, "error")}


MAT_NAMES = {"time": "t", "reference": "ft", "disturbance": "fd", "output": "x", "control": "u"}
"""The variables a MATLAB-run laboratory saves a trial as (:func:`mat_bytes`): time, target
forcing, disturbance forcing, the controlled element's output, the stick."""


def mat_bytes(trial, names: dict | None = None, degrees: bool = True) -> bytes:
    """The MATLAB file (version 5, ``.mat``) of `trial`: each signal a column vector named as in
    `names` (default :data:`MAT_NAMES`), angles in degrees when `degrees`, time in seconds, and
    the label in a text variable ``note``.

    Parameters
    ----------
    trial : Trial
    names : dict, optional
        SPEC column name → variable name.
    degrees : bool
        Every signal but time times 180/pi (no unit is written: a MAT file holds none).
    """
    names = {**MAT_NAMES, **(names or {})}
    scale = 180.0 / np.pi if degrees else 1.0
    data = {names[c]: (trial.time if c == "time" else scale * getattr(trial, c)).reshape(-1, 1) for c in COLUMNS}
    data["note"] = _label(trial)
    buf = io.BytesIO()
    savemat(buf, data, format="5", oned_as="column")
    return buf.getvalue()


def mat_runs_bytes(trials, names: dict | None = None, degrees: bool = True) -> bytes:
    """The MATLAB file (version 5) of a session's `trials` saved together: each signal a matrix
    of one column per run (``x`` of samples x runs, read as ``x:1`` ... ``x:R``), the time one
    vector, angles in degrees when `degrees`, the runs' labels in the text variable ``note``.

    Parameters
    ----------
    trials : sequence of Trial
        Runs of one forcing layout: the same time grid (their phases may differ).
    names : dict, optional
        SPEC column name → variable name (default :data:`MAT_NAMES`).
    degrees : bool
        Every signal but time times 180/pi.

    Raises
    ------
    HesspipeError
        No trial, or trials of different time grids.
    """
    trials = list(trials)
    if not trials or any(not np.array_equal(t.time, trials[0].time) for t in trials):
        raise HesspipeError("trials: expected at least one trial, all on the same time grid")
    names = {**MAT_NAMES, **(names or {})}
    scale = 180.0 / np.pi if degrees else 1.0
    data = {names[c]: np.column_stack([scale * getattr(t, c) for t in trials]) for c in COLUMNS if c != "time"}
    data[names["time"]] = trials[0].time.reshape(-1, 1)
    data["note"] = "; ".join(_label(t) for t in trials)
    buf = io.BytesIO()
    savemat(buf, data, format="5", oned_as="column")
    return buf.getvalue()


def xlsx_bytes(trial, style=LAB) -> bytes:
    """The Excel workbook (``.xlsx``) of `trial`: one sheet, the label and two lines of
    metadata above the header, the columns of `style` (default :data:`LAB`: its names, with
    ``[deg]`` units and degrees when it says so), numbers stored as numbers.

    Parameters
    ----------
    trial : Trial
    style : dict
        The columns' order, names and units (``columns``, ``names``, ``degrees``).
    """
    st = _style(style)
    scale = 180.0 / np.pi if st["degrees"] else 1.0
    head = _header_names({**st, "units_row": False})   # a workbook's units stand in its names
    frame = pd.DataFrame({head[c]: (trial.time if c == "time" else scale * _signal(trial, c)) for c in st["columns"]})
    meta = pd.DataFrame([[_label(trial)],
                         [f"Trial: {trial.spec.name}"], ["Sample rate [Hz]: " + f"{1.0 / (trial.time[1] - trial.time[0]):g}"]])
    buf = io.BytesIO()
    with pd.ExcelWriter(buf, engine="openpyxl") as book:
        meta.to_excel(book, sheet_name="trial", header=False, index=False)
        frame.to_excel(book, sheet_name="trial", startrow=len(meta) + 1, index=False)
    return buf.getvalue()


def plants_dict(spec) -> dict:
    """The SPEC plants JSON a researcher would hand hesspipe for this trial.

    Parameters
    ----------
    spec : TrialSpec
    """
    p = spec.plant

    out = {"control_to_output": tf_dict(p.nominal_yc), "disturbance_to_output": tf_dict(p.nominal_yd),
           "source": f"{LABEL} ({p.name}); nominal plants"
                     + (", rolling approximation of the flown aircraft" if "dutch_roll" in spec.effects else "")}
    default = series(PLATFORM, WASHOUT)
    motion = spec.motion_tf if spec.motion_tf is not None else p.motion()
    if not (np.array_equal(motion[0], default[0]) and np.array_equal(motion[1], default[1])):
        out["motion_path"] = tf_dict(motion)
    elif p.output == "angle":
        out["motion_path"] = tf_dict(ANGLE_MOTION)
    return out


def write_trial(folder, trial, style=None) -> Path:
    """Write ``NAME.csv``, ``NAME.truth.json`` and ``plants.json`` into `folder`.

    Parameters
    ----------
    folder : path
        Output folder (created if missing).
    trial : Trial
        From :func:`hesspipe.humanlike.simulate_trial`.
    style : dict or str, optional
        CSV style (module doc); default the style drawn with the trial.

    Returns
    -------
    Path
        The CSV file.

    Raises
    ------
    HesspipeError
        If `folder` already holds a different ``plants.json`` (trials of different
        plants belong in different folders).
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    plants = plants_dict(trial.spec)
    ppath = folder / "plants.json"
    if ppath.exists():
        try:
            old = json.loads(ppath.read_text(encoding="utf-8-sig"))
        except (OSError, ValueError):
            old = None
        if old != json.loads(to_json(plants)):
            raise HesspipeError(f"{ppath}: holds other plants than trial {trial.spec.name}'s; "
                                "expected one plant per folder")
    else:
        write_json(ppath, plants)
    st = style if style is not None else trial.spec.style
    path = folder / f"{trial.spec.name}.csv"
    data = csv_bytes(trial, st)
    truth = dict(trial.truth)
    truth["style"] = _style(st)
    write_json(folder / f"{trial.spec.name}.truth.json", truth)
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return path
