"""Tests of the independent human-like trial generator (hesspipe.humanlike).

The generator is checked against its own analytic formulas and against plain
numpy spectra; hesspipe's readers appear only in the smoke test at the end.
"""

import json
import subprocess
import sys

import numpy as np
import pytest

from hesspipe.core.errors import HesspipeError
from hesspipe.humanlike import (
    closed_loop,
    csv_bytes,
    draw_trial,
    make_plant,
    make_trials,
    retest,
    simulate_trial,
    write_trial,
)
from hesspipe.humanlike.pilots import loop_metrics

SHORT = dict(T_m=15.0, run_in=10.0)     # 900 samples at 60 Hz: fast, whole periods


def test_independent_of_the_code_under_test():
    forbidden = ["pilot", "identification", "pilots", "diagnose", "plants", "flight", "core.formats"]
    code = ("import sys, hesspipe.humanlike; "
            "print(' '.join(m for m in sys.modules if m.startswith('hesspipe')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    loaded = set(out.stdout.split())
    assert not {m for m in loaded if any(m == f"hesspipe.{f}" or m.startswith(f"hesspipe.{f}.")
                                         for f in forbidden)}, loaded
    assert {m for m in loaded if not m.startswith("hesspipe.humanlike")} <= \
        {"hesspipe", "hesspipe.core", "hesspipe.core.lazy", "hesspipe.core.errors", "hesspipe.core.io",
         "hesspipe.core.stops", "hesspipe.core.seeds", "hesspipe.core.paper"}, loaded
    # paper: the printed numbers, no code; stops: io's record of a signal, no analysis


def test_fine_step_convergence():
    # Remnant noise is defined at a fixed rate, so halving the step keeps its realisation.
    spec = draw_trial("1/(s(s+1))", 4, task="both", pilot="hess", **SHORT)
    a, b = simulate_trial(spec), simulate_trial(spec, fine_ratio=40)
    for name in ("output", "control"):
        x, y = getattr(a, name), getattr(b, name)
        assert np.max(np.abs(x - y)) < 0.01 * np.std(x), name
    assert np.array_equal(a.disturbance, b.disturbance)


@pytest.mark.parametrize("task", ["disturbance", "both"])
def test_simulation_matches_analytic_closed_loop(task):
    # A pilot without equalisation (gain, delay, neuromuscular lag) on 1/s, no remnant.
    pilot = {"structure": "precision", "tau": 0.2, "wn": 12.0, "zn": 0.3, "TL": 0.0,
             "TI": 0.0, "Kp": 3.0}
    spec = draw_trial("1/s", 5, task=task, pilot_params=pilot, remnant_share=0.0, **SHORT)
    tr = simulate_trial(spec)
    h = tr.truth["forcing"]["fine_step_s"]
    U, Y, D = (np.fft.fft(x) for x in (tr.control, tr.output, tr.disturbance))
    k = spec.disturbance.k
    cl = closed_loop(spec, spec.disturbance.w, h)
    assert np.max(np.abs(U[k] / D[k] / cl["u_d"] - 1)) < 0.02
    assert np.max(np.abs(Y[k] / D[k] / cl["y_d"] - 1)) < 0.02
    # Off the forcing lines there is (almost) nothing: steady state, whole periods.
    off = np.ones(U.size, dtype=bool)
    off[k] = off[-k] = False
    if spec.target is not None:
        R = np.fft.fft(tr.reference)
        kt = spec.target.k
        clt = closed_loop(spec, spec.target.w, h)
        assert np.max(np.abs(U[kt] / R[kt] / clt["u_r"] - 1)) < 0.02
        off[kt] = off[-kt] = False
    assert np.sum(np.abs(U[off]) ** 2) < 1e-4 * np.sum(np.abs(U) ** 2)
    # The truth's describing function is the pilot's U/E at the disturbance lines.
    H = np.array(tr.truth["describing_function"]["re"]) \
        + 1j * np.array(tr.truth["describing_function"]["im"])
    sets = tr.truth["describing_function"]["line_set"]
    E = np.fft.fft(tr.reference - tr.output)
    hd = H[[i for i, s in enumerate(sets) if s == "disturbance"]]
    assert np.max(np.abs(U[k] / E[k] / hd - 1)) < 0.02


def test_remnant_share():
    for seed in range(2):
        spec = draw_trial("1/s", seed)          # 45 s: lines sparse enough to interpolate
        tr = simulate_trial(spec)
        rem = tr.truth["remnant"]
        assert 0.10 <= rem["share_drawn"] <= 0.40
        assert rem["share_realised"] == pytest.approx(rem["share_drawn"], rel=1e-6)
        # Independent check from the spectrum: power off the lines plus, at each line, the
        # remnant interpolated from its neighbours.
        u = tr.control - tr.control.mean()
        P = np.abs(np.fft.rfft(u)) ** 2
        lines = np.zeros(P.size, dtype=bool)
        lines[spec.disturbance.k] = True
        est = P[1:][~lines[1:]].sum() + sum(
            P[[j for j in (k - 2, k - 1, k + 1, k + 2) if not lines[j]]].mean()
            for k in spec.disturbance.k)
        assert est / P[1:].sum() == pytest.approx(rem["share_drawn"], abs=0.04)


@pytest.mark.parametrize("plant", ["1/s", "1/(s(s+1))", "K/s2", "roll"])
@pytest.mark.parametrize("pilot", ["precision", "hess"])
def test_pilots_meet_the_crossover_model(plant, pilot):
    for seed in range(3):
        spec = draw_trial(plant, seed, pilot=pilot)
        p = spec.pilot
        assert 0.15 <= p["tau_v"] <= 0.35 and 7 <= p["wn"] <= 15 and 0.1 <= p["zn"] <= 0.5
        m = loop_metrics(lambda w: sum(spec.pilot_parts(w)) * spec.yc_effective(w))
        assert 1.5 <= m["frequency_rad_s"] <= 4.0 and 20 <= m["phase_margin_deg"] <= 60
        if pilot == "precision" and plant in ("K/s2", "1/(s(s+1))"):
            assert p["TL"] > 0          # lead for K/s^2-like plants
        if pilot == "precision" and plant == "1/s":
            assert p["TL"] == 0         # lag or nothing for K/s


def test_same_seed_same_bytes(tmp_path):
    paths = [make_trials(tmp_path / name, "1/s", 2, 11, **SHORT) for name in ("a", "b")]
    for pa, pb in zip(*paths):
        for suffix in (".csv", ".truth.json"):
            assert pa.with_suffix(suffix).read_bytes() == pb.with_suffix(suffix).read_bytes()
    assert (tmp_path / "a" / "plants.json").read_bytes() == (tmp_path / "b" / "plants.json").read_bytes()
    other = make_trials(tmp_path / "c", "1/s", 1, 12, **SHORT)[0]
    assert other.read_bytes() != paths[0][0].read_bytes()


def test_csv_styles(tmp_path):
    spec = draw_trial("1/s", 2, task="both", **SHORT)
    tr = simulate_trial(spec)
    raw = csv_bytes(tr, {"time": "ms", "bom": True, "newline": "\r\n"})
    assert raw.startswith(b"\xef\xbb\xbf#")
    text = raw[3:].decode("utf-8")
    assert text.count("\r\n") == text.count("\n") == len(tr.time) + 2
    lines = text.split("\r\n")
    assert "synthetic data: independent human-like generator" in lines[0]
    assert lines[1] == "time,disturbance,output,control,reference"
    t = [row.split(",")[0] for row in lines[2:-1]]
    assert all(len(x.split(".")[1]) == 3 for x in t[1:])
    assert np.max(np.abs(np.array(t, dtype=float) - tr.time)) <= 0.0005 + 1e-12
    vals = np.array([row.split(",")[1:] for row in lines[2:-1]], dtype=float)
    assert np.allclose(vals[:, 2], tr.control, rtol=1e-5, atol=0)
    raw = csv_bytes(tr, {"time": "epoch_us", "epoch0": 1.7e9,
                         "columns": ["time", "reference", "output", "control", "disturbance"]})
    rows = raw.decode().split("\n")
    assert rows[1] == "time,reference,output,control,disturbance" and "\r" not in raw.decode()
    assert float(rows[3].split(",")[0]) == pytest.approx(1.7e9 + 1 / 60, abs=1e-6)
    g9 = csv_bytes(tr, {"time": "g9"}).decode().split("\n")
    assert g9[3].split(",")[0] == "0.0166666667"
    path = write_trial(tmp_path, tr)
    truth = json.loads(path.with_suffix(".truth.json").read_text())
    assert truth["synthetic"] is True and truth["style"]["time"] == spec.style["time"]


def test_plants_file_and_dutch_roll(tmp_path):
    spec = draw_trial("roll", 3, effects=("dutch_roll",), **SHORT)
    tr = simulate_trial(spec)
    write_trial(tmp_path, tr)
    plants = json.loads((tmp_path / "plants.json").read_text())
    assert plants["control_to_output"]["den"] == pytest.approx([1.0, 1.0496], abs=1e-4)
    assert plants["control_to_output"]["num"] == pytest.approx([2.436], abs=1e-3)
    assert plants["disturbance_to_output"] == plants["control_to_output"]
    # The aircraft flown is the full lateral one: its Dutch-roll pair shows near 0.74 rad/s.
    poles = np.linalg.eigvals(spec.plant.true.A)
    assert np.any(np.abs(poles - (-0.0341 + 0.7362j)) < 1e-3)
    other = draw_trial("1/s", 3, **SHORT)
    with pytest.raises(HesspipeError, match="plants.json"):
        write_trial(tmp_path, simulate_trial(other))


@pytest.mark.parametrize("output", ["rate", "angle"])
def test_paper_dutch_roll_aircraft_feels_the_papers_wind(output):
    # The "paper" trial sizes its wind for Eq. 16; the full aircraft behind it must move as
    # much per ft/s, or the disturbance lines vanish under the target's (Table 4's own
    # sideslip path is 15-120 times weaker).
    full = make_plant("paper", output=output, dutch_roll=True).true
    nominal = make_plant("paper", output=output).true
    w = np.geomspace(0.2, 5.0, 25)
    ratio = np.abs(full.freqresp(w, 1)) / np.abs(nominal.freqresp(w, 1))
    assert 0.5 < np.exp(np.mean(np.log(ratio))) < 2.0
    # The control path and the Dutch roll are Table 4's, untouched.
    assert np.allclose(full.freqresp(w, 0), make_plant("roll", output=output, dutch_roll=True).true.freqresp(w, 0))


def test_bad_input():
    with pytest.raises(HesspipeError, match="unknown option"):
        draw_trial("1/s", 1, tua=0.2)
    with pytest.raises(HesspipeError, match="effects"):
        draw_trial("1/s", 1, effects=("nope",))
    with pytest.raises(HesspipeError, match="motion_path"):     # canals x s^3 x NM: improper
        simulate_trial(draw_trial("K/s2", 1, effects=("motion_feedback",), output="angle",
                                  motion_path=([1.0, 0.0, 0.0, 0.0], [1.0]), **SHORT))
    with pytest.raises(HesspipeError, match="plant"):
        make_plant("no/such/plants.json")
    with pytest.raises(HesspipeError, match="T_m"):
        draw_trial("1/s", 1, T_m=45.01)
    with pytest.raises(HesspipeError, match="gain_drift"):
        draw_trial("1/s", 1, gain_drift=0.8)
    with pytest.raises(HesspipeError, match="drift_tc"):
        draw_trial("1/s", 1, gain_drift=0.1, drift_tc=0.0)


def test_gain_drift():
    # A pilot without equalisation on 1/s and no remnant: off the lines there is only what
    # the wandering gain puts there (its sidebands).
    pilot = {"structure": "precision", "tau": 0.2, "wn": 12.0, "zn": 0.3, "TL": 0.0,
             "TI": 0.0, "Kp": 3.0}
    kw = dict(task="disturbance", pilot_params=pilot, remnant_share=0.0, T_m=45.0, run_in=10.0)
    steady = simulate_trial(draw_trial("1/s", 2, **kw))
    assert steady.truth["gain_drift"]["realised_sd"] == 0.0
    assert np.array_equal(steady.control, simulate_trial(draw_trial("1/s", 2, gain_drift=0.0, **kw)).control)
    spec = draw_trial("1/s", 2, gain_drift=0.2, drift_tc=5.0, **kw)
    tr = simulate_trial(spec)
    gd = tr.truth["gain_drift"]
    assert gd["cv"] == 0.2 and 0.1 < gd["realised_sd"] < 0.3
    assert np.array_equal(tr.control, simulate_trial(spec).control)     # seeded
    U = np.fft.rfft(tr.control)
    off = np.ones(U.size, dtype=bool)
    off[spec.disturbance.k] = off[0] = False
    share = np.sum(np.abs(U[off]) ** 2) / np.sum(np.abs(U[1:]) ** 2)
    # u ~ kv(t) u0(t) in open loop puts about sd^2 of the power off the lines; the loop
    # rejects part of it below crossover.
    assert 0.2 * gd["realised_sd"] ** 2 < share < 1.5 * gd["realised_sd"] ** 2
    # A retest keeps the pilot's variability and draws another realisation of it.
    again = simulate_trial(retest(spec, 7))
    assert again.truth["gain_drift"]["cv"] == 0.2
    assert again.truth["seeds"]["gain_drift"] != tr.truth["seeds"]["gain_drift"]


def test_line_bins():
    # A layout of one's own: the forcing sits on exactly those lines, and a retest keeps it.
    kd, kt = [3, 7, 12, 20], [4, 9, 15, 26]
    spec = draw_trial("1/s", 4, task="both", line_bins=(kd, kt), **SHORT)
    assert spec.disturbance.k.tolist() == kd and spec.target.k.tolist() == kt
    tr = simulate_trial(spec)
    for sig, k in ((tr.disturbance, kd), (tr.reference, kt)):
        P = np.abs(np.fft.rfft(sig)) ** 2
        assert set(np.flatnonzero(P > 1e-9 * P.max())) == set(k)
    assert retest(spec, 5).target.k.tolist() == kt
    assert "line_bins" not in draw_trial("1/s", 4, **SHORT).options     # default layout unchanged
    for bad, what in [(([3, 7], [7, 9]), "share line"), (([7, 3], [4, 9]), "increasing"),
                      (([3, 7], [4, 450]), "from 1 to 449"), ((3, 4), "got 3$"),
                      ((1, 2, 3), "pair")]:
        with pytest.raises(HesspipeError, match=what):
            draw_trial("1/s", 4, task="both", line_bins=bad, **SHORT)


def test_readable_by_hesspipe(tmp_path):
    from hesspipe.core.formats import read_run
    tr = simulate_trial(draw_trial("1/s", 6, task="both", **SHORT))
    path = write_trial(tmp_path, tr, style="plain")
    run = read_run(path)
    assert np.allclose(run.control, tr.control, rtol=1e-5)


@pytest.mark.parametrize("time_style", ["g9", "ms", "epoch_ms", "epoch_us"])
def test_readable_by_hesspipe_rounded_times(tmp_path, time_style):
    # Every logger style the generator draws must be accepted as it is written.
    from hesspipe.core.formats import read_run
    tr = simulate_trial(draw_trial("1/s", 6, **SHORT))
    path = write_trial(tmp_path, tr, style={"time": time_style, "bom": True, "newline": "\r\n",
                                            "epoch0": 1.7e9})
    run = read_run(path)
    assert len(run.time) == len(tr.time) and run.synthetic
    # ms stamps jitter by +-0.5 ms; the whole-record interval is still good to ~1e-7.
    assert abs(run.dt / (tr.time[1] - tr.time[0]) - 1) < 1e-6


@pytest.mark.parametrize("style", [{}, {"sep": "\t", "encoding": "utf-16"},
                                   {"sep": ",", "decimal": ",", "degrees": True}, "DAQ"])
def test_a_laboratorys_own_files_read_back_as_the_trial(tmp_path, style):
    # The LAB style (semicolons, decimal commas, degrees, CRLF, Windows-1252, the lab's own
    # names) and variations of it; a separator that is also the decimal mark is refused.
    # DAQ: metadata above the header, a units row, clock times across midnight, two
    # frames written twice.
    from hesspipe.core.errors import HesspipeError
    from hesspipe.core.formats import read_run
    from hesspipe.humanlike.writer import DAQ, LAB

    tr = simulate_trial(draw_trial("1/s", 6, **SHORT))
    st = {**DAQ, "repeat": (10, len(tr.time) // 2), "clock0": 86395.0} if style == "DAQ" else {**LAB, **style}
    if st["sep"] == st["decimal"]:
        with pytest.raises(HesspipeError, match="fields 'sep' and 'decimal'"):
            write_trial(tmp_path, tr, style=st)
        return
    path = write_trial(tmp_path, tr, style=st)
    run = read_run(path, columns=",".join(f"{r}={LAB['names'][r]}" for r in ("reference", "disturbance",
                                                                           "output", "control")))
    assert run.synthetic and len(run.time) == len(tr.time)
    assert run.dt == pytest.approx(tr.time[1] - tr.time[0], rel=1e-6)
    for name in ("reference", "disturbance", "output", "control"):
        want = getattr(tr, name)
        assert np.allclose(getattr(run, name), want, rtol=0, atol=1e-6 * (1 + np.abs(want).max())), name
    if style == "DAQ":
        said = " | ".join(run.notes)
        for words in ("3 line(s) above the header", "as the columns' units", "clock times",
                      "dropped 2 row(s) repeating", "tab-separated with decimal commas"):
            assert words in said, said


@pytest.mark.parametrize("output", ["rate", "angle"])
def test_motion_feedback_is_simulated_as_reported(output, tmp_path):
    spec = draw_trial("roll", 9, task="both", pilot="hess", effects=("motion_feedback",),
                      output=output, remnant_share=0.0, T_m=15.0)
    assert spec.pilot["Km"] != 0 and spec.motion_tf is not None
    tr = simulate_trial(spec)
    t = tr.truth
    U, E = np.fft.fft(tr.control), np.fft.fft(tr.reference - tr.output)
    df = t["describing_function"]
    H = np.array(df["re"]) + 1j * np.array(df["im"])
    sets = np.array(df["line_set"])
    k = spec.disturbance.k
    # Relative to the size of the two paths, |A| + |B|: where the visual and vestibular
    # parts nearly cancel (|A + B| a tenth of each, as at one line of this angle draw) a
    # 1 % fine-step error of each part is 10 % of their sum.
    from hesspipe.humanlike.pilots import parts
    a, b = parts(spec.pilot, spec.disturbance.w, spec.motion_tf)
    assert np.max(np.abs(U[k] / E[k] - H[sets == "disturbance"]) / (np.abs(a) + np.abs(b))) < 0.03
    tl = t["target_lines_u_over_e"]
    kt = spec.target.k
    ue = np.array(tl["re"]) + 1j * np.array(tl["im"])
    assert np.max(np.abs(U[kt] / E[kt] / ue - 1)) < 0.03
    # With motion the two differ: the vestibular path is closed through the plant.
    assert np.max(np.abs(ue / H[sets == "target"] - 1)) > 0.05
    write_trial(tmp_path, tr)
    plants = json.loads((tmp_path / "plants.json").read_text())
    assert ("motion_path" in plants) == (output == "angle")
    if output == "angle":
        assert plants["motion_path"] == {"num": [1.0, 0.0], "den": [0.01, 1.0]}


@pytest.mark.parametrize("plant", ["1/s", "K/s2"])
def test_precision_pilot_with_motion_is_simulated_as_reported(plant):
    # The multimodal pilot (McRuer's visual path, its own canals): fine-step simulation
    # against the truth's analytic parts, at both line sets.
    spec = draw_trial(plant, 1, task="both", pilot="precision", effects=("motion_feedback",),
                      output="angle", remnant_share=0.0, tau_m=0.15, T_m=15.0)
    p = spec.pilot
    assert p["Km"] > 0 and p["tau_m"] == 0.15
    m = loop_metrics(lambda w: sum(spec.pilot_parts(w)) * spec.yc_effective(w))
    assert 1.5 <= m["frequency_rad_s"] <= 4.0 and 20 <= m["phase_margin_deg"] <= 60
    tr = simulate_trial(spec)
    U, E = np.fft.fft(tr.control), np.fft.fft(tr.reference - tr.output)
    from hesspipe.humanlike.pilots import parts
    a, b = parts(p, spec.disturbance.w, spec.motion_tf)
    k = spec.disturbance.k
    assert np.max(np.abs(U[k] / E[k] - (a + b)) / (np.abs(a) + np.abs(b))) < 0.03
    tl = tr.truth["target_lines_u_over_e"]
    ue = np.array(tl["re"]) + 1j * np.array(tl["im"])
    kt = spec.target.k
    assert np.max(np.abs(U[kt] / E[kt] / ue - 1)) < 0.03
    # The cab's motion supplies lead: on K/s2 the visual lead is less than without it.
    if plant == "K/s2":
        static = draw_trial(plant, 1, task="both", pilot="precision", output="angle", T_m=15.0)
        assert p["TL"] < static.pilot["TL"]


def test_effects_are_in_the_truth():
    base = draw_trial("roll", 5, pilot="hess", **SHORT)
    spec = draw_trial("roll", 5, pilot="hess", effects=("extra_delay", "actuator_lag",
                                                         "rate_limit", "remnant"), **SHORT)
    tr = simulate_trial(spec)
    t = tr.truth
    assert 0.04 <= t["pilot"]["extra_delay"] <= 0.10
    assert t["pilot"]["tau_realised"] == pytest.approx(t["pilot"]["tau_v"] + t["pilot"]["extra_delay"],
                                                       abs=1.0 / 2400)
    assert 0.05 <= t["actuator"]["tau_s"] <= 0.15
    assert 0.0 < t["actuator"]["rate_limited_fraction"] < 0.5
    assert 0.40 <= t["remnant"]["share_drawn"] <= 0.60 and base.remnant["share"] <= 0.40
    # The plants file leaves the actuator out: the nominal loop crosses elsewhere.
    assert t["crossover"]["frequency_rad_s"] != pytest.approx(
        t["crossover_nominal_plant"]["frequency_rad_s"], rel=0.02)


def test_no_drawn_hess_pilot_has_a_stiffer_inner_loop_than_a_human():
    # Paper plants, roll rate, vestibular delay 0.15 s: this draw's visual and vestibular
    # paths nearly cancelled at crossover, K1*K2 came out ~150 and the loop diverged.
    from hesspipe.core.seeds import derive_seed
    from hesspipe.humanlike.pilots import PF_GAIN_MAX

    s = derive_seed(2, "bench-diagnose", "paper", "rate", "both", "motion_feedback")
    spec = draw_trial("paper", s, task="both", pilot="hess", effects=("motion_feedback",), fs=50.0,
                      T_m=70.0, output="rate", disturbance="wind", tau_m=0.15)
    assert spec.pilot["K1"] * spec.pilot["K2"] <= PF_GAIN_MAX
    trial = simulate_trial(spec, fine_ratio=10)
    assert np.all(np.isfinite(trial.control))


def test_pursuit_feedforward():
    # A pursuit display's feedforward on the target (option `feedforward`): at the target
    # lines U/R = (H + F) / (1 + H Yc), F = Kff Yc^-1 Y_NM / (1 + 0.2 s)^2 e^(-tau s);
    # without remnant it halves the error at the lowest line (0.84 rad/s); nearer crossover
    # its delay and lag make it add error, as a human's does on an unpredictable target.
    pilot = {"structure": "precision", "tau": 0.2, "wn": 12.0, "zn": 0.3, "TL": 0.0,
             "TI": 0.0, "Kp": 3.0}
    kw = dict(task="tracking", pilot_params=pilot, remnant_share=0.0, **SHORT)
    plain, ff = (simulate_trial(draw_trial("1/s", 5, feedforward=kff, **kw)) for kff in (0.0, 1.0))
    assert "feedforward" not in draw_trial("1/s", 5, **kw).options     # default draws unchanged
    k = draw_trial("1/s", 5, **kw).target.k
    w = 2 * np.pi * k / SHORT["T_m"]
    s = 1j * w
    nm = 144.0 / (s * s + 2 * 0.3 * 12.0 * s + 144.0)
    h, f = 3.0 * nm * np.exp(-0.2 * s), s * nm / (1 + 0.2 * s) ** 2 * np.exp(-0.2 * s)
    U, R = np.fft.fft(ff.control), np.fft.fft(ff.reference)
    assert np.max(np.abs(U[k] / R[k] / ((h + f) / (1 + h / s)) - 1)) < 0.05
    err = [abs(np.fft.fft(t.reference - t.output)[k[0]]) for t in (plain, ff)]
    assert err[1] < 0.6 * err[0]
    for bad, what in [(dict(feedforward=2.0), r"feedforward: expected a gain in \(0, 1.5\]"),
                      (dict(feedforward=0.5, task="disturbance"), "needs a precision pilot and a target")]:
        with pytest.raises(HesspipeError, match=what):
            draw_trial("1/s", 5, **{**kw, **bad})


def test_pursuit_feedforward_with_its_own_delay():
    # Option `ff_delay`: the feedforward F of test_pursuit_feedforward delayed by ff_delay, not
    # by the visual delay (0.3 s here): U/R's phase at the target lines follows e^(-ff_delay s).
    pilot = {"structure": "precision", "tau": 0.3, "wn": 12.0, "zn": 0.3, "TL": 0.0,
             "TI": 0.0, "Kp": 2.0}
    kw = dict(task="tracking", pilot_params=pilot, remnant_share=0.0, feedforward=1.0, **SHORT)
    assert "ff_delay" not in draw_trial("1/s", 5, **kw).options     # stored only when given
    for ff_delay in (0.05, 0.0):    # 0: no buffer
        tr = simulate_trial(draw_trial("1/s", 5, ff_delay=ff_delay, **kw))
        assert tr.spec.options["ff_delay"] == ff_delay
        assert tr.truth["pilot"]["tau_ff_realised"] == pytest.approx(ff_delay, abs=1e-12)
        k = tr.spec.target.k
        s = 1j * 2 * np.pi * k / SHORT["T_m"]
        nm = 144.0 / (s * s + 2 * 0.3 * 12.0 * s + 144.0)
        h = 2.0 * nm * np.exp(-0.3 * s)
        ur = np.fft.fft(tr.control)[k] / np.fft.fft(tr.reference)[k]

        def model(tau_ff):
            return (h + s * nm / (1 + 0.2 * s) ** 2 * np.exp(-tau_ff * s)) / (1 + h / s)

        assert np.max(np.abs(ur / model(ff_delay) - 1)) < 0.05
        assert np.max(np.abs(np.degrees(np.angle(ur / model(0.3))))) > 20.0   # not the visual delay's
    for bad, what in [(dict(feedforward=0.0), r"ff_delay: expected a feedforward to delay .* got ff_delay=0.05"),
                      (dict(ff_delay=1.5), r"ff_delay: expected a delay in \[0, 1\] s, got 1.5"),
                      (dict(ff_delay=-0.1), r"ff_delay: expected a delay in \[0, 1\] s"),
                      (dict(ff_delay=True), r"ff_delay: expected a delay in \[0, 1\] s, got True")]:
        with pytest.raises(HesspipeError, match=what):
            draw_trial("1/s", 5, **{**kw, "ff_delay": 0.05, **bad})


def test_indifference_threshold():
    # A pilot without equalisation on 1/s and no remnant, as test_gain_drift: what the dead
    # zone does is all there is off the lines.
    pilot = {"structure": "precision", "tau": 0.2, "wn": 12.0, "zn": 0.3, "TL": 0.0,
             "TI": 0.0, "Kp": 3.0}
    kw = dict(task="disturbance", pilot_params=pilot, remnant_share=0.0, T_m=45.0, run_in=10.0)
    steady = simulate_trial(draw_trial("1/s", 2, **kw))
    assert "threshold" not in steady.truth and "threshold" not in draw_trial("1/s", 2, **kw).options
    # A vanishing dead zone is the linear loop, through the step-by-step path.
    tiny = simulate_trial(draw_trial("1/s", 2, threshold=1e-9, **kw))
    np.testing.assert_allclose(tiny.control, steady.control, atol=1e-6 * np.std(steady.control))
    spec = draw_trial("1/s", 2, threshold=0.3, **kw)
    tr = simulate_trial(spec)
    th = tr.truth["threshold"]
    sigma = np.std(steady.reference - steady.output)
    assert th["half_width"] == pytest.approx(0.3 * sigma, rel=1e-9)
    assert th["gaussian_gain"] == pytest.approx(0.7642, abs=1e-4)
    assert np.array_equal(tr.control, simulate_trial(spec).control)     # deterministic
    k = spec.disturbance.k
    E = np.fft.rfft(tr.reference - tr.output)
    U = np.fft.rfft(tr.control)
    U0, E0 = np.fft.rfft(steady.control), np.fft.rfft(steady.reference - steady.output)
    # At the lines the pilot's gain falls about as the random-input describing function of
    # a dead zone says (the multisine error is near-Gaussian); off them its distortion.
    ratio = np.median(np.abs(U[k] / E[k]) / np.abs(U0[k] / E0[k]))
    assert 0.65 < ratio < 0.9, ratio
    off = np.ones(U.size, dtype=bool)
    off[k] = off[0] = False
    assert np.sum(np.abs(U[off]) ** 2) / np.sum(np.abs(U[1:]) ** 2) > 0.01
    assert np.sum(np.abs(U0[off]) ** 2) / np.sum(np.abs(U0[1:]) ** 2) < 1e-4
    assert retest(spec, 7).options["threshold"] == 0.3
    for bad in (1.0, -0.1, True):
        with pytest.raises(HesspipeError, match="^threshold: expected a share of the error's RMS"):
            draw_trial("1/s", 2, threshold=bad, **kw)


def test_logged_run_in_is_the_trial_before_its_window():
    # A lab's logger writes the whole trial: the run-in's end, then the measurement window
    # sample for sample as without it; only when asked (default draws stay as they were).
    window = simulate_trial(draw_trial("1/s", 6, task="both", **SHORT))
    spec = draw_trial("1/s", 6, task="both", logged_run_in=2.5, **SHORT)
    whole = simulate_trial(spec)
    keep = 150   # 2.5 s at 60 Hz
    assert whole.time.size == window.time.size + keep and whole.time[0] == 0.0
    assert np.allclose(np.diff(whole.time), 1 / 60.0)
    for name in ("disturbance", "reference", "output", "control", "gain_factor"):
        np.testing.assert_array_equal(getattr(whole, name)[keep:], getattr(window, name))
    # The run-in is the loop before the window, not a copy of it (the forcing repeats, the
    # remnant does not).
    assert not np.allclose(whole.control[:keep], window.control[-keep:])
    assert whole.truth["pilot"] == window.truth["pilot"]
    assert "logged_run_in" not in draw_trial("1/s", 6, **SHORT).options
    for bad in (-1.0, 10.5, 1 / 120):
        with pytest.raises(HesspipeError, match="logged_run_in: expected a whole number of samples"):
            draw_trial("1/s", 6, logged_run_in=bad, **SHORT)
    # And the logger running on while the forcing fades out: the window is still the same.
    both = simulate_trial(draw_trial("1/s", 6, task="both", logged_run_in=2.5, logged_run_out=2.0, **SHORT))
    assert both.time.size == window.time.size + keep + 120
    for name in ("disturbance", "reference", "output", "control"):
        np.testing.assert_array_equal(getattr(both, name)[keep:keep + window.time.size], getattr(window, name))
    rms = np.std(window.disturbance)
    assert abs(both.disturbance[-1]) < 1e-3 * rms and np.std(both.disturbance[-120:-100]) > 0.3 * rms
    for bad in (-1.0, 1 / 120):
        with pytest.raises(HesspipeError, match="logged_run_out: expected a whole number of samples"):
            draw_trial("1/s", 6, logged_run_out=bad, **SHORT)


def test_polymul_is_numpys():
    from hesspipe.humanlike.lti import polymul

    rng = np.random.default_rng(0)
    cases = [([0, 0, 1.0, 2], [3.0, 0]), ([0.0, 0], [1.0, 2]), ([1, 2], [0, 3]), ([], [1.0]),
             ([5.0], [0.0, 0.0, 1.0])] + [(rng.normal(size=rng.integers(1, 6)), rng.normal(size=3))
                                        for _ in range(20)]
    for a, b in cases:
        got, want = polymul(a, b), np.polymul(a, b)
        assert got.dtype == want.dtype and np.array_equal(got, want), (a, b)
