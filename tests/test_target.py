"""Two-input forcing (hesspipe.flight.target) and the df criterion's reference lines. SYNTHETIC data."""

import numpy as np
import pytest

from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import Run
from hesspipe.flight.target import TWO_INPUT, TargetForcing, interleaved_lines
from hesspipe.identification.criteria import DFObjective, model_df, model_df_reference
from hesspipe.identification.frf import estimate_frf
from hesspipe.pilot.hess import PilotModel
from hesspipe.pilot.simulation import Simulator, synthetic_run
from pilot_data import plants as eq_plants

PARAMS = {"Ke": 2.0, "K1": 1.0, "K2": 2.0, "1/T1": 0.5, "Km": 0.8, "tau0": 0.2}


def _loop(plants, params=PARAMS):
    m = PilotModel(("motion_feedback",))
    sim = Simulator(plants, np.zeros(64), 0.02)
    return m, sim, sim.prepare(m.loop(m.complete(params, 1)))


def _solve(loop, yc, s, r, d_out):
    """Brute force: u, y of the loop's signal equations at one s, by a 2x2 linear solve.

    u = NM (visual (r - y) - vestibular y - PF u) and y = Yc' u + d_out.
    """
    nm, vis = loop.neuromuscular.response(s)[0], loop.visual.response(s)[0]
    ves, pf = loop.vestibular.response(s)[0], loop.proprioceptive.response(s)[0]
    ycp = yc * loop.plant.response(s)[0]
    a = np.array([[1 + nm * pf, nm * (vis + ves)], [-ycp, 1.0]], dtype=complex)
    b = np.array([nm * vis * r, d_out], dtype=complex)
    return np.linalg.solve(a, b)


def test_lines_are_disjoint_interleaved_and_on_the_records_bins():
    kd, kt = interleaved_lines(70.0, 12, 0.03, 2.0)
    assert not set(kd) & set(kt) and np.all(np.diff(kd) >= 3) and kd.min() >= 2
    t = np.arange(2800) * 0.025
    wind, ref = TargetForcing(target_rms=0.03, wind_rms=2.5).signals(t, seed=4)
    assert np.std(wind) == pytest.approx(2.5) and np.std(ref) == pytest.approx(0.03)
    for x, k in ((wind, kd), (ref, kt)):
        p = np.abs(np.fft.rfft(x)) ** 2
        assert np.nonzero(p > 1e-9 * p.max())[0].tolist() == sorted(k.tolist())
    with pytest.raises(HesspipeError, match="do not fit"):
        interleaved_lines(10.0, 12, 0.03, 0.5)


def test_output_equivalent_wind_moves_the_output_like_the_target_line_beside_it(tmp_path):
    """wind_equivalent: each wind line, through Yd, has the amplitude of the target line next to
    it times the ratio; a flight takes Yd from its plants; no path, no design."""
    from hesspipe.flight.approach import FlightConfig
    from hesspipe.flight.closed_loop import fly_pilot_record
    from hesspipe.pilot.blocks import from_tf

    plants = eq_plants()
    yd = from_tf(plants.disturbance_to_output).response
    dt, n = 0.025, 2800
    tg = TargetForcing(target_rms=0.03, wind_equivalent=0.5, corner_hz=0.0)
    wind, ref = tg.signals(np.arange(n) * dt, seed=4, disturbance_path=yd)
    kd, kt = interleaved_lines(n * dt, tg.n_lines, tg.f_min_hz, tg.f_max_hz)
    W, R = np.fft.rfft(wind), np.fft.rfft(ref)
    at_output = np.abs(W[kd]) * np.abs(yd(2j * np.pi * kd / (n * dt)))
    assert at_output == pytest.approx(0.5 * np.abs(R[kt]), rel=1e-9)
    assert np.ptp(np.abs(W[kd])) > 0.5 * np.max(np.abs(W[kd]))  # shaped, not flat
    assert tg.describe()["wind_output_equivalent"] == 0.5
    with pytest.raises(HesspipeError, match="disturbance path"):
        tg.signals(np.arange(n) * dt, seed=4)
    with pytest.raises(HesspipeError, match="wind_equivalent"):
        TargetForcing(wind_equivalent=-1.0)
    cfg = FlightConfig(duration_s=20.0)
    small = TargetForcing(target_rms=0.01, n_lines=6, f_min_hz=0.1, wind_equivalent=0.5, paper_side_wind=False)
    f = fly_pilot_record("737", plants, "expanded", {}, seed=3, workdir=tmp_path, config=cfg, target=small)
    m = int(round(20.0 / cfg.dt_s))
    wind, _ = small.signals(np.arange(m) * cfg.dt_s, f.truth["seeds"]["gust"], disturbance_path=yd)
    assert np.corrcoef(f.run.disturbance, wind)[0, 1] > 0.999


def test_reference_line_df_equals_a_brute_force_closed_loop():
    plants = eq_plants()
    _, sim, loop = _loop(plants)
    w = np.array([0.3, 1.0, 2.5, 6.0])
    got_r = model_df_reference(loop, 1j * w, sim.yc_block.response(1j * w))
    got_d = model_df(loop, 1j * w)
    for i, x in enumerate(w):
        s = np.array([1j * x])
        yc = sim.yc_block.response(s)[0]
        u, y = _solve(loop, yc, s, 1.0, 0.0)  # target only
        assert got_r[i] == pytest.approx(u / (1.0 - y), rel=1e-9)
        u, y = _solve(loop, yc, s, 0.0, 1.0)  # disturbance only (e = -y)
        assert got_d[i] == pytest.approx(u / (-y), rel=1e-9)
    # With motion feedback the two sets differ (what makes them informative), without they agree.
    assert np.max(np.abs(got_r / got_d - 1)) > 0.05
    _, sim0, loop0 = _loop(plants, dict(PARAMS, Km=0.0))
    assert np.allclose(model_df_reference(loop0, 1j * w, sim0.yc_block.response(1j * w)),
                       model_df(loop0, 1j * w), rtol=1e-12)


def _two_input_run():
    """A two-input run of the expanded model on the equivalent plants: two periods from
    rest, the second (steady state) kept. Returns (run, plants, model, params, dt, n)."""
    plants = eq_plants()
    dt, n = 0.025, 1400
    wind, ref = TargetForcing(target_rms=0.2, wind_rms=1.0).signals(np.arange(n) * dt, seed=7)
    m = PilotModel(("motion_feedback",))
    p = m.complete(PARAMS, 1)
    full = synthetic_run(m, p, plants, np.tile(wind, 2), dt, seed=1, reference=np.tile(ref, 2))
    run = Run(time=full.time[:n], disturbance=wind, output=full.output[n:], control=full.control[n:],
              reference=ref, id="two-input", synthetic=True)
    return run, plants, m, p, dt, n


def test_df_objective_fits_the_reference_lines_of_a_two_input_run():
    run, plants, m, p, dt, n = _two_input_run()
    frf = estimate_frf(run, plants)
    kd, kt = interleaved_lines(n * dt, 12, 0.03, 2.0)
    assert frf.reference is not None and frf.reference.bins.tolist() == kt.tolist()
    obj = DFObjective(run, plants, m, p, frf)
    assert obj.H_all.size > obj.n_feedback >= 3
    # The closed loop simulated by the FFT model matches the reference-line formula...
    loop = obj.sim.prepare(m.loop(p))
    s = 1j * frf.reference.freq_rad_s
    hr = model_df_reference(loop, s, obj.sim.yc_block.response(s))
    assert np.max(np.abs(frf.reference.H / hr - 1)) < 0.02
    # ...the objective is near zero at the truth and counts the reference lines' misfit
    # of a wrong Km (which those lines see through the vestibular loop around the plant).
    fb_only = DFObjective(run, plants, m, p, type(frf)(**{**frf.__dict__, "reference": None}))
    assert obj(dict()) < 0.5 and fb_only(dict()) < 0.5
    wrong = obj.sim.prepare(m.loop(dict(p, Km=0.0)))
    miss = np.abs(model_df_reference(wrong, s, obj.sim.yc_block.response(s)) - frf.reference.H)
    assert np.max(miss / frf.reference.sigma) > 10
    n_fb = obj.n_feedback
    r = obj.residuals_loop(m.loop(dict(p, Km=0.0))).reshape(2, -1)
    assert np.sum(r[:, n_fb:] ** 2) > 0.1 * np.sum(r ** 2)


def test_a_flight_with_a_target_records_it_and_refuses_a_second_reference(tmp_path):
    from hesspipe.flight.approach import FlightConfig
    from hesspipe.flight.closed_loop import fly_pilot_record

    cfg = FlightConfig(duration_s=20.0)
    tg = TargetForcing(target_rms=0.02, n_lines=6, f_min_hz=0.1)
    f = fly_pilot_record("737", eq_plants(), "expanded", {}, seed=3, workdir=tmp_path, config=cfg, target=tg)
    n = int(round(20.0 / cfg.dt_s))
    _, ref = tg.signals(np.arange(n) * cfg.dt_s, f.truth["seeds"]["gust"])
    assert np.array_equal(f.run.reference, ref) and f.truth["target"]["target_rms_rad_s"] == 0.02
    assert "interleaved" in f.truth["disturbance"]["excitation"]
    with pytest.raises(HesspipeError, match="reference"):
        fly_pilot_record("737", eq_plants(), "expanded", {}, seed=3, workdir=tmp_path, config=cfg,
                         target=tg, reference=np.zeros(n))


def test_run_in_keeps_the_start_transient_out_of_the_identified_period():
    """Noise-free two-input run of the FFT generator, fitted by df: the record that starts with the
    forcing (the first period, transient included) pulls Ke and Km down together; the same
    forcing with a run-in, the last whole period analysed, gives the truth back."""
    from hesspipe.identification.fit import identify

    pl, dt, err = eq_plants(), 0.025, {}
    for run_in in (0.0, 15.0):
        n, first = int(round((70.0 + run_in) / dt)), int(round(run_in / dt))
        tg = TargetForcing(target_rms=0.05, wind_rms=1.0, run_in_s=run_in)
        wind, ref = tg.signals(np.arange(n) * dt, seed=7)
        full = synthetic_run("expanded", PARAMS, pl, wind, dt, seed=7, reference=ref)
        sl = slice(first, None)
        run = Run(time=full.time[sl], disturbance=wind[sl], output=full.output[sl], control=full.control[sl],
                  reference=ref[sl], id="two-input", synthetic=True)
        q = identify(run, pl, "expanded", seed=7, criterion="df", with_benchmark=False,
                     with_identifiability=False).parameters
        err[run_in] = {k: q[k] / PARAMS[k] - 1 for k in ("Ke", "Km", "K1")}
    assert all(abs(v) < 0.02 for v in err[15.0].values()), err
    assert err[0.0]["Km"] < -0.1 and err[0.0]["Ke"] < -0.1, err


def test_a_flight_with_a_run_in_records_the_last_whole_period_without_the_side_wind(tmp_path):
    from hesspipe.flight.approach import FlightConfig
    from hesspipe.flight.closed_loop import fly_pilot_record

    cfg = FlightConfig(duration_s=25.0)
    tg = TargetForcing(target_rms=0.02, n_lines=6, f_min_hz=0.1, run_in_s=5.0, paper_side_wind=False)
    f = fly_pilot_record("737", eq_plants(), "expanded", {}, seed=3, workdir=tmp_path, config=cfg, target=tg,
                         record_every=3)
    run = f.run
    assert run.time[0] == pytest.approx(5.0) and len(run) == 800 and f.truth["record_start_s"] == pytest.approx(5.0)
    assert "none" in f.truth["disturbance"]["side_wind"] and f.truth["target"]["run_in_s"] == 5.0
    assert any("run-in" in c for c in run.comments)
    # the recorded wind is the wind multisine alone (no turning side wind), seen from the heading flown
    n = int(round(25.0 / cfg.dt_s))
    wind, ref = tg.signals(np.arange(n) * cfg.dt_s, f.truth["seeds"]["gust"])
    assert np.array_equal(run.reference, ref[600::3])
    assert np.corrcoef(run.disturbance, wind[600::3])[0, 1] > 0.999
    frf = estimate_frf(run)
    assert frf.window == (0, 800) and frf.feedback.H.size == 6 and frf.reference.H.size == 6
    with pytest.raises(HesspipeError, match="run_in_s"):
        TargetForcing(run_in_s=30.0).signals(np.arange(n) * cfg.dt_s, 1)


def test_pilots_forcing_two_input_flies_a_run_in_and_records_both_line_sets(tmp_path):
    import json
    from types import SimpleNamespace

    from hesspipe.core.formats import read_run
    from hesspipe.pilots.flown import fly_pipeline_cohort
    from hesspipe.pilots.settings import PilotsConfig

    table = {"n": 1, "duration_s": 30.0, "dt_s": 0.025, "forcing": "two_input", "cohort": "table1",
             "effects": ["motion_feedback"]}
    config = PilotsConfig.from_table(table, "x.toml")
    ctx = SimpleNamespace(config={}, source="x.toml", seed=1, out_dir=tmp_path)
    out = fly_pipeline_cohort(config, eq_plants(), ctx)
    run = read_run(tmp_path / "cohort" / "pilot01.csv")
    assert len(run) == 1200 and run.time[0] == pytest.approx(15.0)
    cohort = json.loads((tmp_path / "cohort" / "cohort.json").read_text())
    assert cohort["target"]["run_in_s"] == 15.0 and out.data == str(tmp_path / "cohort")
    from hesspipe.pipeline.report import _simulator_note
    assert "Forcing: two-input" in " ".join(_simulator_note(tmp_path))  # the report says which forcing
    frf = estimate_frf(run)
    assert frf.method == "multisine" and frf.feedback.H.size == 12 and frf.reference.H.size == 12
    with pytest.raises(HesspipeError, match="forcing"):
        PilotsConfig.from_table({"forcing": "gusts"}, "x.toml")
    # The default: the pipeline's cohort answers the motion question unless told otherwise.
    assert PilotsConfig.from_table({}, "x.toml").forcing == "two_input"


def test_the_frequency_domain_cohort_flies_the_two_input_forcing_too(tmp_path):
    """`[pilots] simulator = "fft"` with the default forcing: both line sets in every record,
    periodic over it (the FFT loop's steady state: no run-in), the reference column filled;
    the motion test then tells the cohort with motion feedback from the one without."""
    import json

    from hesspipe.core.formats import read_run
    from hesspipe.identification.motion_test import motion_test
    from hesspipe.pilot.hess import PilotModel
    from hesspipe.pilots.cohort import cohort_spec, synth_cohort
    from hesspipe.pilots.settings import PilotsConfig
    from test_pilotflight import PLANTS

    assert PilotsConfig.from_table({"simulator": "fft"}, "x.toml").forcing == "two_input"
    plants = PLANTS  # the JSBSim 737's fitted plants, which TWO_INPUT's levels were set for
    spec = cohort_spec("crossover_model", duration_s=70.0, dt_s=0.025, target=TWO_INPUT)
    p = {}
    for effects in (("motion_feedback",), ()):
        out = tmp_path / ("motion" if effects else "none")
        # Seeds 0-5 (ad hoc, /tmp probe): p < 0.01 for 5 of 6 motion pilots, 0 of 6 without.
        synth_cohort(plants, 1, 5, effects, out, spec=spec)
        run = read_run(out / "pilot01.csv")
        assert len(run) == 2800 and abs(run.time[0]) < 1e-9 and np.std(run.reference) > 0
        frf = estimate_frf(run)
        assert frf.method == "multisine" and frf.feedback.H.size == 12 and frf.reference.H.size == 12
        cohort = json.loads((out / "cohort.json").read_text())
        truth = json.loads((out / "pilot01.truth.json").read_text())
        assert cohort["target"]["run_in_s"] == 0.0 and truth["disturbance"]["target"]["run_in_s"] == 0.0
        p[effects] = motion_test(run, plants, PilotModel().complete({}, 1))["p_value"]
    assert p[("motion_feedback",)] < 0.01 < p[()]


def test_a_constant_in_the_reference_is_where_the_loop_operates_not_a_step():
    # A heading task logs target and yaw in compass terms (270 deg = 4.71 rad): the same run
    # about another constant. Simulated from rest, that constant was a step into the model's
    # loop and moved the spectral fitness; the analyses take the reference less its mean.
    from hesspipe.identification.problem import SpectralObjective

    run, plants, m, p, dt, n = _two_input_run()
    wind, ref = run.disturbance, run.reference
    heading = Run(time=run.time, disturbance=wind, output=run.output + 4.71, control=run.control,
                  reference=ref + 4.71, id="heading", synthetic=True)
    np.testing.assert_allclose(heading.reference_forcing, run.reference_forcing, atol=1e-12)
    values = [SpectralObjective(r, plants, m, p)(dict()) for r in (run, heading)]
    assert values[0] == pytest.approx(values[1], rel=1e-9)
    # The step itself: the same objective fed the offset reference differs by far more.
    stepped = SpectralObjective(run, plants, m, p)
    stepped.sim = Simulator(plants, wind, dt, reference=ref + 4.71)
    assert abs(stepped(dict()) - values[0]) > 1e-3 * abs(values[0]), (stepped(dict()), values)
