"""Extra delay against the same pilot's baseline run (SYNTHETIC: hesspipe.humanlike trials).

The runs are drawn and simulated by the independent generator (fine-step block simulation;
it shares no model code with identification or diagnose) and read back from the files it
writes. The retest's pilot is the first trial's with the generator's run-to-run scatter.
"""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from hesspipe.cli import main
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_plants, read_run
from hesspipe.core.seeds import derive_seed
from hesspipe.diagnose.workflow import diagnose
from hesspipe.humanlike import draw_trial, retest, simulate_trial, write_trial


def _pair(folder, effect, seed):
    """(run, baseline run, plants, true delay difference s) as benchmarks/bench_diagnose.py
    --paired draws them for roll-rate tracking with disturbance and target."""
    effects = () if effect == "none" else (effect,)
    s = derive_seed(seed, "bench-diagnose", "roll", "rate", "both", effect)
    spec = draw_trial("roll", s, task="both", pilot="hess", effects=effects, fs=50.0, T_m=70.0,
                      output="rate", name="run")
    base = retest(spec, derive_seed(s, "baseline-run"), effects=(), name="base")
    runs = [read_run(write_trial(folder, simulate_trial(x))) for x in (spec, base)]
    return runs[0], runs[1], read_plants(folder / "plants.json"), spec.pilot["tau"] - base.pilot["tau"]


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


def test_extra_delay_is_named_against_the_baseline_run_and_not_without_one(tmp_path):
    run, base, plants, true_diff = _pair(tmp_path, "extra_delay", 102)
    alone = diagnose(run, plants)
    assert "extra_delay" not in alone.named_effects          # one record: one delay
    d = diagnose(run, plants, baseline_run=base)
    assert "extra_delay" in d.named_effects
    dv = d.delay_verdict
    assert dv["baseline_run"] and dv["p_value"] < dv["alpha"]
    assert abs(dv["difference_s"] - true_diff) < 0.03


def test_a_baseline_pair_names_no_extra_delay_and_the_cli_reports_the_pair(tmp_path, capsys):
    run, base, plants, true_diff = _pair(tmp_path, "none", 100)
    assert abs(true_diff) < 0.03                            # the pilot's scatter only
    out = tmp_path / "d.json"
    assert main(["diagnose", str(run.source), "--plants", str(tmp_path / "plants.json"),
                 "--baseline-run", str(base.source), "--json", str(out)]) == 0
    assert "against the same pilot's baseline run" in capsys.readouterr().out
    dv = json.loads(out.read_text())["delay_verdict"]
    assert not dv["named"] and abs(dv["difference_s"] - true_diff) < 0.03


def test_a_baseline_run_without_forcing_lines_is_an_error_naming_it(tmp_path):
    run, base, plants, _ = _pair(tmp_path, "none", 100)
    rng = np.random.default_rng(0)     # random forcing: no lines, no describing function
    noisy = replace(base, disturbance=rng.standard_normal(len(base)), reference=0.0 * base.reference)
    with pytest.raises(HesspipeError, match="baseline run"):
        diagnose(run, plants, baseline_run=noisy)
