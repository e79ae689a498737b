"""LabVIEW's TDMS files: a trial logged by National Instruments' software, channel by channel.

A TDMS file holds groups of channels, each channel a vector with properties: its unit
(``unit_string``), and for a waveform its sample interval (``wf_increment``, s) and start
(``wf_start_offset``); the file and its groups carry properties of their own (a
description, the subject). npTDMS reads the binary format; here the channels become
columns as a MATLAB file's variables do (:mod:`hesspipe.core._mat`):

- a channel is the column ``GROUP/CHANNEL [unit]`` and, where no other group has a channel
  of its name, ``CHANNEL [unit]`` too; a group per run (``Run 1/Yaw``, ``Run 2/Yaw``) is read
  with a ``*`` for the run's number (``output=Run */Yaw``);
- a time-stamp channel is seconds from its first stamp;
- without a time channel, waveforms that share one interval give the column ``time`` from
  it (said in a note);
- the columns are those of the length most channels share, the others left out and said;
- the file's and the groups' text properties are the comments (a ``description`` saying
  ``synthetic`` marks the run synthetic).
"""

from __future__ import annotations

import io as _io
import struct
from pathlib import Path

import numpy as np
import pandas as pd

from ._mat import left_out, record_columns
from .errors import HesspipeError, reason
from .io import read_bytes


def tdms_frame(path: str | Path) -> tuple[pd.DataFrame, tuple[str, ...], list[str], list[str]]:
    """The columns of a TDMS file (:func:`hesspipe.core._mat.record_columns` of its channels).

    Parameters
    ----------
    path : path
        The ``.tdms`` file.

    Returns
    -------
    frame : pandas.DataFrame
        The channels that share the record's length (the length most channels have; the
        longest on a tie), in the file's order, values as written, named with their units.
    comments : tuple of str
        Text properties, ``NAME: text`` (a group's as ``GROUP: NAME: text``).
    notes : list of str
        What reading did, one sentence each.
    others : list of str
        Channels left out: another length (``Run 1/Marker (3 values)``).

    Raises
    ------
    HesspipeError
        Naming the file: missing, not a TDMS file, no numeric channel in it.
    """
    from nptdms import TdmsFile  # deferred: only TDMS files need it

    path = Path(path)
    raw = read_bytes(path, "a LabVIEW TDMS file")
    try:
        tdms = TdmsFile.read(_io.BytesIO(raw))
    except (ValueError, KeyError, IndexError, struct.error, OSError, EOFError) as exc:
        raise HesspipeError(f"{path}: not a readable TDMS file ({reason(exc)}); expected a LabVIEW TDMS file") from None
    comments = [f"{k}: {v}" for k, v in tdms.properties.items() if isinstance(v, str) and v.strip()]
    columns: dict[str, np.ndarray] = {}
    named: dict[str, list[str]] = {}
    steps, notes = {}, []
    for group in tdms.groups():
        comments += [f"{group.name}: {k}: {v}" for k, v in group.properties.items() if isinstance(v, str) and v.strip()]
        for channel in group.channels():
            values = channel[:]
            if np.issubdtype(values.dtype, np.datetime64):
                if not values.size or np.isnat(values).any():
                    continue   # no stamps, or a stamp missing: no clock to read
                stamps = values.astype("datetime64[ns]").astype(np.int64)
                values = (stamps - stamps[0]) * 1e-9
                notes.append(f"TDMS file: channel '{group.name}/{channel.name}': time stamps read as seconds from "
                             "the first")
            elif values.dtype.kind not in "iuf":
                continue   # text, complex: not a signal
            unit = str(channel.properties.get("unit_string", "") or "").strip()
            name = f"{group.name}/{channel.name}" + (f" [{unit}]" if unit else "")
            columns[name] = np.asarray(values, dtype=float)
            named.setdefault(channel.name + (f" [{unit}]" if unit else ""), []).append(name)
            dt = channel.properties.get("wf_increment")
            if dt:
                steps[name] = (float(dt), float(channel.properties.get("wf_start_offset", 0.0) or 0.0))
    if not columns:
        raise HesspipeError(f"{path}: no numeric channel in the TDMS file; expected a channel per signal")
    frame, others = record_columns(columns, named)
    n = len(frame)
    waves = {steps[k] for k in frame.columns if k in steps}
    has_time = any(c.split("/")[-1].split(" [")[0].strip().lower() == "time" for c in frame.columns)
    if len(waves) == 1 and not has_time:
        dt, start = waves.pop()
        frame.insert(0, "time", start + dt * np.arange(n))
        notes.append(f"TDMS file: no time channel: 'time' from the waveforms' interval (wf_increment {dt:g} s)")
    notes.insert(0, f"TDMS file: {len(named)} channel name(s) in {len(tdms.groups())} group(s), {n} samples read, "
                    "units from the channels' unit_string")
    return frame, tuple(comments), notes + left_out("TDMS file", "channel", others), others
