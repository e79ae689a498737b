"""Runs logged by LabVIEW as TDMS files (:mod:`hesspipe.core._tdms`): channels with units,
waveforms without a time channel, a group per run, time stamps. The files are written by
npTDMS's writer (a writer of the published format, no hesspipe code); the signals are built
here (SYNTHETIC)."""

from __future__ import annotations

import numpy as np
import pytest
from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_file_runs, read_run
from hesspipe.pilots.compare import list_runs
from known_signals import refused
from test_runs_in_file import signals

LAB = {"reference": "Target", "disturbance": "Disturbance", "output": "Yaw", "control": "Stick"}


def _write(path, groups: dict, root=None, time_channel=True, stamps=False):
    """A TDMS file: per group, `LAB`'s channels in degrees (scaled by the group's factor),
    with or without a time channel (waveforms then) or with a time-stamp channel."""
    s = signals()
    objects = [RootObject(properties=root or {})]
    for group, k in groups.items():
        objects.append(GroupObject(group, properties={"subject": "s01"}))
        if time_channel:
            if stamps:
                t0 = np.datetime64("2026-11-29T23:59:58")
                times = t0 + (s["time"] * 1e9).round().astype("timedelta64[ns]")
                objects.append(ChannelObject(group, "Time", times))
            else:
                objects.append(ChannelObject(group, "Time", s["time"], properties={"unit_string": "s"}))
        for role, name in LAB.items():
            values = np.degrees(s[role]) * (k if role in ("output", "control") else 1.0)
            props = {"unit_string": "deg"}
            if not time_channel:
                props.update(wf_increment=0.01, wf_start_offset=0.0)
            objects.append(ChannelObject(group, name, values, properties=props))
    objects.append(ChannelObject(next(iter(groups)), "Marker", np.arange(3.0)))
    with TdmsWriter(str(path)) as writer:
        writer.write_segment(objects)
    return s


def test_a_tdms_trial_is_read_with_its_units(tmp_path):
    s = _write(tmp_path / "s01_motion_r1.tdms", {"Data": 1.0}, root={"description": "synthetic trial"})
    cols = "time=Time," + ",".join(f"{r}={n}" for r, n in LAB.items())
    run = read_run(tmp_path / "s01_motion_r1.tdms", columns=cols)
    assert run.synthetic and run.id == "s01_motion_r1"
    for role in ("time", "reference", "disturbance", "output", "control"):
        np.testing.assert_allclose(getattr(run, role), s[role], rtol=1e-12, atol=1e-12)
    assert any("'Yaw [deg]' (output): deg converted" in n for n in run.notes), run.notes
    assert any("left out 1 channel(s) of another length: Data/Marker (3 values)" in n for n in run.notes)
    assert [p.name for p in list_runs(tmp_path)] == ["s01_motion_r1.tdms"]   # a folder's run


def test_waveforms_without_a_time_channel_and_a_group_per_run(tmp_path):
    s = _write(tmp_path / "s02.tdms", {"Run 1": 1.0, "Run 2": 2.0, "Run 3": 3.0}, time_channel=False)
    cols = ",".join(f"{r}=Run */{n}" for r, n in LAB.items())
    runs = read_file_runs(tmp_path / "s02.tdms", columns=cols)
    assert [r.id for r in runs] == ["s02#1", "s02#2", "s02#3"]
    for k, run in enumerate(runs, 1):
        np.testing.assert_allclose(run.time, s["time"], atol=1e-12)
        np.testing.assert_allclose(run.control, k * s["control"], rtol=1e-12)
        assert any("no time channel: 'time' from the waveforms' interval (wf_increment 0.01 s)" in n
                   for n in run.notes)
    # A channel name in several groups is no column by itself.
    with pytest.raises(HesspipeError, match=r"s02.tdms: channel 'Yaw' missing \(role output\); found channels: "
                                            r"time, Run 1/Target \[deg\]"):
        read_run(tmp_path / "s02.tdms", columns=cols.replace("*", "1").replace("Run 1/Yaw", "Yaw"))


def test_time_stamps_and_files_it_cannot_read(tmp_path):
    s = _write(tmp_path / "stamped.tdms", {"Data": 1.0}, stamps=True)
    run = read_run(tmp_path / "stamped.tdms", columns="time=Time," + ",".join(f"{r}={n}" for r, n in LAB.items()))
    np.testing.assert_allclose(run.time - run.time[0], s["time"], atol=1e-9)
    assert any("time stamps read as seconds from the first" in n for n in run.notes)
    # An empty time-stamp channel beside the signals is no clock (and no crash).
    with TdmsWriter(str(tmp_path / "empty_stamps.tdms")) as writer:
        writer.write_segment([RootObject(), GroupObject("Data"),
                              ChannelObject("Data", "Stamp", np.array([], dtype="datetime64[ns]")),
                              ChannelObject("Data", "Yaw", s["output"], properties={"wf_increment": 0.01})])
    from hesspipe.core._tdms import tdms_frame

    frame = tdms_frame(tmp_path / "empty_stamps.tdms")[0]
    assert list(frame.columns) == ["time", "Data/Yaw", "Yaw"]
    refused(tmp_path / "bad.tdms", b"TDSm not really" + b"\x00" * 40, r"bad.tdms: not a readable TDMS file")
    refused(tmp_path / "missing.tdms", None, r"missing.tdms: file not found; expected a LabVIEW TDMS file")
