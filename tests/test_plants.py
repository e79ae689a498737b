"""Stage two end to end: known-answer synthetic records, bad input, and the JSBSim transports."""

import json
import shutil

import control as ct
import numpy as np
import pandas as pd
import pytest

from hesspipe.cli import main
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_plants
from hesspipe.core.paper import EQ16
from hesspipe.plants import analytic
from hesspipe.plants.d2c import frequency_response
from hesspipe.plants.fit import fit_plants
from hesspipe.plants.settings import PlantsConfig
from hesspipe.viz.plants import draw_plants

DT = 1 / 120


def _multisine(t, rng, f_min=0.02, f_max=2.0):
    period = t[-1] + (t[1] - t[0])
    k = np.arange(int(np.ceil(f_min * period)), int(f_max * period) + 1)
    x = np.sin(2 * np.pi * np.outer(t, k / period) + rng.uniform(0, 2 * np.pi, k.size)).sum(axis=1)
    x *= np.clip(t / 1.0, 0, 1)  # fade in: the record starts at trim, as stage one's do
    return x / x.std()


def _write_synthetic_flight(folder, *, seed=0, n=8400):
    """Records of the paper's analytic aircraft (full model, zero-order hold at 120 Hz)."""
    folder.mkdir(parents=True, exist_ok=True)
    sysd = ct.c2d(analytic.lateral_model(analytic.load_analytic("roskam")), DT, "zoh")
    t = DT * np.arange(n)
    rng = np.random.default_rng(seed)
    for name, col, j, rms in (("wind.csv", "wind_lateral_fps", 1, 3.0),
                              ("aileron.csv", "aileron_cmd", 0, 0.02)):
        u = rms * _multisine(t, rng)
        inputs = np.zeros((2, n))
        inputs[j] = u
        y = ct.forced_response(sysd, T=t, U=inputs).outputs[0]
        df = pd.DataFrame({"time": t, col: u, "roll_rate_rps": y})
        (folder / name).write_text("# synthetic data: roskam analytic model, not a flight\n"
                                   + df.to_csv(index=False, float_format="%.10g"))
    return folder


@pytest.fixture(scope="module")
def synthetic_flight(tmp_path_factory):
    return _write_synthetic_flight(tmp_path_factory.mktemp("flight"))


@pytest.fixture(scope="module")
def synthetic_result(synthetic_flight, tmp_path_factory):
    out = tmp_path_factory.mktemp("plants")
    return fit_plants(synthetic_flight, out, PlantsConfig(), draw=draw_plants), out


# -- configuration ----------------------------------------------------------------------

def test_config_defaults_and_errors():
    cfg = PlantsConfig.from_table({}, "p.toml")
    assert cfg == PlantsConfig() and cfg.decimate == 6 and cfg.criterion == "bic"
    assert PlantsConfig.from_table({"criterion": "aic", "decimate": 4}, "p.toml").decimate == 4
    with pytest.raises(HesspipeError, match="p.toml: field 'plants.decimal': unknown field"):
        PlantsConfig.from_table({"decimal": 4}, "p.toml")
    with pytest.raises(HesspipeError, match="field 'plants.criterion': expected one of 'aic'"):
        PlantsConfig.from_table({"criterion": "mdl"}, "p.toml")
    with pytest.raises(HesspipeError, match="field 'plants.nk_max'"):
        PlantsConfig.from_table({"nk_min": 3, "nk_max": 2}, "p.toml")
    with pytest.raises(HesspipeError, match="field 'plants.check_band_hz'"):
        PlantsConfig.from_table({"check_band_hz": [2.0, 1.0]}, "p.toml")


# -- known answer ---------------------------------------------------------------------------

def test_recovers_the_analytic_aircraft_from_synthetic_records(synthetic_result):
    result, _ = synthetic_result
    truth = analytic.analytic_transfer_functions(analytic.load_analytic("roskam"))
    f = np.logspace(np.log10(0.02), np.log10(2.0), 200)
    for key, true in (("control_to_output", truth.full_control),
                      ("disturbance_to_output", truth.full_disturbance)):
        fit = result.fits[key]
        assert fit.fit_validation > 98.0, key
        assert fit.model.nk == 1  # the zero-order hold's one-sample delay
        assert fit.check.passed
        ratio = frequency_response(fit.continuous, f) / frequency_response(true, f)
        # The identified continuous plant matches the true one over the excited band.
        assert np.max(np.abs(20 * np.log10(np.abs(ratio)))) < 1.0, key
        assert np.max(np.abs(np.degrees(np.angle(ratio)))) < 5.0, key


def test_outputs_are_complete_and_labelled_synthetic(synthetic_result, synthetic_flight):
    result, out = synthetic_result
    names = {p.name for p in out.iterdir()}
    assert {"plants.json", "plants_report.md", "plants_report.json", "manifest.json",
            "plants_validation.png", "plants_bode.png", "plants_residuals.png"} <= names
    plants = read_plants(out / "plants.json")
    assert plants.meta["synthetic"] is True
    assert set(plants.meta["orders"]) == {"control_to_output", "disturbance_to_output"}
    assert plants.meta["fit"]["control_to_output"]["validation"] > 98.0
    # plants.json holds exactly the continuous models that were validated
    np.testing.assert_allclose(np.squeeze(plants.Yd.den[0][0]),
                               np.squeeze(result.plants.Yd.den[0][0]))
    md = (out / "plants_report.md").read_text()
    assert "SYNTHETIC DATA" in md and "Eq. 16" in md and "validation" in md
    report = json.loads((out / "plants_report.json").read_text())
    rt = report["channels"]["disturbance_to_output"]["residual_tests"]
    assert {"pass", "bound", "p_value"} <= set(rt["whiteness"])
    assert report["paper_eq16"]["den"] == list(EQ16[1])
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["inputs"]["wind.csv"].startswith("sha256:")
    assert "numpy" in manifest["versions"]


# A small grid keeps the tests that do not check identification quality fast.
SMALL = PlantsConfig(na_max=4, nb_max=4, nk_max=1)


def test_same_input_same_output(synthetic_flight, tmp_path):
    a = fit_plants(synthetic_flight, tmp_path / "a", SMALL)
    b = fit_plants(synthetic_flight, tmp_path / "b", SMALL)
    assert (tmp_path / "a" / "plants.json").read_text() == (tmp_path / "b" / "plants.json").read_text()
    assert (tmp_path / "a" / "plants_report.json").read_text() == (tmp_path / "b" / "plants_report.json").read_text()
    assert a.fits["control_to_output"].model.orders == b.fits["control_to_output"].model.orders


# -- bad input -------------------------------------------------------------------------------

def _edit(src, dst, name, change):
    shutil.copytree(src, dst)
    path = dst / name
    lines = path.read_text().splitlines(keepends=True)
    comments = [ln for ln in lines if ln.startswith("#")]
    df = pd.read_csv(path, comment="#")
    df = change(df)
    path.write_text("".join(comments) + df.to_csv(index=False, float_format="%.10g"))
    return dst


def _nan(df):
    df.loc[500, "roll_rate_rps"] = np.nan
    return df


def _jitter(df):
    df.loc[300, "time"] += 0.3 * DT
    return df


def _constant(df):
    df["aileron_cmd"] = 0.01
    return df


def _sine(df):
    df["aileron_cmd"] = 0.02 * np.sin(2 * np.pi * 0.5 * df["time"])
    return df


@pytest.mark.parametrize("name, change, expected", [
    ("aileron.csv", lambda df: df.drop(columns=["aileron_cmd"]), "aileron.csv: column 'aileron_cmd' missing"),
    ("wind.csv", _nan, "wind.csv: column 'roll_rate_rps': expected finite numbers"),
    ("wind.csv", _jitter, "wind.csv: column 'time': expected uniform sampling"),
    ("aileron.csv", lambda df: df.iloc[:400], "aileron.csv: record too short"),
    ("aileron.csv", _constant, "aileron.csv: column 'aileron_cmd': input not persistently exciting"),
    ("aileron.csv", _sine, "aileron.csv: column 'aileron_cmd': input not persistently exciting"),
])
def test_bad_input_is_one_line_and_writes_nothing(synthetic_flight, tmp_path, capsys, name, change, expected):
    flight = _edit(synthetic_flight, tmp_path / "flight", name, change)
    out = tmp_path / "out"
    assert main(["plants", "--flight", str(flight), "--out", str(out), "--no-figures"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("hesspipe: error: ") and err.count("\n") == 1
    assert expected in err
    assert not out.exists()


def test_missing_flight_folder_and_file(tmp_path, capsys):
    assert main(["plants", "--flight", str(tmp_path / "nope"), "--out", str(tmp_path / "o")]) == 1
    assert "flight folder not found" in capsys.readouterr().err
    (tmp_path / "wind.csv").write_text("time\n0\n")   # the record given for its folder
    assert main(["plants", "--flight", str(tmp_path / "wind.csv"), "--out", str(tmp_path / "o")]) == 1
    assert "wind.csv: a file, not a folder; expected the flight stage's output folder" in capsys.readouterr().err
    (tmp_path / "empty").mkdir()
    assert main(["plants", "--flight", str(tmp_path / "empty"), "--out", str(tmp_path / "o")]) == 1
    assert "wind.csv: file not found" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_existing_outputs_survive_a_failed_run(synthetic_flight, tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "plants.json").write_text("{}")
    flight = _edit(synthetic_flight, tmp_path / "flight", "wind.csv", _nan)
    assert main(["plants", "--flight", str(flight), "--out", str(out)]) == 1
    assert [p.name for p in out.iterdir()] == ["plants.json"]
    assert (out / "plants.json").read_text() == "{}"


def test_bad_config_file(synthetic_flight, tmp_path, capsys):
    cfg = tmp_path / "c.toml"
    cfg.write_text("[plants]\ndecimate = 0\n")
    assert main(["plants", "--flight", str(synthetic_flight), "--out", str(tmp_path / "o"),
                 "--config", str(cfg)]) == 1
    err = capsys.readouterr().err
    assert "c.toml: field 'plants.decimate': expected an integer >= 1" in err


# -- the JSBSim transports with the default excitation -----------------------------------------

@pytest.mark.parametrize("aircraft", ["737", "B747"])
def test_jsbsim_plants_meet_the_bar(aircraft, tmp_path):
    from hesspipe.flight.approach import FlightConfig, fly

    fly(aircraft, FlightConfig(), tmp_path / "flight", seed=1)
    result = fit_plants(tmp_path / "flight", tmp_path / "plants")
    for key, fit in result.fits.items():
        assert fit.fit_validation >= 90.0, (aircraft, key, fit.fit_validation)
        assert fit.check.band_hz == (0.01, 2.0)
        assert fit.check.max_gain_error_db <= 1.0 and fit.check.max_phase_error_deg <= 5.0, (aircraft, key)
        assert fit.model.is_stable()


def test_failed_frequency_check_is_an_error_unless_warned(synthetic_flight, tmp_path):
    from dataclasses import replace

    strict = replace(SMALL, check_gain_db=1e-4, check_phase_deg=1e-4)
    with pytest.raises(HesspipeError, match="continuous lateral wind -> roll rate model differs"):
        fit_plants(synthetic_flight, tmp_path / "a", strict)
    assert not (tmp_path / "a").exists()
    res = fit_plants(synthetic_flight, tmp_path / "b", replace(strict, on_check_failure="warn"))
    assert not res.report["channels"]["control_to_output"]["conversion"]["check"]["pass"]
    assert "FAIL" in (tmp_path / "b" / "plants_report.md").read_text()


def test_paper_wind_profile_alone_is_not_persistently_exciting(tmp_path, capsys):
    # SPEC.md: the slow turning wind alone barely excites roll; stage two must refuse it.
    from dataclasses import replace

    from hesspipe.flight.approach import FlightConfig, fly
    from hesspipe.flight.wind import Excitation

    fly("737", replace(FlightConfig(), wind_excitation=Excitation(kind="none")), tmp_path / "f", seed=1)
    assert main(["plants", "--flight", str(tmp_path / "f"), "--out", str(tmp_path / "p")]) == 1
    err = capsys.readouterr().err
    assert "wind.csv: column 'wind_lateral_fps': input not persistently exciting" in err
    assert not (tmp_path / "p").exists()
