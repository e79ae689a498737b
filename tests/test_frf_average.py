"""Repeated runs averaged into one describing function (SYNTHETIC: hesspipe.humanlike trials).

The runs come from the independent generator (fine-step block simulation, sharing no model
code with identification), and the truth is the generator's own describing function of the
drawn pilot at the lines, never the estimate under test.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from hesspipe.cli import main
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import Run
from hesspipe.humanlike import draw_trial, retest, simulate_trial, write_trial
from hesspipe.identification.frf import estimate_frf
from hesspipe.identification.frf_average import average_frf

N_RUNS = 6


def _run(spec, name):
    tr = simulate_trial(spec, fine_ratio=10)
    return Run(time=tr.time, disturbance=tr.disturbance, output=tr.output, control=tr.control,
               reference=tr.reference, id=name, synthetic=True), tr.truth


@pytest.fixture(scope="module")
def repeats():
    """Six runs of one pilot (roll rate, target and disturbance) that differ by their remnant
    alone, its share raised to 40 % of the control power, and the truth at the lines."""
    spec = draw_trial("roll", 5, task="both", pilot="hess", fs=50.0, T_m=70.0, output="rate",
                      remnant_share=0.4)
    out = [_run(dataclasses.replace(spec, remnant={**spec.remnant, "noise_seed": 1000 + j}), f"r{j}")
           for j in range(N_RUNS)]
    truth = out[0][1]["describing_function"]
    true_h = dict(zip(np.round(truth["frequency_rad_s"], 6),
                      np.asarray(truth["re"]) + 1j * np.asarray(truth["im"])))
    return spec, [r for r, _ in out], true_h


def _errors(resp, true_h):
    t = np.array([true_h[w] for w in np.round(resp.freq_rad_s, 6)])
    return np.abs(resp.H - t) / np.abs(t), np.abs(resp.H - t) / resp.sigma


def test_averaging_runs_brings_the_describing_function_to_the_truth(repeats):
    _, runs, true_h = repeats
    single = np.array([_errors(estimate_frf(r).feedback, true_h)[0] for r in runs])
    avg = average_frf(runs)
    rel, z = _errors(avg.feedback, true_h)
    # Six runs: each line's squared error falls by about 6 on average; at least by 2 at the
    # median line (one run alone: about 1).
    assert np.median(rel ** 2 / np.mean(single ** 2, axis=0)) < 0.5
    # The stated errors hold the scatter: |z|^2 is exponential with mean 1 for calibrated
    # errors (widened by the runs' own scatter, so at most about 1).
    assert 0.1 < np.mean(z ** 2) < 2.5
    ref_rel, _ = _errors(avg.reference, true_h)
    single_ref = np.array([_errors(estimate_frf(r).reference, true_h)[0] for r in runs])
    assert np.median(ref_rel ** 2 / np.mean(single_ref ** 2, axis=0)) < 0.5
    assert avg.repeats["runs"] == N_RUNS and avg.run_id == "+".join(f"r{j}" for j in range(N_RUNS))
    assert 0.3 < avg.repeats["feedback"] < 2.0            # runs that differ by remnant alone


def test_runs_that_scatter_more_than_their_remnant_widen_the_errors(repeats):
    spec, runs, _ = repeats
    same = average_frf(runs[:3])
    moved = [_run(retest(spec, 50 + j, effects=()), f"t{j}")[0] for j in range(2)]
    scattered = average_frf(runs[:1] + moved)
    assert scattered.repeats["feedback"] > 1.5 * same.repeats["feedback"]
    assert "Birge" in " ".join(scattered.notes)


def test_runs_of_other_lengths_or_without_lines_are_refused_by_name(repeats):
    _, runs, _ = repeats
    short = dataclasses.replace(runs[1], id="short", time=runs[1].time[:2000],
                                disturbance=runs[1].disturbance[:2000], output=runs[1].output[:2000],
                                control=runs[1].control[:2000], reference=runs[1].reference[:2000])
    with pytest.raises(HesspipeError, match="^short: .* samples .* expected .* like r0"):
        average_frf([runs[0], short])
    rng = np.random.default_rng(3)
    noisy = dataclasses.replace(runs[2], id="broadband", disturbance=rng.standard_normal(runs[2].time.size),
                                reference=np.zeros(runs[2].time.size))
    with pytest.raises(HesspipeError, match="^broadband: no multisine lines"):
        average_frf([runs[0], noisy])
    with pytest.raises(HesspipeError, match="at least one run"):
        average_frf([])
    with pytest.raises(HesspipeError, match="^r1: the same record as r1; expected distinct"):
        average_frf([runs[0], runs[1], runs[1]])


def test_identify_and_frf_take_repeated_runs_from_files(tmp_path, repeats, capsys):
    spec, _, _ = repeats
    paths = [str(write_trial(tmp_path / f"r{j}", simulate_trial(
        dataclasses.replace(spec, remnant={**spec.remnant, "noise_seed": 2000 + j}), fine_ratio=10)))
        for j in range(3)]
    plants = str(tmp_path / "r0" / "plants.json")
    out = tmp_path / "frf.json"
    assert main(["frf", *paths, "--plants", plants, "--json", str(out)]) == 0
    assert "averaged over 3 run(s)" in capsys.readouterr().out
    # The same runs as a lab writes them (semicolons, decimal commas): what reading did is
    # said once for the three files, not once per file.
    lab = []
    for j, path in enumerate(paths):
        text = Path(path).read_text(encoding="utf-8-sig").splitlines()
        rows = [r if r.startswith("#") else r.replace(",", ";").replace(".", ",") for r in text]
        lab.append(tmp_path / f"lab{j}.csv")
        lab[-1].write_text("\n".join(rows) + "\n")
    assert main(["frf", *map(str, lab), "--plants", plants]) == 0
    notes = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("hesspipe: note:")]
    assert notes == [f"hesspipe: note: 3 files ({lab[0]} … {lab[2]}): semicolon-separated with decimal commas"]
    obj = json.loads(out.read_text())
    assert obj["repeats"]["runs"] == 3 and obj["run"] == paths
    ident = tmp_path / "ident.json"
    assert main(["identify", *paths, "--plants", plants, "--model", "expanded", "--no-benchmark",
                 "--json", str(ident)]) == 0
    assert json.loads(ident.read_text())["run"] == paths
    capsys.readouterr()
    assert main(["identify", *paths[:2], "--plants", plants, "--criterion", "paper"]) == 1
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "--criterion: 2 runs" in err and "'df'" in err
