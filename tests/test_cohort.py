"""Synthetic cohort: parameters around Table 1, truth beside each run, all labelled synthetic."""

from __future__ import annotations

import dataclasses
import json

import control as ct
import numpy as np
import pytest

from hesspipe.cli import main
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import Plants, plants_coefficients, read_run, write_plants
from hesspipe.core.paper import EQ14, EQ16
from hesspipe.identification.spectra import psd
from hesspipe.pilot.crossover import gain_scale
from hesspipe.pilot.hess import PilotModel, table1
from hesspipe.pilot.motion import paper_motion_path
from hesspipe.pilots import cohort as cohort_mod
from hesspipe.pilots.cohort import CohortSpec, disturbance, draw_parameters, pilot_ids, synth_cohort

SHORT = CohortSpec(duration_s=24.0)  # 1200 samples at 50 Hz: one spectral segment and a bit


def paper_plants() -> Plants:
    return Plants(ct.tf(*EQ14), ct.tf(*EQ16))


def test_cohort_files_truth_and_labels(tmp_path):
    out = tmp_path / "cohort"
    paths = synth_cohort(paper_plants(), 3, 11, ["motion_feedback"], out, spec=SHORT)
    assert [p.name for p in paths] == ["pilot01.csv", "pilot02.csv", "pilot03.csv"]
    assert sorted(p.name for p in out.iterdir()) == sorted(
        [".hesspipe-output", "cohort.json"] + [f"pilot0{i}.{ext}" for i in (1, 2, 3) for ext in ("csv", "truth.json")])
    for path in paths:
        run = read_run(path, min_samples=1024)
        assert run.synthetic and len(run) == 1200 and run.dt == pytest.approx(0.02)
        truth = json.loads(path.with_name(f"{run.id}.truth.json").read_text())
        assert truth["synthetic"] is True and truth["id"] == run.id and truth["base_seed"] == 11
        assert truth["effects"] == ["motion_feedback", "remnant"]
        lo, hi = SHORT.km_range
        g = gain_scale(paper_plants())
        assert truth["gain_scale"] == pytest.approx(g)
        assert g * lo <= truth["parameters"]["Km"] <= g * hi
        assert np.all(np.isfinite(run.control)) and np.std(run.control) > 0
        np.testing.assert_allclose(run.disturbance, disturbance(SHORT, truth["seeds"]["gust"])[1], atol=1e-8)
    summary = json.loads((out / "cohort.json").read_text())
    assert summary["synthetic"] is True and summary["note"].startswith("SYNTHETIC DATA")
    assert summary["plants"] == plants_coefficients(paper_plants()) and "motion_path" not in summary["plants"]


def test_cohort_records_the_plants_motion_path_it_was_drawn_with(tmp_path):
    # The cohort's motion pilots feel the cab through the plants' motion path, so the
    # cohort's record of its plants carries it (one record for every output: formats).
    plants = dataclasses.replace(paper_plants(), motion_path=paper_motion_path())
    synth_cohort(plants, 1, 11, ["motion_feedback"], tmp_path, spec=SHORT)
    record = json.loads((tmp_path / "cohort.json").read_text())["plants"]
    assert record["motion_path"] == plants_coefficients(plants)["motion_path"]


def test_same_seed_same_bytes_and_pilot_independent_of_cohort_size(tmp_path):
    a = synth_cohort(paper_plants(), 2, 5, ["motion_feedback"], tmp_path / "a", spec=SHORT)
    b = synth_cohort(paper_plants(), 3, 5, ["motion_feedback"], tmp_path / "b", spec=SHORT)
    c = synth_cohort(paper_plants(), 1, 6, ["motion_feedback"], tmp_path / "c", spec=SHORT)
    assert a[0].read_bytes() == b[0].read_bytes() and a[1].read_bytes() == b[1].read_bytes()
    assert a[0].read_bytes() != c[0].read_bytes()
    assert pilot_ids(3) == ["pilot01", "pilot02", "pilot03"] and pilot_ids(100)[0] == "pilot001"


def test_no_motion_feedback_means_no_km(tmp_path):
    paths = synth_cohort(paper_plants(), 1, 7, [], tmp_path / "c", spec=SHORT)
    truth = json.loads(paths[0].with_name("pilot01.truth.json").read_text())
    assert truth["effects"] == ["remnant"] and "Km" not in truth["parameters"]
    with_mf = synth_cohort(paper_plants(), 1, 7, ["motion_feedback"], tmp_path / "d", spec=SHORT)
    truth_mf = json.loads(with_mf[0].with_name("pilot01.truth.json").read_text())
    # The same seed gives the same core pilot whether or not motion feedback is added (when the
    # first draw is stable with both; an unstable draw is redrawn).
    assert truth["draws"] == truth_mf["draws"] == 1
    for name in ("Ke", "K1", "K2", "tau0", "wn"):
        assert truth["parameters"][name] == truth_mf["parameters"][name]
    # The remnant's share of control power is the same; its gain Kn follows each loop.
    assert truth["remnant_share"] == truth_mf["remnant_share"]


def test_parameter_distributions_stay_in_the_search_box_around_table1():
    model = PilotModel(("motion_feedback", "remnant"))
    rng = np.random.default_rng(0)
    draws = [draw_parameters(model, rng, CohortSpec(tau0_spread=0.15, wn_spread=0.1)) for _ in range(400)]
    bounds = model.bounds()
    for name in ("Ke", "K1", "K2", "tau0", "wn", "Km"):
        x = np.array([d[name] for d in draws])
        assert np.all((x >= bounds[name][0]) & (x <= bounds[name][1])), name
        assert np.std(x) > 0, name
    t1 = table1(1)
    for name in ("K1", "K2", "tau0", "wn"):  # not truncated in practice: median at Table 1
        assert np.median([d[name] for d in draws]) == pytest.approx(t1[name], rel=0.1), name
    ke = np.array([d["Ke"] for d in draws])  # gain scale 1: Yc = 1/s, Table 1's own plant
    assert np.median(ke) == pytest.approx(t1["Ke"], rel=0.1) and ke.max() <= bounds["Ke"][1]
    assert all(d["zn"] == t1["zn"] and d["1/T1"] == t1["1/T1"] for d in draws)
    # Default: only what the identification frees varies (tau0, wn at Table 1).
    default = draw_parameters(model, np.random.default_rng(1))
    assert default["tau0"] == t1["tau0"] and default["wn"] == t1["wn"] and default["Ke"] != t1["Ke"]


def test_disturbance_excites_the_fitness_band():
    t, w = disturbance(CohortSpec(), seed=3)
    assert len(t) == 3500
    side = CohortSpec().side_wind(t, 70.0)[1]
    assert np.max(np.abs(side)) == pytest.approx(17.3, abs=0.5)
    f, p = psd(w - side, 50.0)
    low = p[(f > 0.05) & (f < 0.5)].mean()
    high = p[(f > 4.0) & (f <= 5.0)].mean()
    assert high > 1e-3 * low  # gusts still present at 5 Hz (first-order roll-off from 1 Hz)


def test_failed_pilot_publishes_nothing(tmp_path, monkeypatch):
    real = cohort_mod.synth_pilot
    calls = []

    def flaky(plants, pid, seed, effects, spec):
        calls.append(pid)
        if len(calls) == 2:
            raise HesspipeError(f"synthetic run {pid}: the closed loop is unstable")
        return real(plants, pid, seed, effects, spec)

    monkeypatch.setattr(cohort_mod, "synth_pilot", flaky)
    with pytest.raises(HesspipeError, match="unstable"):
        synth_cohort(paper_plants(), 3, 1, ["motion_feedback"], tmp_path / "out", spec=SHORT)
    assert not (tmp_path / "out").exists()


def test_cli_synth_pilots(tmp_path, capsys):
    plants = write_plants(tmp_path / "plants.json", paper_plants())
    code = main(["synth-pilots", "--plants", str(plants), "--n", "2", "--seed", "3", "--duration", "21",
                 "--effects", "motion_feedback,extra_delay", "--out", str(tmp_path / "c")])
    out = capsys.readouterr().out
    assert code == 0 and out.startswith("SYNTHETIC DATA: wrote 2 synthetic pilot runs")
    truth = json.loads((tmp_path / "c" / "pilot02.truth.json").read_text())
    assert truth["effects"] == ["motion_feedback", "extra_delay", "remnant"]


@pytest.mark.parametrize("extra, words", [
    (["--effects", "motion,remnant"], "--effects: unknown effect 'motion'; expected one of"),
    (["--n", "0"], "--n: expected an integer >= 1, got 0"),
    (["--duration", "10"], "--duration 10 s at --dt 0.02 s is 500 samples; expected 1024 to"),
])
def test_cli_synth_pilots_errors(tmp_path, capsys, extra, words):
    plants = write_plants(tmp_path / "plants.json", paper_plants())
    argv = ["synth-pilots", "--plants", str(plants), "--n", "2", "--out", str(tmp_path / "c")]
    code = main(argv + extra)
    err = capsys.readouterr().err
    assert code == 1 and err.startswith("hesspipe: error: ") and words in err and err.count("\n") == 1
    assert not (tmp_path / "c").exists()


def test_hess_corner_follows_the_plant():
    from hesspipe.pilots.cohort import CORNER_RANGE, hess_corner

    # 1/s: the proprioceptive feedback is a constant (Table 1's corner, the box's floor)
    assert hess_corner(ct.tf([1], [1, 0])) == pytest.approx(CORNER_RANGE[0])
    # K/(s + a): the feedback K1 K2 s/(s + a) has the shape of s Yc: the corner is the plant's pole
    assert hess_corner(ct.tf([2.0], [1, 0.5])) == pytest.approx(0.5, rel=0.05)


def test_crossover_model_cohort_meets_the_limits_on_the_paper_and_a_slow_zero_plant(tmp_path):
    # The pilots' crossover, recomputed here with python-control's margin on a Padé-delay
    # loop (not hesspipe's loop code), is the drawn target and within 1-5 rad/s, 20-60 deg.
    from hesspipe.pilots.cohort import cohort_spec, synth_pilot

    slow_zero = Plants(ct.tf([0.5, -0.5 * 0.0064], [1.0, 1.07, 0.07]), paper_plants().disturbance_to_output)
    spec = cohort_spec("crossover_model", duration_s=24.0)
    for plants in (paper_plants(), slow_zero):
        for i in range(3):
            _, truth = synth_pilot(plants, f"p{i}", 100 + i, ("motion_feedback",), spec)
            p = truth["parameters"]
            assert truth["crossover"]["within_limits"]
            assert truth["crossover"]["frequency_rad_s"] == pytest.approx(truth["target_crossover_rad_s"], rel=1e-3)
            assert 1.5 <= truth["target_crossover_rad_s"] <= 4.0 and 0.05 <= p["tau0"] <= 0.5
            # Independent: the expanded loop built with python-control (SPEC.md's blocks, Padé
            # delay; default motion path = platform x washout), |L| and phase at the target.
            wn, zn = p["wn"], p["zn"]
            nm = ct.tf([wn ** 2], [1, 2 * zn * wn, wn ** 2])
            pf = ct.tf([p["K1"] * p["K2"], 0], [1, p["1/T1"]])
            delay = ct.tf(*ct.pade(p["tau0"], 8))
            canals = ct.tf([80 * 5.73, 0, 0], np.polymul([80, 1], [5.73, 1]))
            platform = ct.tf([31.4 ** 2], [1, 2 * 0.7 * 31.4, 31.4 ** 2])
            washout = ct.tf([1, 0, 0], [1, 2 * 1.02, 1.02 ** 2])
            yc = plants.control_to_output
            inner = ct.feedback(nm, pf + p["Km"] * canals * platform * washout * yc)
            loop = inner * p["Ke"] * delay * yc
            w = truth["target_crossover_rad_s"]
            mag = abs(ct.evalfr(loop, 1j * w))
            assert mag == pytest.approx(1.0, rel=0.02)
            pm = 180 + np.degrees(np.angle(ct.evalfr(loop, 1j * w)))
            assert pm == pytest.approx(truth["crossover"]["phase_margin_deg"], abs=1.5)
            assert 20 <= pm <= 60


def test_table1_draw_is_still_available():
    from hesspipe.pilots.cohort import cohort_spec

    assert cohort_spec("table1").crossover_rad_s is None
    with pytest.raises(HesspipeError, match="cohort"):
        cohort_spec("bogus")


def test_cli_synth_pilots_crossover_model_cohort(tmp_path, capsys):
    plants = tmp_path / "plants.json"
    write_plants(plants, paper_plants())
    out = tmp_path / "c"
    assert main(["synth-pilots", "--plants", str(plants), "--n", "2", "--duration", "24",
                 "--cohort", "crossover_model", "--out", str(out)]) == 0
    for pid in ("pilot01", "pilot02"):
        truth = json.loads((out / f"{pid}.truth.json").read_text())
        assert truth["crossover"]["within_limits"] and "target_crossover_rad_s" in truth
