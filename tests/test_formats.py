"""The pinned file formats: measured-run CSV reader/writer and plants JSON."""

from __future__ import annotations

import json

import control as ct
import numpy as np
import pytest

from hesspipe.errors import HesspipeError
from hesspipe.formats import Plants, Run, read_plants, read_run, write_plants, write_run


def _run(n=200, dt=0.02, synthetic=False, run_id="p1"):
    t = dt * np.arange(n)
    rng = np.random.default_rng(1)
    return Run(time=t, disturbance=np.sin(t), output=0.1 * rng.standard_normal(n),
               control=rng.standard_normal(n), reference=np.zeros(n), id=run_id,
               synthetic=synthetic)


def _csv(path, header, rows, comments=()):
    text = "".join(f"# {c}\n" for c in comments) + ",".join(header) + "\n"
    text += "".join(",".join(str(v) for v in row) + "\n" for row in rows)
    path.write_text(text)
    return path


def _rows(n=50, dt=0.02):
    return [(i * dt, 0.5 * i, 0.01 * i, -0.2 * i) for i in range(n)]


def test_roundtrip_keeps_values_id_and_synthetic_flag(tmp_path):
    run = _run(synthetic=True, run_id="pilot07")
    path = write_run(tmp_path / "pilot07.csv", run)
    back = read_run(path)
    assert back.id == "pilot07"
    assert back.synthetic
    assert back.source == str(path)
    for name in ("time", "disturbance", "output", "control", "reference"):
        np.testing.assert_allclose(getattr(back, name), getattr(run, name), rtol=1e-8, atol=1e-12)
    assert back.dt == pytest.approx(0.02)
    assert back.fs == pytest.approx(50.0)
    np.testing.assert_allclose(back.error, -back.output)


def test_measured_run_is_not_synthetic_and_reference_defaults_to_zero(tmp_path):
    path = _csv(tmp_path / "a.csv", ("time", "disturbance", "output", "control"), _rows(),
                comments=("VMS session 3",))
    run = read_run(path)
    assert not run.synthetic
    assert run.comments == ("VMS session 3",)
    assert np.all(run.reference == 0.0)
    assert len(run) == 50


def test_column_mapping(tmp_path):
    path = _csv(tmp_path / "b.csv", ("t", "wind", "p", "stick"), _rows())
    run = read_run(path, columns="time=t, disturbance=wind,output=p,control=stick")
    np.testing.assert_allclose(run.control, [-0.2 * i for i in range(50)])
    same = read_run(path, columns={"time": "t", "disturbance": "wind", "output": "p", "control": "stick"})
    np.testing.assert_array_equal(same.output, run.output)


@pytest.mark.parametrize("spec, words", [
    ("control", ["columns: expected ROLE=NAME", "'control'"]),
    ("stick=control", ["unknown role", "'stick'"]),
])
def test_bad_column_mapping(tmp_path, spec, words):
    path = _csv(tmp_path / "c.csv", ("time", "disturbance", "output", "control"), _rows())
    with pytest.raises(HesspipeError) as info:
        read_run(path, columns=spec)
    for word in words:
        assert word in str(info.value)


def test_missing_column_names_file_column_and_hint(tmp_path):
    path = _csv(tmp_path / "d.csv", ("time", "disturbance", "output", "stick"), _rows())
    with pytest.raises(HesspipeError) as info:
        read_run(path)
    msg = str(info.value)
    assert str(path) in msg and "'control'" in msg and "columns control=NAME" in msg
    assert "--" not in msg  # the library names its settings, never a command-line flag
    assert "\n" not in msg


def test_non_finite_value_names_column_and_row(tmp_path):
    rows = _rows()
    rows[7] = (rows[7][0], rows[7][1], "abc", rows[7][3])
    path = _csv(tmp_path / "e.csv", ("time", "disturbance", "output", "control"), rows)
    with pytest.raises(HesspipeError, match=r"column 'output': expected finite numbers, got 'abc' "
                                            r"in data row 8"):
        read_run(path)
    rows[7] = (rows[7][0], rows[7][1], "nan", rows[7][3])
    _csv(path, ("time", "disturbance", "output", "control"), rows)
    with pytest.raises(HesspipeError, match="column 'output': expected finite numbers"):
        read_run(path)


def test_non_uniform_time_fails_unless_resampled(tmp_path):
    rows = _rows(n=101)
    del rows[40]  # one dropped sample: a 0.04 s gap
    path = _csv(tmp_path / "f.csv", ("time", "disturbance", "output", "control"), rows)
    with pytest.raises(HesspipeError, match=r"column 'time': expected uniform sampling.*set resample"):
        read_run(path)
    run = read_run(path, resample=True)
    assert len(run) == 101
    np.testing.assert_allclose(np.diff(run.time), 0.02, rtol=1e-9)
    # Linear signals are reproduced exactly by linear interpolation, the gap included.
    np.testing.assert_allclose(run.disturbance, 0.5 * np.arange(101), rtol=1e-9, atol=1e-9)


def test_time_must_increase(tmp_path):
    rows = _rows()
    rows[10] = (rows[9][0],) + rows[10][1:]
    path = _csv(tmp_path / "g.csv", ("time", "disturbance", "output", "control"), rows)
    with pytest.raises(HesspipeError, match="strictly increasing time"):
        read_run(path)


def test_too_few_samples_for_spectra(tmp_path):
    path = _csv(tmp_path / "h.csv", ("time", "disturbance", "output", "control"), _rows(n=50))
    with pytest.raises(HesspipeError, match=r"50 samples; expected at least 1024"):
        read_run(path, min_samples=1024)
    header_only = _csv(tmp_path / "i.csv", ("time", "disturbance", "output", "control"), [])
    with pytest.raises(HesspipeError, match="0 samples"):
        read_run(header_only)


@pytest.mark.parametrize("content, words", [
    (None, "file not found"),
    (b"\xff\xfe\x00\x81binary", "not a UTF-8 text file"),
    (b"", "not a readable CSV"),
])
def test_unreadable_files(tmp_path, content, words):
    path = tmp_path / "x.csv"
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(HesspipeError, match=words):
        read_run(path)


def test_folder_is_not_a_run(tmp_path):
    with pytest.raises(HesspipeError, match="is a folder"):
        read_run(tmp_path)


def _plants():
    return Plants(ct.tf([2.436], [1, 1.0496]),
                  ct.tf([-0.2554, 14.4, -272.6, 25.72], [1, 84.37, 452.2, 1510, 628.8]),
                  {"source": "SPEC.md Eq. 14/16"})


def test_plants_roundtrip(tmp_path):
    path = write_plants(tmp_path / "plants.json", _plants(), units="rad/s")
    back = read_plants(path)
    assert back.meta == {"source": "SPEC.md Eq. 14/16", "units": "rad/s"}
    w = np.array([0.1, 1.0, 10.0])
    for a, b in ((back.Yc, _plants().Yc), (back.Yd, _plants().Yd)):
        np.testing.assert_allclose(a(1j * w), b(1j * w), rtol=1e-12)


@pytest.mark.parametrize("obj, words", [
    ([1, 2], "expected a JSON object"),
    ({"control_to_output": {"num": [1], "den": [1, 1]}}, "field 'disturbance_to_output' missing"),
    ({"control_to_output": {"num": [1], "den": [1, 1]},
      "disturbance_to_output": {"num": [1, 2, 3], "den": [1, 1]}}, "not proper"),
    ({"control_to_output": {"num": ["a"], "den": [1, 1]},
      "disturbance_to_output": {"num": [1], "den": [1, 1]}}, "field 'control_to_output.num'"),
])
def test_bad_plants(tmp_path, obj, words):
    path = tmp_path / "plants.json"
    path.write_text(json.dumps(obj))
    with pytest.raises(HesspipeError, match=words):
        read_plants(path)
