"""Extra delay against the same pilot's baseline run (SYNTHETIC: hesspipe.humanlike trials).

The runs are drawn and simulated by the independent generator (fine-step block simulation;
it shares no model code with identification or diagnose) and read back from the files it
writes. The retest's pilot is the first trial's with the generator's run-to-run scatter.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from hesspipe.cli import main
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_plants, read_run
from hesspipe.core.seeds import derive_seed
from hesspipe.diagnose.motion import observed_delay_variance, paired_delay_test
from hesspipe.diagnose.settings import DiagnoseConfig
from hesspipe.diagnose.workflow import diagnose
from hesspipe.humanlike import draw_trial, retest, simulate_trial, write_trial
from humanlike_trials import repeated_trials


def _pair(folder, effect, seed, task="both"):
    """(run, baseline run, plants, true delay difference s) as benchmarks/bench_diagnose.py
    --paired draws them for roll-rate tracking (`task`: with disturbance and target, or
    "disturbance" alone)."""
    effects = () if effect == "none" else (effect,)
    s = derive_seed(seed, "bench-diagnose", "roll", "rate", task, effect)
    spec = draw_trial("roll", s, task=task, pilot="hess", effects=effects, fs=50.0, T_m=70.0,
                      output="rate", name="run")
    base = retest(spec, derive_seed(s, "baseline-run"), effects=(), name="base")
    runs = [read_run(write_trial(folder, simulate_trial(x))) for x in (spec, base)]
    return runs[0], runs[1], read_plants(folder / "plants.json"), spec.pilot["tau"] - base.pilot["tau"]


@pytest.fixture(scope="module")
def baseline_pair(tmp_path_factory):
    """(folder, run, baseline run, plants, true delay difference s): seed 100's pair without an
    extra delay; computed once: 3 tests read it (its files too; none writes into its folder)."""
    folder = tmp_path_factory.mktemp("pair_none_100")
    return (folder, *_pair(folder, "none", 100))


def test_retest_keeps_the_pilot_and_the_aircraft_and_draws_a_new_run():
    spec = draw_trial("roll", 7, task="both", pilot="hess", effects=("actuator_lag", "extra_delay"),
                      fs=50.0, T_m=70.0)
    again = retest(spec, 8, effects=())
    assert again.effects == ("actuator_lag",)
    assert again.actuator["tau"] == spec.actuator["tau"]
    assert again.pilot["extra_delay"] == 0.0
    assert abs(again.pilot["tau"] - spec.pilot["tau_v"]) < 0.06    # the scatter, not the extra
    assert 0.6 < again.pilot["Ke"] / spec.pilot["Ke"] < 1.6
    assert again.remnant["noise_seed"] != spec.remnant["noise_seed"]
    assert retest(spec, 8, effects=()).pilot == again.pilot           # seeded
    with pytest.raises(HesspipeError, match="pilot-side"):
        retest(spec, 8, effects=("dutch_roll",))
    # The logger too: a run-in and fade-out logged on the first run are logged on the second.
    logged = draw_trial("roll", 7, task="both", pilot="hess", effects=(), fs=50.0, T_m=70.0,
                        logged_run_in=5.0, logged_run_out=2.0)
    again = retest(logged, 8)
    assert {k: again.options[k] for k in ("run_in", "logged_run_in", "logged_run_out")} == {
        k: logged.options[k] for k in ("run_in", "logged_run_in", "logged_run_out")}


def test_extra_delay_is_named_against_the_baseline_run_and_not_without_one(tmp_path):
    run, base, plants, true_diff = _pair(tmp_path, "extra_delay", 102)
    alone = diagnose(run, plants)
    assert "extra_delay" not in alone.named_effects          # one record: one delay
    d = diagnose(run, plants, baseline_run=base)
    assert "extra_delay" in d.named_effects
    dv = d.delay_verdict
    assert dv["baseline_run"] and dv["p_value"] < dv["alpha"]
    assert abs(dv["difference_s"] - true_diff) < 0.03


def test_a_baseline_pair_names_no_extra_delay_and_the_cli_reports_the_pair(baseline_pair, tmp_path, capsys):
    folder, run, base, plants, true_diff = baseline_pair
    assert abs(true_diff) < 0.03                            # the pilot's scatter only
    out = tmp_path / "d.json"
    assert main(["diagnose", str(run.source), "--plants", str(folder / "plants.json"),
                 "--baseline-run", str(base.source), "--json", str(out)]) == 0
    assert "against the same pilot's baseline run" in capsys.readouterr().out
    dv = json.loads(out.read_text())["delay_verdict"]
    assert not dv["named"] and abs(dv["difference_s"] - true_diff) < 0.03


def test_a_baseline_run_without_forcing_lines_is_an_error_naming_it(baseline_pair):
    _, run, base, plants, _ = baseline_pair
    rng = np.random.default_rng(0)     # random forcing: no lines, no describing function
    noisy = replace(base, disturbance=rng.standard_normal(len(base)), reference=0.0 * base.reference)
    with pytest.raises(HesspipeError, match="baseline run"):
        diagnose(run, plants, baseline_run=noisy)


def _repeats(folder, effect, seed, n, task="disturbance"):
    """n runs of each condition, roll rate (tests/humanlike_trials.py), and the extra delay (s)."""
    cond, base, plants, spec = repeated_trials(folder, "roll", "rate", task, effect, seed, n, baselines=True)
    return cond, base, plants, spec.pilot["extra_delay"]


def test_repeated_runs_name_an_extra_delay_that_one_pair_cannot(tmp_path):
    # Development seed 100, roll rate, disturbance only: 0.054 s of extra delay; one pair
    # measures it but within the pilot's run-to-run spread (p = 0.02), three runs of each
    # condition shrink the spread by sqrt(3).
    cond, base, plants, extra = _repeats(tmp_path, "extra_delay", 100, 3)
    assert cond[1].source != cond[0].source and len(base) == 3
    one = diagnose(cond[0], plants, baseline_run=base[0], candidates=("extra_delay",)).delay_verdict
    assert not one["named"]
    out = tmp_path / "d.json"
    assert main(["diagnose", *(str(r.source) for r in cond), "--plants", str(tmp_path / "run" / "plants.json"),
                 "--baseline-run", *(str(b.source) for b in base), "--candidates", "extra_delay",
                 "--json", str(out)]) == 0
    d = json.loads(out.read_text())
    dv = d["delay_verdict"]
    assert "extra_delay" in d["named_effects"] and dv["runs"] == 3 and dv["baseline_runs"] == 3
    assert dv["spread_s"] == pytest.approx(DiagnoseConfig().retest_delay_sd / np.sqrt(3))
    assert abs(dv["difference_s"] - extra) < 0.03


def test_the_allowed_spread_shrinks_with_the_runs_of_each_condition():
    joint = {"difference_s": 0.03, "se_s": 0.0, "delay_s": 0.33, "baseline_delay_s": 0.30}
    one = paired_delay_test(joint, 0.02, 0.01)
    assert one["spread_s"] == pytest.approx(0.02) and not one["named"]            # z = 1.5
    many = paired_delay_test({**joint, "runs": 4, "baseline_runs": 4}, 0.02, 0.01)
    assert many["spread_s"] == pytest.approx(0.01) and many["named"]              # z = 3
    assert paired_delay_test({**joint, "runs": 1, "baseline_runs": 3}, 0.02, 0.01)["spread_s"] == \
        pytest.approx(0.02 * np.sqrt((1 + 1 / 3) / 2))


def test_a_difference_without_an_error_is_not_named():
    # A covariance that could not be computed (se NaN) is no evidence; read as zero it made
    # z grow without limit (any positive difference named).
    joint = {"difference_s": 0.2, "se_s": math.nan, "delay_s": 0.5, "baseline_delay_s": 0.3}
    t = paired_delay_test(joint, 0.02, 0.01)
    assert not t["named"] and math.isnan(t["p_value"]) and math.isnan(t["z"])
    # Three runs each whose own delays scatter: that spread weighs the difference instead.
    seen = paired_delay_test({**joint, "runs": 3, "baseline_runs": 3, "run_delays_s": [0.45, 0.5, 0.55],
                              "baseline_run_delays_s": [0.25, 0.3, 0.35]}, 0.02, 0.01)
    assert seen["named"] and math.isfinite(seen["p_value"])


def test_the_runs_own_delays_set_a_floor_under_the_spread():
    # Four runs each, tested difference 0.03 s: z = 3 on the allowed spread alone (above).
    # Runs whose own delays scatter by 0.04 s about their condition's mean show a spread of
    # the means' difference of 0.04 sqrt(1/4 + 1/4) = 0.028 s: z ~ 1, not named.
    tight = [0.33, 0.33, 0.33, 0.33], [0.30, 0.30, 0.30, 0.30]
    loose = [0.29, 0.37, 0.29, 0.37], [0.26, 0.34, 0.26, 0.34]
    base = {"difference_s": 0.03, "se_s": 0.0, "delay_s": 0.33, "baseline_delay_s": 0.30,
            "runs": 4, "baseline_runs": 4}
    t = paired_delay_test({**base, "run_delays_s": tight[0], "baseline_run_delays_s": tight[1]}, 0.02, 0.01)
    assert t["named"] and t["observed_spread_s"] == pytest.approx(0.0, abs=1e-12)
    lo = paired_delay_test({**base, "run_delays_s": loose[0], "baseline_run_delays_s": loose[1]}, 0.02, 0.01)
    sd = np.std(loose[0], ddof=1)
    assert lo["observed_spread_s"] == pytest.approx(sd * np.sqrt(0.5))
    assert not lo["named"] and lo["z"] == pytest.approx(0.03 / (sd * np.sqrt(0.5)))
    # One run each: nothing to see the runs' scatter in.
    assert observed_delay_variance({"run_delays_s": [0.3], "baseline_run_delays_s": [0.2]}) is None


def test_a_record_given_twice_or_another_forcing_is_refused_by_name(baseline_pair, capsys):
    folder, run, base, plants, _ = baseline_pair
    assert main(["diagnose", str(run.source), "--plants", str(folder / "plants.json"),
                 "--baseline-run", str(base.source), str(base.source)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "the same record as" in err and str(base.source) in err
    with pytest.raises(HesspipeError, match="the same record as"):
        diagnose(run, plants, repeat_runs=[run])
    cut = slice(0, len(base) - 500)
    short = replace(base, time=base.time[cut], disturbance=base.disturbance[cut], output=base.output[cut],
                    control=base.control[cut], reference=base.reference[cut])
    with pytest.raises(HesspipeError, match="samples at .* analysed; expected .* repeated runs of one forcing"):
        diagnose(run, plants, repeat_runs=[short])


def test_a_repeat_of_the_condition_keeps_the_simulators_extra_delay():
    spec = draw_trial("roll", 7, task="both", pilot="hess", effects=("extra_delay",), fs=50.0, T_m=70.0)
    again = retest(spec, 3)
    assert again.pilot["extra_delay"] == spec.pilot["extra_delay"] > 0
    assert again.pilot["tau_v"] != spec.pilot["tau_v"]                   # the pilot's scatter


def test_with_a_target_the_motion_test_keeps_to_the_diagnosed_run(tmp_path):
    # Both line sets give one run's test its power; pooled, the pilot's run-to-run scatter
    # of the shared dynamics became a misfit the vestibular path took (2 of 20 baseline sets
    # named motion on the report seeds). The delay test still takes every run.
    cond, base, plants, _ = _repeats(tmp_path, "none", 100, 2, task="both")
    d = diagnose(cond[0], plants, baseline_run=base, repeat_runs=cond[1:],
                 candidates=("motion_feedback", "extra_delay"))
    assert d.motion_verdict["runs"] == 1 and d.motion_verdict["forcing"] == "disturbance and target"
    assert d.delay_verdict["runs"] == 2 and d.delay_verdict["baseline_runs"] == 2
    assert not set(d.named_effects) & {"motion_feedback", "extra_delay"}


def test_a_known_pilot_delay_lets_one_record_name_the_simulators(tmp_path):
    # Development seed 101, paper angle with a target (benchmarks/bench_diagnose.py's draw):
    # pilot 0.302 s, simulator 0.044 s more. Within a human's longest (0.40 s) one record
    # cannot tell them apart; told the pilot's own delay (+ 0.03 s), the command names it.
    # The generator's display is compensatory and is stated: with "either" (display unknown)
    # the pursuit fit, whose feedforward has its own delay (at most the visual delay) since the
    # thirty-fifth revision, passes the display pretest (level 0.2) on this run and the
    # delay's p is 0.014 (0.0025).
    s = derive_seed(101, "bench-diagnose", "paper", "angle", "both", "extra_delay")
    spec = draw_trial("paper", s, task="both", pilot="hess", effects=("extra_delay",), output="angle",
                      disturbance="wind", fs=50.0, T_m=70.0, name="run")
    path = write_trial(tmp_path, simulate_trial(spec))
    plants = str(tmp_path / "plants.json")
    verdicts = []
    for extra in ([], ["--max-pilot-delay", f"{spec.pilot['tau_v'] + 0.03:.3f}"]):
        out = tmp_path / f"d{len(extra)}.json"
        assert main(["diagnose", str(path), "--plants", plants, "--candidates", "extra_delay",
                     "--display", "compensatory", "--json", str(out), *extra]) == 0
        verdicts.append(json.loads(out.read_text())["delay_verdict"])
    default, known = verdicts
    assert default["max_pilot_delay_s"] == DiagnoseConfig().max_pilot_delay and not default["named"]
    assert known["max_pilot_delay_s"] == pytest.approx(spec.pilot["tau_v"] + 0.03, abs=1e-3)
    assert known["named"] and known["p_value"] < known["alpha"]
    assert abs(known["delay_s"] - spec.pilot["tau"]) < 0.03


@pytest.mark.parametrize("value", ["-0.1", "0.1"])
def test_a_pilot_delay_below_the_motion_tests_floor_is_refused_naming_the_flag(capsys, value):
    # The describing-function fits hold the visual delay at or above MIN_VISUAL_DELAY (0.1 s):
    # a human's longest must lie above it.
    assert main(["diagnose", "run.csv", "--plants", "plants.json", "--max-pilot-delay", value]) != 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("hesspipe: error: --max-pilot-delay: expected a number > 0.1 ")


def test_a_delay_ending_on_its_bound_keeps_its_error(tmp_path, monkeypatch):
    # Roll rate, disturbance alone (bench_diagnose --paired's draw, seed 3): the joint fit's
    # delays trade with the neuromuscular mode and lie far below the truth's (0.39 and
    # 0.35 s). With the box's floor raised to 0.1 s the baseline's ends on it; held there,
    # its error was NaN, the test counted it as none and named a 0.06 s difference at
    # p = 0.0009 (p = 0.067 with the floor at 0).
    from hesspipe.identification import paired_delay as pd

    run, b, plants, _ = _pair(tmp_path, "extra_delay", 3, task="disturbance")
    monkeypatch.setattr(pd, "TAU0_BOX", (0.1, 0.6))
    d = diagnose(run, plants, baseline_run=b)
    dv = d.delay_verdict
    assert dv["baseline_delay_s"] == pytest.approx(0.1, abs=1e-6)      # on the bound
    assert np.isfinite(dv["se_s"]) and 0.01 < dv["se_s"] < 0.1
    assert dv["p_value"] > 0.01 and "extra_delay" not in d.named_effects
