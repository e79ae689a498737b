"""Measured runs as laboratories write them: encodings, separators, headers with units
(:mod:`hesspipe.core._csv`). Each file holds the same run; reading must give the same arrays."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hesspipe.core._csv import UNIT_FACTORS
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_plants, read_run

N, DT = 300, 0.02


def _signals():
    t = DT * np.arange(N)
    return t, np.sin(0.7 * t), 0.1 * np.cos(1.3 * t), np.sin(2.1 * t), 0.05 * np.sin(0.4 * t)


def _text(header, sep=",", decimal=".", scale=(1, 1, 1, 1, 1), quote=False):
    cols = _signals()
    q = '"' if quote else ""
    lines = [sep.join(f"{q}{h}{q}" for h in header)]
    for row in zip(*cols):
        lines.append(sep.join(f"{q}{v * k:.9g}{q}".replace(".", decimal) for v, k in zip(row, scale)))
    return "\n".join(lines) + "\n"


def _clock_text(stamp):
    lines = _text(PLAIN).split("\n")
    return "\n".join([lines[0]] + [stamp(k) + ln[ln.index(","):] for k, ln in enumerate(lines[1:-1])]
                     + [""]).encode()


def _units_row(sep, decimal, brackets=False):
    units = ("ms", "m/s", "deg/s", "-", "deg/s")
    lines = _text(PLAIN, sep, decimal, scale=(1000, 0.3048, 180 / math.pi, 1, 180 / math.pi)).split("\n")
    lines.insert(1, sep.join(f"[{u}]" if brackets else u for u in units))
    return "\n".join(lines).encode()


PLAIN = ("time", "disturbance", "output", "control", "reference")


def _labview():
    """A LabVIEW measurement file: two header blocks (key, tab, values; lines that split like
    the data), a line of one tab, then the channels' names with a last 'Comment' over no
    values, tab-separated, CRLF."""
    head = ["LabVIEW Measurement\t", "Writer_Version\t2", "Separator\tTab", "Time\t14:03:05.1234",
            "***End_of_Header***", "\t", "Channels\t4\t\t\t\t", "Samples\t300\t300\t300\t300\t",
            "Y_Unit_Label\tdeg\tdeg\tdeg\tdeg\t", "Delta_X\t0.020000\t0.020000\t0.020000\t0.020000\t",
            "***End_of_Header***\t\t\t\t\t"]
    table = _text(PLAIN, "\t").split("\n")
    table[0] += "\tComment"
    return "\r\n".join(head + table).encode()


@pytest.mark.parametrize("name, data, note", [
    ("plain.csv", _text(PLAIN).encode(), None),
    ("capitals.csv", _text([h.capitalize() for h in PLAIN]).encode(), None),
    ("tab.tsv", _text(PLAIN, "\t").encode(), "tab-separated"),
    ("semicolon.csv", _text(PLAIN, ";").encode(), "semicolon-separated"),
    ("european.csv", _text(PLAIN, ";", ",").encode(), "decimal commas"),
    ("spaces.txt", _text(PLAIN, "   ").encode(), "whitespace-separated"),
    ("excel-unicode.csv", _text(PLAIN, "\t").replace("\n", "\r\n").encode("utf-16"), "utf-16"),
    ("windows.csv", ("# Versuch 3, 21 °C, Pilot Müller\n" + _text(PLAIN)).encode("cp1252"), "cp1252"),
    ("old-mac.csv", _text(PLAIN).replace("\n", "\r").encode(), None),
    ("si-units.csv", _text(["time [s]", "disturbance (ft/s)", "output [rad/s]", "control [-]",
                            "reference [rad/s]"]).encode(), None),
    ("lab-units.csv", _text(["Time [ms]", "Disturbance [m/s]", "Output [deg/s]", "Control [N]",
                             "Reference [deg/s]"],
                            scale=(1000, 0.3048, 180 / math.pi, 1, 180 / math.pi)).encode(), "converted"),
    # Units in a row of their own under the names (LabVIEW, DEWESoft, MATLAB exports).
    ("units-row.csv", _units_row(";", ","), "as the columns' units"),
    ("units-row-brackets.tsv", _units_row("\t", ".", brackets=True), "as the columns' units"),
    # Aligned by spaces, as fixed-width exports write it ('Yaw [deg]' once split into two names).
    ("units-row-aligned.txt", b"\n".join(b"   " + ln for ln in _units_row("   ", ".").split(b"\n")),
     "as the columns' units"),
    # A logger's metadata above the header, not marked as comments.
    ("preamble.csv", ("Subject: s02\r\nDate: 2026-11-01; 14:03\r\nCondition = motion\r\n"
                      + _text(PLAIN, ";", ",").replace("\n", "\r\n")).encode("cp1252"),
     "3 line(s) above the header"),
    # Every cell quoted, decimal commas inside the quotes.
    ("quoted.csv", _text(PLAIN, ";", ",", quote=True).encode(), "decimal commas"),
    # Excel's separator line.
    ("excel-sep.csv", ("sep=;\n" + _text(PLAIN, ";", ",")).encode(), "1 line(s) above the header"),
    # Clock times: the time of day across midnight, and ISO 8601 stamps with a zone.
    ("clock.csv", _clock_text(lambda k: "{:02d}:{:02d}:{:06.3f}".format(
        *(lambda s: (int(s // 3600) % 24, int(s % 3600 // 60), s % 60))(86395.0 + k * DT))), "clock times"),
    ("iso.csv", _clock_text(lambda k: f"2026-11-28T09:00:{k * DT:06.3f}+01:00"), "clock times"),
    ("trial.lvm", _labview(), "no data row has a value under it"),
])
def test_same_run_whatever_the_writer(tmp_path, name, data, note):
    path = tmp_path / name
    path.write_bytes(data)
    run = read_run(path)
    t, d, y, u, r = _signals()
    assert run.dt == pytest.approx(DT, rel=1e-9)
    for got, want in ((run.time, t), (run.disturbance, d), (run.output, y), (run.control, u),
                      (run.reference, r)):
        np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-9)
    if note is None:
        assert not any("converted" in n or "separated" in n for n in run.notes)
    else:
        assert any(note in n for n in run.notes), run.notes


def test_unknown_unit_is_taken_as_written_and_said(tmp_path):
    path = tmp_path / "u.csv"
    path.write_text(_text(["time", "disturbance [N m]", "output", "control [N]", "reference"]))
    run = read_run(path)
    np.testing.assert_allclose(run.disturbance, _signals()[1], rtol=1e-6, atol=1e-9)
    assert any("'disturbance [N m]'" in n and "taken as written" in n for n in run.notes)
    assert any("'control [N]'" in n for n in run.notes)


def test_angles_are_radians_on_every_signal(tmp_path):
    path = tmp_path / "a.csv"
    path.write_text(_text(["time", "disturbance [deg/s]", "output [deg]", "control [deg]", "reference [deg]"],
                          scale=(1, 180 / math.pi, 180 / math.pi, 180 / math.pi, 180 / math.pi)))
    run = read_run(path)
    for got, want in zip((run.disturbance, run.output, run.control, run.reference), _signals()[1:]):
        np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-9)


def test_units_known_for_every_role_convert_to_spec():
    assert UNIT_FACTORS["time"]["ms"] == 1e-3
    assert UNIT_FACTORS["output"]["deg/s"] == pytest.approx(math.pi / 180)
    assert UNIT_FACTORS["disturbance"]["m/s"] == pytest.approx(1 / 0.3048)
    assert UNIT_FACTORS["disturbance"]["kt"] == pytest.approx(1.6878099, rel=1e-6)
    # The note names the unit converted to: one of the role's own units of factor 1.
    from hesspipe.core._csv import target_unit
    for role, units in UNIT_FACTORS.items():
        for unit in units:
            assert units[target_unit(role, unit)] == 1.0, (role, unit)
    assert target_unit("output", "°/s") == "rad/s" and target_unit("time", "ms") == "s"


def test_mapped_column_keeps_its_unit(tmp_path):
    path = tmp_path / "m.csv"
    path.write_text(_text(["t [ms]", "wind", "p [deg/s]", "stick", "r"], scale=(1000, 1, 180 / math.pi, 1, 1)))
    run = read_run(path, columns="time=t [ms],disturbance=wind,output=p [deg/s],control=stick")
    np.testing.assert_allclose(run.output, _signals()[2], rtol=1e-6, atol=1e-9)
    assert run.dt == pytest.approx(DT)
    assert not run.reference.any()  # 'r' is not 'reference'


def test_a_name_asked_with_its_unit_matches_whatever_the_spacing(tmp_path):
    # A units row under the names gives 'p [deg/s]'; a user who read 'p' over '[deg/s]' asks
    # for 'p[deg/s]' or 'p (deg/s)'. A different unit is another column.
    path = tmp_path / "units.csv"
    lines = _text(["t", "wind", "p", "stick", "r"], scale=(1000, 1, 180 / math.pi, 1, 1)).split("\n")
    path.write_text("\n".join([lines[0], "[ms],[ft/s],[deg/s],[-],[-]"] + lines[1:]))
    for output in ("p[deg/s]", "P (deg/s)", "p [ deg/s ]"):
        run = read_run(path, columns=f"time=t[ms],disturbance=wind,output={output},control=stick")
        np.testing.assert_allclose(run.output, _signals()[2], rtol=1e-6, atol=1e-9)
        assert run.dt == pytest.approx(DT)
    with pytest.raises(HesspipeError, match=r"column 'p\[rad/s\]' missing \(role output\); found columns: t \[ms\]"):
        read_run(path, columns="time=t[ms],disturbance=wind,output=p[rad/s],control=stick")


@pytest.mark.parametrize("name, scale", [("time_ms", 1000), ("t_msec", 1000), ("Time ms", 1000), ("time_s", 1),
                                         ("t_sec", 1)])
def test_a_time_named_with_its_unit_is_read_in_it(tmp_path, name, scale):
    # Loggers name the unit after an underscore ('time_ms'); read as seconds, milliseconds at
    # 50 Hz were refused as a 20 s interval.
    path = tmp_path / "suffix.tsv"
    path.write_text(_text([name, "wind", "p_deg", "stick", "r"], "\t", scale=(scale, 1, 1, 1, 1)))
    run = read_run(path, columns=f"time={name},disturbance=wind,output=p_deg,control=stick")
    assert run.dt == pytest.approx(DT)
    np.testing.assert_allclose(run.output, _signals()[2], rtol=1e-6, atol=1e-9)   # an angle's suffix is a name


def test_a_time_suffix_is_only_a_unit_at_the_end_of_a_name(tmp_path):
    # 'times' and 'ms_count' name no unit: milliseconds under them are refused with the remedy.
    for name in ("times", "ms_count"):
        path = tmp_path / f"{name}.csv"
        path.write_text(_text([name, "disturbance", "output", "control", "reference"], scale=(1000, 1, 1, 1, 1)))
        with pytest.raises(HesspipeError, match=rf"column '{name}': sample interval 20 s .*looks like milliseconds"):
            read_run(path, columns=f"time={name}")


def test_two_headers_for_one_role_are_refused(tmp_path):
    path = tmp_path / "two.csv"
    path.write_text(_text(["time", "Output [rad/s]", "output (deg/s)", "control", "disturbance"]))
    with pytest.raises(HesspipeError, match=r"two.csv: columns 'Output \[rad/s\]', 'output \(deg/s\)' "
                                            r"all read as 'output' \(role output\); expected one"):
        read_run(path)


def test_a_name_written_twice_is_refused_and_its_columns_mapped_by_position(tmp_path):
    # Two 'Yaw [deg]' (the second a copy off by a factor): pandas read the second as 'Yaw [deg].1'
    # and 'Yaw' took the first without a word. Two 'Note' columns that no role reads stay fine.
    t, d, y, u, _ = _signals()
    path = tmp_path / "twice.csv"
    deg = 180 / math.pi
    path.write_text("\n".join(["Time [s];Disturbance;Yaw [deg];Yaw [deg];Stick;Note;Note"] + [
        f"{a:.9g};{b:.9g};{2 * c * deg:.9g};{c * deg:.9g};{e:.9g};;x" for a, b, c, e in zip(t, d, y, u)]) + "\n")
    with pytest.raises(HesspipeError, match=r"twice.csv: 'Yaw' \(role output\) matches columns 3 and 4, both headed "
                                            r"'Yaw \[deg\]'; expected one: map the one meant by its position with "
                                            r"columns output=3 or output=4$"):
        read_run(path, columns="disturbance=Disturbance,output=Yaw,control=Stick")
    run = read_run(path, columns="disturbance=Disturbance,output=4,control=Stick")
    np.testing.assert_allclose(run.output, y, rtol=1e-6, atol=1e-9)   # the unit written over it converted
    np.testing.assert_allclose(run.disturbance, d, rtol=1e-6, atol=1e-9)
    with pytest.raises(HesspipeError, match="column '5' missing"):   # a name written once keeps its name
        read_run(path, columns="disturbance=Disturbance,output=4,control=5")


@pytest.mark.parametrize("lines", [
    # A header naming more columns than the rows hold values: the last, mapped, has none.
    ["time disturbance control reference output"] + [f"{0.02 * k:.2f} 0.1 0.2 0.3" for k in range(300)],
    # The same with separators: the header's last name is left out for having no values (a
    # LabVIEW 'Comment'); the role it names was then "missing; found columns: time, ...".
    ["time,disturbance,output,control"] + [f"{0.02 * k:.2f},0.1,0.2" for k in range(300)],
    ["time;disturbance;output;control"] + [f"{0.02 * k:.2f};0,1;0,2" for k in range(300)],
    # No row holding both a time and a control.
    ["time,disturbance,output,control"] + [f"{0.02 * k:.2f},0.1,0.2," if k % 2 == 0 else ",0.1,0.2,0.3"
                                           for k in range(300)],
])
def test_a_column_without_a_value_is_refused_not_interpolated(tmp_path, lines):
    # Interpolating over the missed samples (resample) once crashed on such a column: nothing to
    # interpolate from ("array of sample points is empty").
    path = tmp_path / "bad.txt"
    path.write_text("\n".join(lines) + "\n")
    for resample in (False, True):
        with pytest.raises(HesspipeError, match=r"bad.txt: column '(output|control)': no number in any data row"
                                                r"( that has a time)?; expected a value in each row"):
            read_run(path, resample=resample)


def test_a_name_over_no_values_is_listed_with_the_columns_found(tmp_path):
    # Another column missing as well: both told in one message, the empty one among those found.
    path = tmp_path / "short.csv"
    path.write_text("time,error,control\n" + "".join(f"{0.02 * k:.2f},0.1\n" for k in range(300)))
    with pytest.raises(HesspipeError, match=r"short.csv: column 'output' missing; found columns: time, error, "
                                            r"control \(no number in any data row\)"):
        read_run(path)


def test_empty_optional_column_is_absent_but_a_gap_is_an_error(tmp_path):
    t, d, y, u, _ = _signals()
    rows = [f"{a:.9g},{b:.9g},{c:.9g},{e:.9g}," for a, b, c, e in zip(t, d, y, u)]
    empty = tmp_path / "empty.csv"
    empty.write_text("time,disturbance,output,control,reference\n" + "\n".join(rows) + "\n")
    assert not read_run(empty).reference.any()
    rows[5] = rows[5] + "0.1"
    rows[6] = rows[6] + "0.2"
    gap = tmp_path / "gap.csv"
    gap.write_text("time,disturbance,output,control,reference\n" + "\n".join(rows) + "\n")
    with pytest.raises(HesspipeError, match="gap.csv: column 'reference': expected finite numbers"):
        read_run(gap)


def test_plants_json_with_a_byte_order_mark(tmp_path):
    path = tmp_path / "plants.json"
    path.write_bytes(b"\xef\xbb\xbf" + b'{"control_to_output": {"num": [1], "den": [1, 0]}, '
                     b'"disturbance_to_output": {"num": [1], "den": [1, 1]}}')
    assert read_plants(path).control_to_output.den[0][0].tolist() == [1, 0]


def test_a_separator_ending_every_data_line_shifts_nothing(tmp_path):
    # pandas alone reads such a file with the first column as its index: 'time' would
    # then hold the disturbance.
    path = tmp_path / "logger.csv"
    path.write_text(_text(PLAIN).replace("\n", ",\n").replace("reference,\n", "reference\n", 1))
    run = read_run(path)
    np.testing.assert_allclose(run.disturbance, _signals()[1], rtol=1e-6, atol=1e-9)
    assert run.dt == pytest.approx(DT)


def test_more_values_than_names_is_refused(tmp_path):
    path = tmp_path / "extra.csv"
    path.write_text(_text(PLAIN).replace("\n", ",7\n").replace("reference,7\n", "reference\n", 1))
    with pytest.raises(HesspipeError, match="extra.csv: data row 1 holds 6 values where the header names 5; "
                                            "expected one value per named column"):
        read_run(path)


@pytest.mark.parametrize("sep", [",", ";", "\t"])
def test_one_row_run_together_is_named_by_its_data_row(tmp_path, sep):
    # Two frames written on one line (a logger's lost newline): pandas' own words were
    # "not a readable CSV (Error tokenizing data. C error: Expected 5 fields in line 4, saw 9)",
    # counting lines of its own, comment lines not among them.
    lines = _text(PLAIN).splitlines()
    body = [i for i, ln in enumerate(lines) if ln and not ln.startswith("#")]
    third = body[3]                                    # header, then data rows 1, 2, 3
    lines[third] = lines[third] + "," + lines.pop(third + 1)
    path = tmp_path / "joined.csv"
    path.write_text("\n".join(ln.replace(",", sep) for ln in lines) + "\n")
    with pytest.raises(HesspipeError, match="joined.csv: data row 3 holds 10 values where the header names 5;"):
        read_run(path)


def test_the_digits_written_do_not_change_a_diagnosis(tmp_path):
    """SYNTHETIC (independent generator): one motion trial written with six significant
    digits (the generator's logger) and with four decimals (a fixed-point export). The plant
    check's independence test swings with the digits (the residual of exact plants is the
    simulator's integration between samples); the names must not, and the report must not
    leave a failed test unexplained beside a matching plant finding."""
    import json

    from hesspipe.core.seeds import derive_seed
    from hesspipe.diagnose.report import format_report
    from hesspipe.diagnose.workflow import diagnose
    from hesspipe.humanlike import draw_trial, simulate_trial
    from hesspipe.humanlike.writer import csv_bytes, plants_dict

    spec = draw_trial("paper", derive_seed(0, "quant", "paper", "rate", "both", "motion_feedback"),
                      task="both", pilot="hess", effects=("motion_feedback",), output="rate", name="t")
    trial = simulate_trial(spec)
    (tmp_path / "plants.json").write_text(json.dumps(plants_dict(spec)))
    plants = read_plants(tmp_path / "plants.json")
    results = []
    for fmt in ("%.6g", "%.4f"):
        path = tmp_path / f"t{len(results)}.csv"
        path.write_bytes(csv_bytes(trial, {"values": fmt}))
        results.append(diagnose(read_run(path), plants, seed=0))
    assert results[0].named_effects == results[1].named_effects
    assert "motion_feedback" in results[0].named_effects
    unexplained = [d for d in results if not d.plant_check.passes]
    assert unexplained, "expected the digits to fail one run's independence test (p ~ 0 with %.6g)"
    for d in unexplained:
        assert d.plant_finding["verdict"] == "match"
        assert "is not an aircraft-side effect any candidate explains" in format_report(d)


def test_a_folder_mapping_leaves_plain_files_readable(tmp_path):
    from hesspipe.pilots.compare import list_runs

    (tmp_path / "a.tsv").write_text(_text(["Zeit [ms]", "disturbance", "output", "control", "reference"], "\t",
                                          scale=(1000, 1, 1, 1, 1)))
    (tmp_path / "b.csv").write_text(_text(PLAIN))
    (tmp_path / "notes.txt").write_text("not a run")
    files = list_runs(tmp_path)
    assert [f.name for f in files] == ["a.tsv", "b.csv"]
    runs = [read_run(f, columns="time=Zeit [ms]") for f in files]
    for run in runs:
        np.testing.assert_allclose(run.time, _signals()[0], atol=1e-9)


def test_a_mapping_names_alternatives_for_a_header_changed_within_a_study(tmp_path):
    # A reviewer's logger wrote 'Time [ms]' for three persons and 't [s]' for the others; one
    # mapping could not read the folder, so the run was lost after 53 s of fits.
    (tmp_path / "a.csv").write_text(_text(["Time [ms]", "dist", "roll", "Stick", "target"], scale=(1000, 1, 1, 1, 1)))
    (tmp_path / "b.csv").write_text(_text(["t [s]", "dist", "roll", "stk", "target"], scale=(1, 1, 1, -1, 1)))
    mapping = "time=Time|t,disturbance=dist,output=roll,control=Stick|-stk,reference=target"
    a, b = (read_run(tmp_path / f, columns=mapping) for f in ("a.csv", "b.csv"))
    for run in (a, b):
        np.testing.assert_allclose(run.time, _signals()[0], atol=1e-9)
        np.testing.assert_allclose(run.control, _signals()[3], atol=1e-9)   # each alternative its own sign
    assert "column 'stk' (control): sign flipped, as mapped" in b.notes
    with pytest.raises(HesspipeError, match=r"b.csv: column 'Clock\|Zeit' missing \(role time\)"):
        read_run(tmp_path / "b.csv", columns="time=Clock|Zeit,disturbance=dist,output=roll,control=stk")
    with pytest.raises(HesspipeError, match=r"role 'time': 'Time\|': expected column names separated by '\|'"):
        read_run(tmp_path / "a.csv", columns="time=Time|,disturbance=dist,output=roll,control=Stick")
    both = read_run(tmp_path / "a.csv", columns="time=Time|t,disturbance=dist|roll,output=roll,control=Stick")
    assert "column 'dist' (disturbance) read, the first of 'dist|roll' the file has; 'roll' left unread" \
        in both.notes


def test_incomplete_rows_at_the_edges_are_dropped_and_said(tmp_path):
    lines = _text(PLAIN).splitlines()
    lines.insert(1, "0,,,,")                              # a recorder's empty first row
    lines.append(lines[-1].rsplit(",", 2)[0])             # a last line cut short
    lines.append("end of record")
    path = tmp_path / "edges.csv"
    path.write_text("\n".join(lines) + "\n")
    run = read_run(path)
    np.testing.assert_allclose(run.output, _signals()[2], rtol=1e-6, atol=1e-9)
    assert any("dropped 1 incomplete row(s) at the start and 2 at the end" in n for n in run.notes)
    lines.insert(100, lines[100].rsplit(",", 1)[0] + ",")   # a gap inside: refused, row named
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(HesspipeError, match="column 'reference': expected finite numbers, got an empty or NaN cell in data row 100"):
        read_run(path)


def test_a_sample_missing_is_found_even_where_the_times_end_in_zeros(tmp_path):
    # Written with five decimals, 0.02 s steps: 30.00000 reads back as the float 30.0, whose
    # own digits would allow a whole second; the written digits allow 1e-5 s.
    lines = _text(PLAIN).splitlines()
    rows = [",".join([f"{float(r.split(',')[0]):.5f}"] + r.split(",")[1:]) for r in lines[1:]]
    path = tmp_path / "gap.csv"
    path.write_text("\n".join([lines[0]] + rows[:150] + rows[151:]) + "\n")
    with pytest.raises(HesspipeError, match=r"gap.csv: column 'time': expected uniform sampling .* "
                                            r"from 0.02 to 0.04 s .*after data row 150\)"):
        read_run(path)
    run = read_run(path, resample=True)
    assert len(run) == N and run.dt == pytest.approx(DT)
    np.testing.assert_allclose(run.output[151:], _signals()[2][151:], rtol=1e-6, atol=1e-9)


def test_a_frame_written_twice_is_read_once_and_said(tmp_path):
    lines = _text(PLAIN, ";", ",").splitlines()
    path = tmp_path / "twice.csv"
    path.write_text("\n".join(lines[:101] + [lines[100]] + lines[101:]) + "\n")
    run = read_run(path)
    np.testing.assert_allclose(run.control, _signals()[3], rtol=1e-6, atol=1e-9)
    assert any("dropped 1 row(s) repeating the row before" in n for n in run.notes), run.notes
    # The same time with other values is not a repeat: refused, row named.
    fields = lines[100].split(";")
    path.write_text("\n".join(lines[:101] + [";".join(fields[:2] + ["9,5"] + fields[3:])] + lines[101:]) + "\n")
    with pytest.raises(HesspipeError, match="expected strictly increasing time, not at data row 101"):
        read_run(path)


def test_a_text_cell_in_a_decimal_comma_column_spoils_only_its_row(tmp_path):
    # pandas leaves such a column as text, commas and all: read as NaN everywhere, the
    # message used to blame the first row's good value.
    lines = _text(PLAIN, ";", ",").splitlines()
    lines.append("6,00;---;---;---;---")
    path = tmp_path / "dashes.csv"
    path.write_text("\n".join(lines) + "\n")
    run = read_run(path)
    np.testing.assert_allclose(run.reference, _signals()[4], rtol=1e-6, atol=1e-9)
    lines.insert(50, "0,99;1,0;---;1,0;1,0")
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(HesspipeError, match="column 'output': expected finite numbers, got '---' in data row 50"):
        read_run(path)


@pytest.mark.parametrize("unit, turn", [(" [deg]", 360.0), ("", 360.0), (" [rad]", 2 * math.pi)])
def test_a_heading_logged_within_one_turn_is_unwrapped(tmp_path, unit, turn):
    # A yaw task logging the simulator's heading: target and yaw wrap at different samples
    # near north. Unwrapped, and kept within half a turn of each other, the error is the
    # error; without a unit the turn is 360.
    t, d, y, u, r = _signals()
    k = (180 / math.pi) if turn == 360.0 else 1.0
    head_r, head_y = np.mod(k * (r + 0.01), turn), np.mod(k * (y + 0.01), turn)
    lines = [f"time,disturbance,output{unit},control,reference{unit}"]
    lines += [f"{a:.9g},{b:.9g},{c:.9g},{e:.9g},{f:.9g}" for a, b, c, e, f in zip(t, d, head_y, u, head_r)]
    path = tmp_path / "heading.csv"
    path.write_text("\n".join(lines) + "\n")
    run = read_run(path)
    scale = 1.0 if unit else k   # a column without a unit is read as written
    np.testing.assert_allclose(run.reference - run.output, scale * (r - y), atol=1e-7 * turn)
    assert np.max(np.abs(np.diff(run.output))) < 0.25 * scale * np.pi
    assert any("step(s) of one turn" in n and "output" in n for n in run.notes), run.notes


def test_an_angle_that_does_not_wrap_is_left_as_read(tmp_path):
    # Large swings, but no step of about a turn: nothing to unwrap.
    t, d, y, u, r = _signals()
    lines = ["time,disturbance,output [deg],control,reference [deg]"]
    lines += [f"{a:.9g},{b:.9g},{170 * np.sin(0.2 * a):.9g},{e:.9g},{0:.9g}" for a, b, e in zip(t, d, u)]
    path = tmp_path / "swing.csv"
    path.write_text("\n".join(lines) + "\n")
    run = read_run(path)
    np.testing.assert_allclose(run.output, np.radians(170 * np.sin(0.2 * t)), rtol=1e-7, atol=1e-9)
    assert not any("turn" in n for n in run.notes)


POSITIONS = "time=1,disturbance=2,output=3,control=4,reference=5"


@pytest.mark.parametrize("name, data, note", [
    # MATLAB's save -ascii / dlmwrite: numbers only, no names.
    ("matlab.txt", "".join(_text(PLAIN, "   ").split("\n", 1)[1]).encode(), "whitespace-separated"),
    ("bare.csv", _text(PLAIN).split("\n", 1)[1].encode(), None),
    # A decimal comma splits a semicolon file's numbers in two: the comma must not be taken
    # for the separator when no header says otherwise.
    ("european-bare.csv", _text(PLAIN, ";", ",").split("\n", 1)[1].replace("\n", "\r\n").encode(),
     "decimal commas"),
])
def test_a_file_without_a_header_row_is_read_by_position(tmp_path, name, data, note):
    path = tmp_path / name
    path.write_bytes(data)
    run = read_run(path, columns=POSITIONS)
    for got, want in zip((run.time, run.disturbance, run.output, run.control, run.reference), _signals()):
        np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-9)
    assert any("no header row: columns named by position, 1 to 5" in n for n in run.notes), run.notes
    if note:
        assert any(note in n for n in run.notes), run.notes
    # Unmapped, the message says why no name matches and how to map the positions.
    # Every role is missing at once, and all are named in the one message.
    with pytest.raises(HesspipeError, match=rf"{name}: columns 'time', 'output' and 'control' missing; the "
                                            r"file has no header row, its columns are named by position 1-5; "
                                            r"map them with columns time=POSITION,output=POSITION,"
                                            r"control=POSITION, or give the sample rate"):
        read_run(path)


def test_a_comment_naming_the_columns_above_the_data_is_the_header(tmp_path):
    # gnuplot's habit: "# time disturbance ..." right above numbers.
    path = tmp_path / "gnuplot.dat"
    body = _text(PLAIN, " ").split("\n", 1)[1]
    path.write_text("# subject s03, motion on\n# " + " ".join(PLAIN) + "\n" + body)
    run = read_run(path)
    np.testing.assert_allclose(run.output, _signals()[2], rtol=1e-6, atol=1e-9)
    assert any("comment line above the data as the header" in n for n in run.notes)
    assert run.comments[0] == "subject s03, motion on"
