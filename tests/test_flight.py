"""Stage one: JSBSim trim, records, safety and bad input (hesspipe.flight.approach)."""

import json
import math
import os
import shutil
from argparse import Namespace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from hesspipe.cli import main
from hesspipe.core.config import data_dir
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import write_plants
from hesspipe.flight import approach as flight
from hesspipe.flight.aircraft import AircraftConfig, Approach, known_aircraft, load_aircraft
from hesspipe.flight.approach import COLUMNS, FlightConfig, fly, fly_records
from hesspipe.flight.wind import heading_to_ned
from hesspipe.viz.flight import draw_flight
from pilot_data import plants as paper_plants

OUTPUTS = {"trim.json", "wind.csv", "aileron.csv", "manifest.json", "flight_wind.png",
           "flight_aileron.png"}
SHORT = FlightConfig.from_table({"duration_s": 5.0}, "test")


def _read(path):
    return pd.read_csv(path, comment="#")


@pytest.fixture(scope="module", params=["737", "B747"])
def flown(request, tmp_path_factory):
    out = tmp_path_factory.mktemp(f"flight_{request.param}")
    return fly(request.param, FlightConfig(), out, seed=0, draw=draw_flight), out


def _calm(aircraft, workdir):
    """A record with no wind and no excitation: the numerical noise floor."""
    calm = FlightConfig.from_table({"side_wind": {"speed_end_fps": 0.0},
                                    "wind_excitation": {"kind": "none"}}, "test")
    _, wind, _ = fly_records(aircraft, calm, 0, workdir)
    return wind


# --------------------------------------------------------------------------- done-when

def test_trim_meets_the_approach_condition(flown):
    result, out = flown
    trim = json.loads((out / "trim.json").read_text())
    assert trim["aircraft"] == result.aircraft
    assert trim["vc_kts"] == pytest.approx(135.0, abs=1.0)
    assert trim["flaps_norm"] == pytest.approx(1.0, abs=1e-6)
    assert trim["gear_norm"] == pytest.approx(1.0, abs=1e-6)
    assert trim["psi_deg"] == pytest.approx(180.0, abs=0.5)
    assert trim["gamma_deg"] == pytest.approx(-3.0, abs=0.2)
    assert trim["h_agl_ft"] == pytest.approx(697.0, abs=1.0)
    for key in ("alpha_deg", "theta_deg", "throttle", "elevator_norm"):
        assert math.isfinite(trim[key])
    assert 0 < trim["throttle"] <= 1


def test_outputs_columns_and_comments(flown):
    result, out = flown
    assert {p.name for p in out.iterdir()} == OUTPUTS | {".hesspipe-output"}  # + hesspipe's marker
    for name in ("wind.csv", "aileron.csv"):
        text = (out / name).read_text()
        comments = [ln for ln in text.splitlines() if ln.startswith("#")]
        joined = "\n".join(comments)
        for word in (f"aircraft: {result.aircraft}", "record:", "excitation:", "seed: 0", "signs:"):
            assert word in joined, (name, word)
        df = _read(out / name)
        assert tuple(df.columns) == COLUMNS
        assert len(df) == 70 * 120
        np.testing.assert_allclose(df["time"], np.arange(len(df)) / 120.0, atol=1e-9)
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["seed"] == 0 and manifest["aircraft"] == result.aircraft
    assert manifest["aircraft_file_hash"].startswith("sha256:")
    assert manifest["config"]["duration_s"] == 70.0
    assert "jsbsim" in manifest["versions"]


def test_records_stay_airborne_and_on_speed(flown):
    result, out = flown
    vc = result.trim["vc_kts"]
    for df in (result.wind, result.aileron):
        assert np.all(np.abs(df["vc_kts"] - vc) <= 10.0)
        assert df["h_agl_ft"].min() > 50.0


def test_wind_record_holds_the_wind_actually_applied(flown):
    """The recorded wind is the commanded profile + excitation, to rounding."""
    result, _ = flown
    cfg = FlightConfig()
    t = result.wind["time"].to_numpy()
    along, lateral = cfg.side_wind(t, cfg.duration_s)
    lateral = lateral + cfg.wind_excitation.signal(t, flight.record_seeds(0)[0])
    north, east = heading_to_ned(along, lateral, math.radians(result.trim["psi_deg"]))
    np.testing.assert_allclose(result.wind["wind_north_fps"], north, atol=1e-9)
    np.testing.assert_allclose(result.wind["wind_east_fps"], east, atol=1e-9)
    # lateral relative to the actual heading (the aircraft weathervanes a little)
    psi = np.radians(result.wind["heading_deg"])
    lat = -result.wind["wind_north_fps"] * np.sin(psi) + result.wind["wind_east_fps"] * np.cos(psi)
    np.testing.assert_allclose(result.wind["wind_lateral_fps"], lat, atol=1e-9)
    # the paper's side wind reaches about 17 ft/s, from the right (negative)
    assert -20 < result.wind["wind_lateral_fps"].iloc[-600:].mean() < -14
    assert np.all(result.aileron["wind_lateral_fps"] == 0)  # aileron record in calm air


def test_roll_response_stands_far_above_calm_noise(flown, tmp_path):
    result, _ = flown
    calm = _calm(result.aircraft, tmp_path)
    noise = np.sqrt(np.mean(calm["roll_rate_rps"] ** 2))
    for df in (result.wind, result.aileron):
        p_rms = np.sqrt(np.mean(df["roll_rate_rps"] ** 2))
        assert p_rms > 1e3 * noise
        assert p_rms > 1e-3  # rad/s: a clearly visible response, not just a quiet floor


def test_inputs_act_one_row_later(tmp_path):
    """A PRBS without taper steps the aileron at row 0; roll rate moves from row 1."""
    cfg = FlightConfig.from_table({"duration_s": 1.0, "aileron_excitation": {
        "kind": "prbs", "clock_s": 0.25, "rms": 0.1, "taper_s": 0.0}}, "test")
    trim, _, ail = fly_records("737", cfg, 0, tmp_path)
    assert abs(ail["aileron_cmd"][0] - trim["aileron_norm"]) == pytest.approx(0.1)
    p = ail["roll_rate_rps"].to_numpy()
    assert abs(p[0]) < 1e-8 and abs(p[1]) > 1e-4


def test_same_seed_identical_files_other_seed_differs(tmp_path):
    a, b, c = tmp_path / "a", tmp_path / "b", tmp_path / "c"
    for out, seed in ((a, 5), (b, 5), (c, 6)):
        fly("737", SHORT, out, seed=seed)
    for name in ("wind.csv", "aileron.csv", "trim.json"):
        assert (a / name).read_bytes() == (b / name).read_bytes()
    assert (a / "wind.csv").read_bytes() != (c / "wind.csv").read_bytes()
    assert (a / "aileron.csv").read_bytes() != (c / "aileron.csv").read_bytes()


@pytest.mark.parametrize("name", ["MD11", "global5000"])
def test_other_transports_trim(name, tmp_path):
    trim, wind, _ = fly_records(name, SHORT, 0, tmp_path)
    assert trim["vc_kts"] == pytest.approx(135.0, abs=1.0)
    assert trim["gamma_deg"] == pytest.approx(-3.0, abs=0.2)
    assert len(wind) == 600


# --------------------------------------------------------------------------- safety

def _socket_fds():
    out = set()
    for fd in os.listdir("/proc/self/fd"):
        try:
            link = os.readlink(f"/proc/self/fd/{fd}")
        except OSError:
            continue
        if link.startswith("socket:"):
            out.add(link)
    return out


@pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="needs Linux /proc")
def test_no_socket_is_opened(tmp_path, monkeypatch):
    """The bundled 737 opens two sockets at run_ic (measured: 2 new socket fds);
    the sanitised copy must open none while the records are flown."""
    before = _socket_fds()
    seen = []
    original = flight._fly_record

    def spy(fdm, **kw):
        seen.append(_socket_fds() - before)  # after load, run_ic and trim
        df = original(fdm, **kw)
        seen.append(_socket_fds() - before)
        return df

    monkeypatch.setattr(flight, "_fly_record", spy)
    fly("737", SHORT, tmp_path / "out", seed=0)
    assert len(seen) == 4 and all(s == set() for s in seen)


@pytest.mark.parametrize("name", ["737", "global5000"])
def test_sanitised_copy_drops_io_elements(name, tmp_path):
    """The bundled files carry socket inputs (737) / a CSV output (global5000); the copy does not,
    and keeps the <output> elements of flight-control components."""
    import xml.etree.ElementTree as ET

    import jsbsim

    def io_elements(path):
        return [el.tag for el in ET.parse(path).getroot() if el.tag in ("input", "output")]

    original = Path(jsbsim.get_default_root_dir()) / "aircraft" / name / f"{name}.xml"
    assert io_elements(original)  # the hazard exists in the wheel
    copy = flight._sanitised_aircraft(name, tmp_path) / name / f"{name}.xml"
    assert io_elements(copy) == []
    assert len(ET.parse(copy).getroot().findall(".//output")) == len(
        ET.parse(original).getroot().findall(".//output")) - io_elements(original).count("output")


@pytest.mark.parametrize("name", ["global5000", "737"])
def test_nothing_written_outside_out_dir(name, tmp_path, monkeypatch):
    import jsbsim

    cwd = tmp_path / "cwd"
    cwd.mkdir()
    monkeypatch.chdir(cwd)
    wheel = Path(jsbsim.get_default_root_dir())

    def listing(root):
        return sorted(str(p.relative_to(root)) for p in root.rglob("*"))

    wheel_before = listing(wheel / "aircraft" / name)
    assert main(["flight", "--aircraft", name, "--out", "out", "--config",
                 str(_config(tmp_path, "[flight]\nduration_s = 5.0\n"))]) == 0
    assert listing(cwd) == sorted(["out", "out/.hesspipe-output"] + [f"out/{n}" for n in OUTPUTS])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cfg.toml", "cwd"]
    assert listing(wheel / "aircraft" / name) == wheel_before


# --------------------------------------------------------------------------- bad input

def _config(tmp_path, text):
    path = tmp_path / "cfg.toml"
    path.write_text(text)
    return path


def _fails(capsys, argv, *needles):
    assert main(argv) == 1
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("hesspipe: error: "), err
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])
    return lines[0]


def test_unknown_aircraft_lists_known(tmp_path, capsys):
    out = tmp_path / "out"
    line = _fails(capsys, ["flight", "--aircraft", "C172", "--out", str(out)], "'C172'", "737", "B747")
    assert "roskam" not in line  # the analytic aircraft is not flyable
    assert not out.exists()


@pytest.mark.parametrize("name, why", [("A320", "155 KCAS"), ("787-8", "angle of attack")])
def test_unsupported_aircraft_say_why(name, why, tmp_path, capsys):
    out = tmp_path / "out"
    _fails(capsys, ["flight", "--aircraft", name, "--out", str(out)], name, "not supported", why)
    assert not out.exists()


@pytest.mark.parametrize("text, needles", [
    ("[flight]\nduration_s = 0\n", ["cfg.toml", "flight.duration_s", "> 0"]),
    ("[flight]\nduration_s = -5\n", ["flight.duration_s", "> 0"]),
    ("[flight]\nduration_s = 'long'\n", ["flight.duration_s", "'long'"]),
    ("[flight]\ndurration_s = 10\n", ["flight.durration_s", "unknown field"]),
    ("[flight.wind_excitation]\nkind = 'gusts'\n", ["flight.wind_excitation.kind", "'gusts'"]),
    ("[flight.side_wind]\nspeed_end_fps = -1\n", ["flight.side_wind.speed_end_fps", ">= 0"]),
    ("[flight]\ndt_s = 1.0\n", ["flight.dt_s"]),
    ("[flight\n", ["cfg.toml", "not valid TOML"]),
])
def test_bad_config_values(text, needles, tmp_path, capsys):
    out = tmp_path / "out"
    _fails(capsys, ["flight", "--out", str(out), "--config", str(_config(tmp_path, text))], *needles)
    assert not out.exists()


def test_a_copy_of_the_default_configuration_is_accepted(tmp_path, capsys):
    """What `run --config` takes, `flight --config` takes: its [flight] aircraft among the rest."""
    copy = tmp_path / "mine.toml"
    shutil.copy(data_dir("pipeline") / "default.toml", copy)
    out = tmp_path / "out"
    assert main(["flight", "--out", str(out), "--config", str(copy)]) == 0, capsys.readouterr().err
    assert json.loads((out / "trim.json").read_text())["aircraft"] == "737"
    # ... and its seed: the records `hesspipe run` flies with that file
    assert json.loads((out / "manifest.json").read_text())["seed"] == 1


def test_the_configurations_aircraft_is_flown_unless_the_flag_names_one(tmp_path):
    from hesspipe.cli._options import read_cli_flight

    cfg = _config(tmp_path, 'seed = 7\n[flight]\naircraft = "B747"\nduration_s = 30.0\n')
    assert read_cli_flight(Namespace(config=cfg, aircraft=None, seed=None)) == \
        ("B747", FlightConfig(duration_s=30.0), 7)
    assert read_cli_flight(Namespace(config=cfg, aircraft="MD11", seed=3))[::2] == ("MD11", 3)
    assert read_cli_flight(Namespace(config=None, aircraft=None, seed=None)) == ("737", FlightConfig(), 0)


@pytest.mark.parametrize("command", ["flight", "fly-pilot", "plants"])
@pytest.mark.parametrize("text", ["[flihgt]\nduration_s = 30.0\n", "seed = -1\n", "seed = 1.5\n"],
                         ids=["section", "seed -1", "seed 1.5"])
def test_a_configuration_is_checked_as_run_checks_it(command, text, tmp_path, capsys):
    """A misspelt section or a bad seed is refused by every command that takes --config, in
    `run`'s words, before any work."""
    cfg = _config(tmp_path, text)
    expected = _fails(capsys, ["run", "--config", str(cfg), "--out", str(tmp_path / "run")], str(cfg))
    plants = tmp_path / "plants.json"
    write_plants(plants, paper_plants())
    argv = {"flight": ["flight"], "fly-pilot": ["fly-pilot", "--plants", str(plants)],
            "plants": ["plants", "--analytic", "roskam"]}[command]
    out = tmp_path / "out"
    assert _fails(capsys, argv + ["--out", str(out), "--config", str(cfg)]) == expected
    assert not out.exists()


def test_negative_seed_and_file_as_out(tmp_path, capsys):
    # The one seed rule (hesspipe.core.seeds.check_seed) is a usage error on every command: exit 2.
    with pytest.raises(SystemExit) as info:
        main(["flight", "--out", str(tmp_path / "o"), "--seed", "-1"])
    err = capsys.readouterr().err
    assert info.value.code == 2 and err.count("\n") == 1 and "argument --seed: expected an integer 0 <= seed" in err
    (tmp_path / "f").write_text("x")
    _fails(capsys, ["flight", "--out", str(tmp_path / "f")], "not a folder")
    assert not (tmp_path / "o").exists() and (tmp_path / "f").read_text() == "x"


def test_missing_config_file(tmp_path, capsys):
    _fails(capsys, ["flight", "--out", str(tmp_path / "o"), "--config", str(tmp_path / "nope.toml")],
           "nope.toml", "not found")


def test_ground_contact_fails_without_output(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()  # an existing (empty) folder is left as it was
    cfg = _config(tmp_path, "[flight]\nrecord_terrain_ft = 1000.0\n")  # 300 ft AGL at the start
    _fails(capsys, ["flight", "--out", str(out), "--config", str(cfg)], "ground contact", "wind record")
    assert [p.name for p in out.iterdir()] == []


def test_speed_excursion_fails(tmp_path, capsys):
    cfg = _config(tmp_path, "[flight]\nmax_speed_dev_kts = 0.2\n")
    _fails(capsys, ["flight", "--out", str(tmp_path / "out"), "--config", str(cfg)], "airspeed", "+- 0.2 kt")
    assert not (tmp_path / "out").exists()


def test_trim_failure_is_one_line(tmp_path, capsys, monkeypatch):
    """The A320 file refuses early; its model, forced through, fails JSBSim's trim."""
    a320 = AircraftConfig(name="A320", model="A320", approach=Approach(), record_terrain_ft=0.0,
                          path=Path("A320.toml"))
    monkeypatch.setattr(flight, "load_aircraft", lambda name: a320)
    _fails(capsys, ["flight", "--aircraft", "A320", "--out", str(tmp_path / "out")], "trim failed", "135 KCAS")
    assert not (tmp_path / "out").exists()


def test_known_aircraft_and_loading():
    assert {"737", "B747", "MD11", "global5000", "A320", "787-8"} <= set(known_aircraft())
    ac = load_aircraft("737")
    assert ac.model == "737" and ac.approach == Approach() and ac.record_terrain_ft == 0.0
    with pytest.raises(HesspipeError, match="unknown aircraft"):
        load_aircraft("nope")


def test_figures_are_optional(tmp_path):
    fly("737", SHORT, tmp_path / "with", seed=0, draw=draw_flight)
    fly("737", SHORT, tmp_path / "without", seed=0)
    assert (tmp_path / "with" / "flight_wind.png").is_file()
    assert not list((tmp_path / "without").glob("*.png"))
    for name in ("wind.csv", "aileron.csv", "trim.json"):
        assert (tmp_path / "with" / name).read_bytes() == (tmp_path / "without" / name).read_bytes()
