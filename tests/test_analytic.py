"""The paper's analytic aircraft (Tables 3-4, Eqs. 11-14): numbers from SPEC.md."""

import json

import control as ct
import numpy as np
import pytest

from hesspipe.cli import main
from hesspipe.core.config import aircraft_file
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_plants
from hesspipe.plants import analytic


@pytest.fixture(scope="module")
def roskam():
    return analytic.load_analytic("roskam")


def test_table3_checks_within_one_percent(roskam):
    d = analytic.dimensional_derivatives(roskam)
    assert d["q"] == pytest.approx(61.55, rel=0.01)
    assert d["Lda"] == pytest.approx(2.436, rel=0.01)
    assert d["Lp"] == pytest.approx(-1.0496, rel=0.01)
    # The mass is Table 4's "564000" read as weight in lb.
    assert roskam.mass_slug == pytest.approx(564000 / 32.174)


def test_lateral_modes_within_one_percent(roskam):
    m = analytic.modes(roskam)
    assert m["roll"].real == pytest.approx(-1.27, rel=0.01)
    assert m["dutch_roll"].real == pytest.approx(-0.034, rel=0.01)
    assert m["dutch_roll"].imag == pytest.approx(0.736, rel=0.01)
    assert m["spiral"].real == pytest.approx(-0.043, rel=0.01)


def test_state_space_matches_roskam_closed_form_polynomial(roskam):
    # Eq. 12's coefficients written out independently of the state-space assembly.
    np.testing.assert_allclose(np.poly(analytic.lateral_model(roskam).A),
                               analytic.characteristic_polynomial(roskam), rtol=1e-10)


def test_rolling_approximation_is_eq14(roskam):
    p = analytic.analytic_transfer_functions(roskam)
    num = np.squeeze(p.rolling_control.num[0][0])
    den = np.squeeze(p.rolling_control.den[0][0])
    assert float(num) == pytest.approx(2.436, rel=0.01)
    np.testing.assert_allclose(den, [1.0, 1.0496], rtol=0.01)


def test_structure_and_signs_of_full_model(roskam):
    p = analytic.analytic_transfer_functions(roskam)
    # p = s phi: no steady roll rate from a steady aileron; a steady wind only drifts the aircraft.
    assert ct.dcgain(p.full_control) == 0.0
    assert np.squeeze(p.full_disturbance.num[0][0])[-2:].tolist() == [0.0, 0.0]
    # Positive aileron and a wind towards the right wing both start a positive roll rate.
    t = np.linspace(0, 1, 101)
    assert ct.step_response(p.full_control, t).outputs[-1] > 0
    assert ct.step_response(p.full_disturbance, t).outputs[-1] > 0
    # The initial roll acceleration of the wind path is -Lb/U per ft/s, same as the rolling form.
    d = analytic.dimensional_derivatives(roskam)
    lead = np.squeeze(p.full_disturbance.num[0][0])[0]
    assert lead == pytest.approx(-d["Lb"] / roskam.U_fps / (1 - roskam.Ixz ** 2 / (roskam.Ixx * roskam.Izz))
                                 + roskam.Ixz / roskam.Ixx * (-(d["Nb"] + d["NTb"]) / roskam.U_fps)
                                 / (1 - roskam.Ixz ** 2 / (roskam.Ixx * roskam.Izz)), rel=1e-9)


def test_bad_analytic_file(tmp_path):
    text = aircraft_file("roskam").read_text()
    bad = tmp_path / "plane.toml"
    bad.write_text(text.replace("[condition]\n", "[condition]\nspeed = 3\n"))
    with pytest.raises(HesspipeError, match="plane.toml: field 'condition.speed': unknown"):
        analytic.load_analytic(bad)
    bad.write_text(text.replace("[geometry]\nS_ft2 = 5500.0", "[geometry]\n"))
    with pytest.raises(HesspipeError, match="field 'geometry.S_ft2': expected a number > 0, missing"):
        analytic.load_analytic(bad)
    jsb = tmp_path / "jsb.toml"
    jsb.write_text('[jsbsim]\nmodel = "737"\n')
    with pytest.raises(HesspipeError, match="field 'kind'"):
        analytic.load_analytic(jsb)
    with pytest.raises(HesspipeError, match="not found"):
        analytic.load_analytic("no_such_aircraft")


def test_cli_analytic_writes_plants_and_report(tmp_path, capsys):
    out = tmp_path / "an"
    assert main(["plants", "--analytic", "roskam", "--out", str(out), "--no-figures"]) == 0
    plants = read_plants(out / "plants.json")
    assert float(ct.dcgain(plants.Yc)) == pytest.approx(2.436 / 1.0496, rel=0.01)
    assert plants.meta["source"]["kind"] == "analytic"
    assert set(plants.meta["models"]) == {"full_control", "full_disturbance", "rolling_control",
                                         "rolling_disturbance"}
    md = (out / "plants_report.md").read_text()
    assert "0.0107" in md and "does not follow from its Table 4" in md
    report = json.loads((out / "plants_report.json").read_text())
    assert report["paper_eq15"]["num"] == [0.0107]
    assert (out / "manifest.json").exists()


def test_cli_analytic_full_control_from_config(tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text('[analytic]\ncontrol = "full"\n')
    out = tmp_path / "an"
    assert main(["plants", "--analytic", "roskam", "--out", str(out), "--config", str(cfg),
                 "--no-figures"]) == 0
    assert len(read_plants(out / "plants.json").control_to_output.den[0][0]) == 5


def test_cli_analytic_bad_config_is_one_line(tmp_path, capsys):
    cfg = tmp_path / "c.toml"
    cfg.write_text('[analytic]\ncontrol = "partial"\n')
    out = tmp_path / "an"
    assert main(["plants", "--analytic", "roskam", "--out", str(out), "--config", str(cfg)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "field 'analytic.control'" in err
    assert not out.exists()
