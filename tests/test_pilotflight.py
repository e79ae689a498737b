"""The Hess pilot model flying JSBSim in closed loop (hesspipe.flight.closed_loop, hesspipe.pilot.discrete)."""

import json
import shutil

import control as ct
import numpy as np
import pytest

from hesspipe.cli import main
from hesspipe.core.config import data_dir
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import Plants, plants_coefficients, read_run, write_plants
from hesspipe.core.io import MARKER
from hesspipe.flight.approach import FlightConfig
from hesspipe.flight.closed_loop import AircraftEffects, fly_pilot_record, pilot_loop
from hesspipe.pilot.crossover import gain_scale
from hesspipe.pilot.discrete import DiscretePilot, continuous_paths
from hesspipe.pilot.effects import PLATFORM, WASHOUT
from hesspipe.pilot.hess import PilotModel

DT = 1.0 / 120.0
# The JSBSim 737's plants as stage two fits them (flight seed 1, ARX(4,6,1) / ARX(3,5,1)).
PLANTS = Plants(
    ct.tf([-0.0300117234, 0.153748556, 26.0451807, 623.051200, 380.560609, 608.359798, -3.87270147],
          [1.0, 81.5503984, 1725.77043, 2620.98412, 2882.71956, 2025.26932, 129.281692]),
    ct.tf([-0.000581296540, 0.00151985488, 0.555086615, 12.5042505, 2.54182698, -0.0799672648],
          [1.0, 81.3897924, 1712.75984, 2350.79354, 2603.10025, 1615.63374]),
    {"aircraft": "737"})
SHORT = FlightConfig.from_table({"duration_s": 20.0}, "test")


@pytest.fixture(scope="module")
def plants_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("plants") / "plants.json"
    write_plants(path, PLANTS)
    return path


def _fly(tmp_path, model="expanded+remnant", params=None, **kw):
    return fly_pilot_record("737", PLANTS, model, params or {}, seed=kw.pop("seed", 0),
                            workdir=tmp_path / "work", config=kw.pop("config", SHORT), **kw)


# --------------------------------------------------------------------------- the discrete pilot

def _loop(model="expanded+remnant+extra_delay", **params):
    m = PilotModel(tuple(e for e in model.split("+")[1:]) if model.startswith("original") else
                   ("motion_feedback",) + tuple(model.split("+")[1:]))
    p = m.complete({"Km": 2.0, "Kn": 0.1, "tau_x": 0.037, **params}, gain=gain_scale(PLANTS))
    return m, p, m.loop(p)


def test_delay_buffer_is_exact():
    """A step through the visual path appears exactly tau0 (+ tau_x) later, not a sample earlier."""
    for tau0, tau_x, samples in ((0.1, None, 12), (0.2, 0.05, 30)):
        model = "original" if tau_x is None else "original+extra_delay"
        _, _, loop = _loop(model, tau0=tau0, **({} if tau_x is None else {"tau_x": tau_x}))
        e = np.zeros(200)
        e[50:] = 1.0
        delta = DiscretePilot(loop, DT).simulate(e)
        assert np.all(delta[:50 + samples] == 0.0)
        assert delta[50 + samples] != 0.0


def test_sample_lag_comes_off_the_buffer():
    """In the flight the pilot sees the previous row's output: its buffer is one sample
    shorter, so that the record shows exactly tau0 from output to control."""
    _, _, loop = _loop("original", tau0=0.1)
    e = np.zeros(100)
    e[20:] = 1.0
    delta = DiscretePilot(loop, DT, sample_lag=1).simulate(e)
    assert np.all(delta[:31] == 0.0) and delta[31] != 0.0
    with pytest.raises(HesspipeError, match="tau0"):
        DiscretePilot(_loop("original", tau0=0.5 * DT)[2], DT, sample_lag=1)


def test_fractional_delay_interpolates_between_samples():
    _, _, loop = _loop("original", tau0=0.1 + 0.25 * DT)
    e = np.zeros(100)
    e[20:] = 1.0
    delta = DiscretePilot(loop, DT).simulate(e)
    assert np.all(delta[:32] == 0.0) and delta[32] != 0.0
    _, _, whole = _loop("original", tau0=0.1)
    ref = DiscretePilot(whole, DT).simulate(e)
    # 3/4 of the sample-12 response plus 1/4 of the sample-13 one (the filter is linear).
    assert delta[32] == pytest.approx(0.75 * ref[32], rel=1e-12)


def test_discrete_pilot_matches_continuous_response():
    """Tustin sections + delay buffer vs the continuous blocks, 0.5-10 rad/s: within 0.2 % and 0.2 deg."""
    _, _, loop = _loop()
    pilot = DiscretePilot(loop, DT)
    w = np.logspace(np.log10(0.5), 1.0, 40)
    cont = continuous_paths(loop, w)
    for path in ("visual", "vestibular", "noise"):
        ratio = pilot.response(w, path) / cont[path]
        assert np.max(np.abs(np.abs(ratio) - 1.0)) < 2e-3, path
        assert np.max(np.abs(np.degrees(np.angle(ratio)))) < 0.2, path
    # As flown (one sample of the loop's sampling taken off the buffer, the motion path
    # extrapolated over it): the recorded loop's paths, within 1 % and 0.2 deg (the
    # extrapolation's (w dt)^2 error is 0.7 % at 10 rad/s).
    lagged = DiscretePilot(loop, DT, sample_lag=1)
    for path, tol in (("visual", 2e-3), ("vestibular", 1e-2), ("noise", 2e-3)):
        ratio = lagged.response(w, path) / cont[path]
        assert np.max(np.abs(np.abs(ratio) - 1.0)) < tol, path
        assert np.max(np.abs(np.degrees(np.angle(ratio)))) < 0.2, path
    # and the time-domain stepping is the filter whose response was just checked
    rng = np.random.default_rng(0)
    e = rng.standard_normal(4096)
    out = DiscretePilot(loop, DT).simulate(e)
    spec = np.fft.rfft(out) / np.fft.rfft(e)
    w_fft = 2 * np.pi * np.fft.rfftfreq(4096, DT)
    band = (w_fft > 2) & (w_fft < 8)
    # circular vs linear convolution: compare on the band, loosely (finite record)
    assert np.median(np.abs(spec[band] / pilot.response(w_fft[band], "visual") - 1)) < 0.05


def test_motion_path_follows_the_plants():
    m, p, _ = _loop("expanded")
    default = pilot_loop(m, p, PLANTS)
    paper = (PLATFORM * WASHOUT).terms[0]
    same = Plants(PLANTS.Yc, PLANTS.Yd, motion_path=ct.tf(np.asarray(paper.num) * paper.gain, paper.den))
    fixed_base = Plants(PLANTS.Yc, PLANTS.Yd, motion_path=ct.tf([1.0, 0.0], [0.01, 1.0]))
    w = np.array([0.5, 2.0, 8.0])
    r0 = DiscretePilot(default, DT).response(w, "vestibular")
    r1 = DiscretePilot(pilot_loop(m, p, same), DT).response(w, "vestibular")
    r2 = DiscretePilot(pilot_loop(m, p, fixed_base), DT).response(w, "vestibular")
    assert np.allclose(r0, r1, rtol=1e-6)
    assert not np.allclose(r0, r2, rtol=0.1)


def test_aircraft_effect_in_the_pilot_is_refused(tmp_path):
    with pytest.raises(HesspipeError, match="dutch_roll"):
        _fly(tmp_path, "original+dutch_roll")


# --------------------------------------------------------------------------- flights

def test_pilot_keeps_the_envelope_and_damps_the_roll_rate(tmp_path):
    flown = _fly(tmp_path)
    env = flown.truth["envelope"]
    assert abs(env["speed_kts"][0] - 135) < 10 and abs(env["speed_kts"][1] - 135) < 10
    assert env["min_agl_ft"] > 50 and env["max_abs_bank_deg"] < 15
    assert flown.truth["simulator"] == "jsbsim" and flown.run.synthetic
    # A pilot with no gains flies the same wind hands off: the pilot must do better.
    idle = _fly(tmp_path, "original", {"Ke": 0.0})
    assert np.std(idle.run.control) < 1e-9
    assert np.std(flown.run.output) < 0.8 * np.std(idle.run.output)


def test_the_record_replays_through_the_pilot_row_by_row(tmp_path):
    # The pilot at row k acted on row k - 1's output and reference, so the record's own
    # e = r - y, fed one row late through the same discrete pilot, gives the recorded
    # control. (It read row k's reference before: the target reached the control 1 step
    # early, 1.5-3.4 % of |U| of equation error at flown runs' target lines.)
    n = int(round(SHORT.duration_s / DT))
    t = np.arange(n) * DT
    r = 0.02 * np.sin(2.0 * t) + 0.01 * np.sin(5.3 * t + 1.0)
    flown = _fly(tmp_path, "expanded", {"Km": 2.0}, reference=r)
    m = PilotModel(("motion_feedback",))
    pilot = DiscretePilot(pilot_loop(m, m.complete(flown.truth["parameters"], gain=gain_scale(PLANTS)),
                                     PLANTS), DT, sample_lag=1)
    run = flown.run
    e, y = run.reference - run.output, run.output
    u = run.control - flown.trim["aileron_norm"]
    replay = [pilot.step(r[0], 0.0)] + [pilot.step(e[k - 1], y[k - 1]) for k in range(1, n)]
    assert np.max(np.abs(np.asarray(replay) - u)[1:]) < 1e-3 * np.std(u)


def test_rate_limit_bounds_the_aileron_rate_and_lag_delays_it(tmp_path):
    free = _fly(tmp_path)
    rate = np.max(np.abs(np.diff(free.record["applied"]))) / DT
    limit = 0.2 * rate
    limited = _fly(tmp_path, aircraft_effects=AircraftEffects(rate_limit_per_s=limit))
    assert np.max(np.abs(np.diff(limited.record["applied"]))) / DT <= limit * (1 + 1e-9)
    assert limited.truth["aircraft_effects"] == {"rate_limit_per_s": limit}
    assert not np.allclose(limited.run.output, free.run.output)
    lag = _fly(tmp_path, aircraft_effects=AircraftEffects(actuator_lag_s=0.2))
    # a first-order lag: the applied command is smoother than the pilot's
    assert np.std(np.diff(lag.record["applied"])) < 0.5 * np.std(np.diff(lag.record["control"]))


def test_yaw_damper_off_changes_the_aircraft(tmp_path):
    on = _fly(tmp_path / "on")
    off = _fly(tmp_path / "off", aircraft_effects=AircraftEffects(yaw_damper=False))
    assert off.truth["aircraft_effects"]["yaw_damper"] == "off"
    assert any("yaw-damper" in s for s in off.truth["aircraft_effects"]["yaw_damper_inputs_removed"])
    assert np.max(np.abs(on.run.output - off.run.output)) > 1e-4


def test_cli_writes_synthetic_run_truth_and_figure_reproducibly(tmp_path, plants_file, capsys):
    outs = []
    for name, seed in (("a", 4), ("b", 4), ("c", 5)):
        out = tmp_path / name
        assert main(["fly-pilot", "--plants", str(plants_file), "--out", str(out), "--seed", str(seed),
                     "--aircraft", "B747"]) == 0
        outs.append(out)
    assert sorted(p.name for p in outs[0].iterdir()) == [MARKER, "pilot.csv", "pilot.png", "pilot.truth.json"]
    # 1/120 s written to 9 digits jitters by ~1e-5 of the interval: SPEC.md's uniformity is 1e-4
    run = read_run(outs[0] / "pilot.csv", rtol=1e-4)
    assert run.synthetic and len(run) == 8400 and run.dt == pytest.approx(DT)
    truth = json.loads((outs[0] / "pilot.truth.json").read_text())
    assert truth["simulator"] == "jsbsim" and truth["synthetic"] and truth["seed"] == 4
    assert truth["aircraft"] == "B747" and truth["plants_aircraft"] == "737"
    assert truth["aircraft_differs_from_plants"] is True
    assert set(truth["effects"]) == {"motion_feedback", "remnant"}
    for f in ("pilot.csv", "pilot.truth.json"):
        assert (outs[0] / f).read_bytes() == (outs[1] / f).read_bytes()
        assert (outs[0] / f).read_bytes() != (outs[2] / f).read_bytes()
    assert "SYNTHETIC" in capsys.readouterr().out


def test_cli_two_input_forcing_records_the_duration_after_the_run_in(tmp_path, plants_file):
    from hesspipe.flight.target import TWO_INPUT

    out = tmp_path / "two"
    assert main(["fly-pilot", "--plants", str(plants_file), "--out", str(out), "--forcing", "two_input"]) == 0
    run = read_run(out / "pilot.csv", rtol=1e-4)
    truth = json.loads((out / "pilot.truth.json").read_text())
    # the record is the default 70 s; the run-in before it is flown but not written
    assert len(run) == 8400 and truth["record_start_s"] == pytest.approx(TWO_INPUT.run_in_s, abs=DT)
    assert truth["target"]["run_in_s"] == TWO_INPUT.run_in_s and not truth["target"]["paper_side_wind"]
    assert np.std(run.reference) > 0


def test_limit_violation_is_one_line_and_writes_nothing(tmp_path, plants_file, capsys):
    out = tmp_path / "out"
    code = main(["fly-pilot", "--plants", str(plants_file), "--out", str(out), "--max-bank", "0.05"])
    err = capsys.readouterr().err
    assert code == 1
    assert err.count("\n") == 1 and "Traceback" not in err
    assert "bank" in err and "t = " in err
    assert not out.exists()


def test_bad_params_file_is_one_line(tmp_path, plants_file, capsys):
    params = tmp_path / "p.json"
    params.write_text('{"Ke": "high"}')
    code = main(["fly-pilot", "--plants", str(plants_file), "--out", str(tmp_path / "o"),
                 "--params", str(params)])
    err = capsys.readouterr().err
    assert code == 1 and "'Ke'" in err and err.count("\n") == 1


@pytest.mark.parametrize("params, words", [
    ({"tau0": -0.1}, "field 'tau0': expected a number >= 0, got -0.1"),
    ({"wn": 0}, "field 'wn': expected a number > 0, got 0"),
    ({"Kx": 1}, "field 'Kx': unknown parameter for model expanded+remnant; expected one of Ke, K1"),
], ids=["tau0 < 0", "wn = 0", "unknown"])
def test_params_out_of_the_models_range_are_one_line_naming_file_and_field(params, words, tmp_path,
                                                                          plants_file, capsys):
    path = tmp_path / "p.json"
    path.write_text(json.dumps(params))
    out = tmp_path / "o"
    code = main(["fly-pilot", "--plants", str(plants_file), "--out", str(out), "--params", str(path)])
    err = capsys.readouterr().err
    assert code == 1 and err.startswith(f"hesspipe: error: {path}: {words}"), err
    assert err.count("\n") == 1 and not out.exists()


def test_a_truth_files_parameters_fly_again():
    """The boxes' high ends do not bound a pilot: a drawn pilot's Kn lies far above its box."""
    truth = {"Ke": 23.1, "Km": 3.7, "Kn": 49.9, "k": 1.0, "wn": 10.0}
    assert PilotModel(("motion_feedback", "remnant")).check_values(truth, "t.json") == truth
    assert PilotModel().check_values(truth, "t.json") == {"Ke": 23.1, "k": 1.0, "wn": 10.0}


def test_an_empty_id_is_refused(tmp_path, plants_file, capsys):
    out = tmp_path / "o"
    assert main(["fly-pilot", "--plants", str(plants_file), "--out", str(out), "--id", ""]) == 1
    assert capsys.readouterr().err == "hesspipe: error: --id: expected a non-empty name for the run's files, got ''\n"
    assert not out.exists()


def test_a_copy_of_the_default_configuration_flies(tmp_path, plants_file, capsys):
    """What `run --config` takes, `fly-pilot --config` takes ([flight] aircraft among the rest)."""
    copy = tmp_path / "mine.toml"
    shutil.copy(data_dir("pipeline") / "default.toml", copy)
    out = tmp_path / "o"
    code = main(["fly-pilot", "--plants", str(plants_file), "--out", str(out), "--config", str(copy)])
    assert code == 0, capsys.readouterr().err
    assert json.loads((out / "pilot.truth.json").read_text())["aircraft"] == "737"


def test_cohort_is_the_synthetic_cohorts_draw_flown_in_jsbsim(tmp_path):
    from hesspipe.core.seeds import derive_seed
    from hesspipe.pilots.cohort import CohortSpec, synth_pilot
    from hesspipe.pilots.flown import fly_cohort

    paths = fly_cohort(PLANTS, 2, 11, ["motion_feedback"], tmp_path / "cohort", config=SHORT)
    cohort = json.loads((tmp_path / "cohort" / "cohort.json").read_text())
    assert cohort["simulator"] == "jsbsim" and cohort["synthetic"] and cohort["dt_s"] == pytest.approx(0.025)
    assert cohort["plants"] == plants_coefficients(PLANTS)
    for path in paths:
        pid = path.stem
        truth = json.loads(path.with_suffix(".truth.json").read_text())
        _, drawn = synth_pilot(PLANTS, pid, derive_seed(11, pid), ("motion_feedback",),
                               CohortSpec(duration_s=SHORT.duration_s))
        same = {k: v for k, v in drawn["parameters"].items() if k != "Kn"}  # Kn: per 120 Hz step
        assert {k: truth["parameters"][k] for k in same} == same
        run = read_run(path)
        assert run.synthetic and run.dt == pytest.approx(0.025) and len(run) == 800


def test_crossover_model_cohort_flies_the_737_within_the_limits(tmp_path):
    # The pipeline's default cohort on the 737's fitted plants (slow RHP zero, Dutch roll):
    # every pilot's tracking crossover is the drawn target, within 1-5 rad/s and 20-60 deg,
    # and the pilot keeps the JSBSim aircraft in the envelope.
    from hesspipe.pilots.cohort import cohort_spec, hess_corner
    from hesspipe.pilots.flown import fly_cohort

    spec = cohort_spec("crossover_model", duration_s=SHORT.duration_s)
    paths = fly_cohort(PLANTS, 3, 5, ["motion_feedback"], tmp_path / "cohort", config=SHORT, spec=spec)
    corner = hess_corner(PLANTS)
    assert 0.1 < corner < 1.0  # the roll mode's corner region, not Table 1's 0.01
    for path in paths:
        truth = json.loads(path.with_suffix(".truth.json").read_text())
        c = truth["crossover"]
        assert c["within_limits"] and 1.5 <= c["frequency_rad_s"] <= 4.0
        assert 20.0 <= c["phase_margin_deg"] <= 60.0
        assert truth["parameters"]["1/T1"] == pytest.approx(corner)
        env = truth["envelope"]
        assert env["max_abs_bank_deg"] < 15.0 and env["min_agl_ft"] > 50.0
        assert abs(env["speed_kts"][0] - env["trim_speed_kts"]) < 10.0
