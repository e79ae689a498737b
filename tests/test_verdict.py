"""Motion verdict (hesspipe.pilots.verdict) and target tracking, on SYNTHETIC data from the
independent generator hesspipe.humanlike (fine-step time-domain, no hesspipe pilot code)."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from hesspipe.cli import main
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_plants, read_run
from hesspipe.humanlike import draw_trial, make_trials, retest, simulate_trial, write_trial
from hesspipe.pilot.crossover import gain_scale
from hesspipe.pilot.hess import PilotModel
from hesspipe.pilots.compare import compare_pilots, read_runs
from hesspipe.pilots.results import PilotComparison
from hesspipe.pilots.verdict import cohort_verdict, forcing_lines, motion_test, pilot_groups, verdict_lines

FAST = dict(T_m=30.0, fs=50.0, style="plain")


def _tests(folder, effects, n, seed, **kw):
    paths = make_trials(folder, "roll", n, seed, pilot="hess", effects=effects, **FAST, **kw)
    plants = read_plants(folder / "plants.json")
    start = PilotModel().complete({}, 1, gain=gain_scale(plants, 1))
    return {p.stem: motion_test(read_run(p), plants, start) for p in paths}, plants, paths


def test_verdict_yes_for_motion_cohort_no_without(tmp_path):
    yes, _, _ = _tests(tmp_path / "m", ("motion_feedback",), 3, 1, km_ratio=(0.6, 1.0))
    no, _, _ = _tests(tmp_path / "n", (), 3, 1, task="both")
    v_yes, v_no = cohort_verdict(yes), cohort_verdict(no)
    assert {t["forcing"] for t in yes.values()} == {"disturbance only"}
    assert {t["forcing"] for t in no.values()} == {"disturbance and target"}
    assert all(t["available"] and t["n_lines"] >= 10 for t in {**yes, **no}.values())
    assert v_yes["answer"] == "yes" and v_yes["sentence"].startswith("yes: motion feedback")
    assert "on the model's shapes of the two paths alone for the 3 pilot(s)" in v_yes["sentence"]
    assert v_no["answer"] == "no" and v_no["sentence"].startswith("no: ")
    assert v_yes["majority_p"] < 0.01 < v_no["majority_p"]
    assert v_yes["n_significant"] >= 2 and v_no["n_significant"] <= 1
    assert v_yes["median_gain"] > v_no["median_gain"] + 0.1


def test_random_forcing_has_no_lines_and_an_undetermined_verdict(tmp_path):
    (folder := tmp_path / "m").mkdir()
    paths = make_trials(folder, "roll", 1, 3, pilot="hess", **FAST)
    run = read_run(paths[0])
    rng = np.random.default_rng(0)
    noisy = dataclasses.replace(run, disturbance=rng.standard_normal(len(run.control)))
    assert forcing_lines(noisy).size == 0
    t = motion_test(noisy, read_plants(folder / "plants.json"), PilotModel().complete({}))
    assert t["available"] is False and "forcing lines" in t["reason"]
    v = cohort_verdict({"a": t})
    assert v["answer"] == "undetermined" and "no pilot" in v["sentence"]


def _t(p, forcing="disturbance and target"):
    return {"available": True, "p_value": p, "lr": 1.0, "gain": 0.5, "Km": 1.0, "Km_se": 0.1,
            "significant": p < 0.01, "forcing": forcing}


@pytest.mark.parametrize("task", ["disturbance", "tracking"])
def test_one_forcing_function_cannot_rule_motion_out(tmp_path, task):
    """A cohort whose records have one line set is "cannot tell" unless the test finds motion,
    as diagnose says run by run: one describing function, the two paths on one signal."""
    no, _, _ = _tests(tmp_path / "n", (), 3, 2, task=task)
    kind = {"disturbance": "disturbance only", "tracking": "target only"}[task]
    assert {t["forcing"] for t in no.values()} == {kind}
    v = cohort_verdict(no)
    assert v["answer"] == "undetermined" and v["n_separable"] == 0, v["sentence"]
    assert v["sentence"].startswith(f"undetermined: cannot tell whether the pilots use motion: 3 of 3 "
                                    f"pilots' records have one forcing function ({kind})")
    assert v["per_pilot"][next(iter(no))]["forcing"] == kind
    assert all(f"(one forcing function, {kind})" in line for line in verdict_lines(v)[1:-1])


def test_a_tracking_cohort_logged_without_a_disturbance_through_the_command_line(tmp_path, capsys):
    """Files of a target-tracking task with no disturbance column (as its laboratory logs
    them) go through ``hesspipe pilots``: read as a task without a disturbance, and the
    verdict on one forcing function is "cannot tell"."""
    folder = tmp_path / "trk"
    paths = make_trials(folder, "roll", 3, 4, pilot="hess", task="tracking", **FAST)
    for path in paths:
        lines = path.read_text().splitlines()
        head = [line for line in lines if line.startswith("#")]
        rows = [line.split(",") for line in lines[len(head):]]
        keep = [i for i, name in enumerate(rows[0]) if name != "disturbance"]
        assert len(keep) == len(rows[0]) - 1
        path.write_text("\r\n".join(head + [",".join(r[i] for i in keep) for r in rows]) + "\r\n")
    out = tmp_path / "c.json"
    code = main(["pilots", str(folder), "--plants", str(folder / "plants.json"), "--workers", "1",
                 "--json", str(out)])
    text = capsys.readouterr()
    assert code == 0, text.err
    note = [line for line in text.err.splitlines() if "no disturbance column: a task without a disturbance" in line]
    assert len(note) == 1 and note[0].startswith("hesspipe: note: 3 files (")    # said once for the folder
    v = json.loads(out.read_text())["motion_verdict"]
    assert v["answer"] == "undetermined" and "(target only)" in v["sentence"]
    assert "MOTION VERDICT: undetermined: cannot tell" in text.out


def test_no_needs_half_of_the_pilots_to_have_both_line_sets():
    one, two = "disturbance only", "disturbance and target"
    assert cohort_verdict({"a": _t(0.5, one), "b": _t(0.7, two)})["answer"] == "no"       # r = 1 of 2
    assert cohort_verdict({"a": _t(0.5, one), "b": _t(0.7, one), "c": _t(0.9, two)})["answer"] == "undetermined"
    assert cohort_verdict({"a": _t(0.5, one), "b": _t(0.7, two), "c": _t(0.9, two)})["answer"] == "no"
    # "Yes" stands on one line set too, and says what it rests on.
    v = cohort_verdict({"a": _t(1e-6, one), "b": _t(1e-5, one), "c": _t(0.9, two)})
    assert v["answer"] == "yes" and "alone for the 2 pilot(s) with one forcing function" in v["sentence"]
    # A pilot's runs of different forcing count as one line set: not separable.
    g = cohort_verdict({"a1": _t(0.5, one), "a2": _t(0.6, two)}, groups={"a1": "a", "a2": "a"})
    assert g["answer"] == "undetermined" and g["per_pilot"]["a"]["forcing"] == f"{two} / {one}"


def test_cohort_counts_and_binomial():
    t = _t
    v = cohort_verdict({"a": t(0.001), "b": t(0.005), "c": t(0.5), "d": {"available": False}})
    assert v["n_tested"] == 3 and v["n_significant"] == 2
    assert v["binomial_p"] == pytest.approx(3 * 0.01 ** 2 * 0.99 + 0.01 ** 3)
    assert "2 of 3 pilots" in v["sentence"] and "1 pilot(s) without forcing lines" in v["sentence"]
    chi = -2 * np.log([0.001, 0.005, 0.5]).sum()
    assert v["fisher_p"] == pytest.approx(np.exp(-chi / 2) * sum((chi / 2) ** j / math.factorial(j)
                                                                 for j in range(3)))
    # The median pilot (r = 2 of 3) has p = 0.005: two or more of three uniform p-values at
    # or below it.
    assert v["majority_r"] == 2
    assert v["majority_p"] == pytest.approx(3 * 0.005 ** 2 * 0.995 + 0.005 ** 3)
    assert v["answer"] == "yes"
    assert cohort_verdict({"a": t(0.04), "b": t(0.6), "c": t(0.9)})["answer"] == "no"
    # The cohort's level is the motion test's: one pilot at p = 0.013 is a "no".
    assert cohort_verdict({"a": t(0.013)})["majority_p"] == pytest.approx(0.013)
    assert cohort_verdict({"a": t(0.013)})["answer"] == "no"


def test_one_atypical_pilot_does_not_decide_the_cohort():
    """Fisher's combination says "some pilot"; the verdict asks for at least half of them."""
    rest = [0.3, 0.45, 0.6, 0.8, 0.95, 1.0, 1.0]
    v = cohort_verdict({f"p{i}": _t(p) for i, p in enumerate([1e-9] + rest)})
    assert v["fisher_p"] < 0.01 < v["majority_p"]
    assert v["answer"] == "no" and "1 of 8 pilots" in v["sentence"]
    assert "some pilot's fit improves, not the typical pilot's" in v["sentence"]
    # Half of them strongly, the others not at all: yes (r = 4 of 8).
    v = cohort_verdict({f"p{i}": _t(p) for i, p in enumerate([1e-6] * 4 + [1.0] * 4)})
    assert v["answer"] == "yes" and v["majority_r"] == 4
    # Three of eight is not half: no, whatever their p-values.
    v = cohort_verdict({f"p{i}": _t(p) for i, p in enumerate([1e-12] * 3 + [0.5] * 5)})
    assert v["answer"] == "no" and v["fisher_p"] < 1e-20


def test_median_pilot_p_is_calibrated_under_the_null():
    """Uniform p-values: the median-pilot test rejects at most at its level."""
    from hesspipe.pilots.verdict import median_pilot_p
    rng = np.random.default_rng(5)
    for n in (1, 2, 5, 8):
        p = np.array([median_pilot_p(rng.random(n))[0] for _ in range(4000)])
        assert np.mean(p < 0.05) <= 0.05 + 3 * math.sqrt(0.05 * 0.95 / 4000)
    with pytest.raises(HesspipeError, match="at least one p-value"):
        median_pilot_p([])


def test_tracking_target_lines_drive_the_motion_test(tmp_path):
    """Task "both": target and disturbance on interleaved lines; e = r - y enters the test."""
    tests, plants, paths = _tests(tmp_path, ("motion_feedback",), 1, 4, task="both",
                                  km_ratio=(0.6, 1.0))
    (t,) = tests.values()
    truth = json.loads(paths[0].with_suffix(".truth.json").read_text())["pilot"]["Km"]
    assert t["available"] and t["n_lines"] >= 20 and t["p_value"] < 0.05
    assert 0.5 * truth < t["Km"] < 2.0 * truth
    run = read_run(paths[0])
    start = PilotModel().complete({}, 1, gain=gain_scale(plants, 1))
    blind = motion_test(dataclasses.replace(run, reference=np.zeros_like(run.reference)), plants, start)
    # Without the reference only the disturbance's lines are tested, and their Km is wrong.
    # (Whether that one set is significant depends on the model's shapes alone: with the
    # generator's output-equivalent disturbance it can be, so p is not asserted.)
    assert blind["n_lines"] < t["n_lines"]
    assert not 0.5 * truth < blind["Km"] < 2.0 * truth


def test_identify_uses_the_reference_of_a_tracking_trial(tmp_path):
    from hesspipe.identification.fit import identify

    paths = make_trials(tmp_path, "roll", 1, 5, task="tracking", pilot="hess", **FAST)
    run, plants = read_run(paths[0]), read_plants(tmp_path / "plants.json")
    kw = dict(optimizer="scipy", passes=3, with_benchmark=False, with_identifiability=False)
    with_r = identify(run, plants, "original", **kw)
    without = identify(dataclasses.replace(run, reference=np.zeros_like(run.reference)), plants,
                       "original", **kw)
    # Tracking only: without the reference nothing drives the simulated loop (control 0);
    # with it the target response is fitted.
    assert np.nanmax(without.simulated_psd) < 1e-6 * np.nanmax(with_r.simulated_psd)
    assert with_r.fitness < 0.75 * without.fitness


def test_report_carries_the_verdict_at_the_top(tmp_path):
    from hesspipe.pipeline.report import build_report

    v = cohort_verdict({"a": _t(0.001)})
    (tmp_path / "pilots").mkdir()
    (tmp_path / "pilots" / "comparison.json").write_text(json.dumps(
        {"motion_verdict": v, "synthetic": True, "pilots": [], "failures": []}))
    md = build_report({"pilots": tmp_path / "pilots"}, tmp_path, config_file="x.toml", seed=0)
    head = md.split("## ")[0]
    assert "Does the pilot need motion?" in head and "1 of 1 pilots" in head
    assert "Display assumed" not in head                  # not recorded: not claimed
    # The display the test assumed, said beside its method.
    (tmp_path / "pilots" / "comparison.json").write_text(json.dumps(
        {"motion_verdict": v, "synthetic": True, "pilots": [], "failures": [],
         "settings": {"display": "compensatory"}}))
    md = build_report({"pilots": tmp_path / "pilots"}, tmp_path, config_file="x.toml", seed=0)
    assert "Display assumed: compensatory (the pilots saw only the error)." in md.split("## ")[0]


def test_undetermined_verdict_on_the_papers_task_says_how_to_answer(tmp_path):
    from hesspipe.pipeline.report import build_report

    v = cohort_verdict({"a": {"available": False}})
    (tmp_path / "pilots" / "cohort").mkdir(parents=True)
    (tmp_path / "pilots" / "comparison.json").write_text(json.dumps(
        {"motion_verdict": v, "synthetic": True, "pilots": [], "failures": []}))
    for target, hint in ((None, True), ({"kind": "multisine", "run_in_s": 15.0}, False)):
        (tmp_path / "pilots" / "cohort" / "cohort.json").write_text(json.dumps({"target": target}))
        head = build_report({"pilots": tmp_path / "pilots"}, tmp_path, config_file="x.toml",
                            seed=0).split("## ")[0]
        assert head.startswith("# hesspipe report") and "Undetermined" in head
        assert ('forcing = "two_input"' in head) is hint


def test_pilot_groups_find_the_pilot_in_each_run_id():
    ids = ["s01_motion_r1", "s01_motion_r2", "s12_motion_r1"]
    assert pilot_groups(ids, None) is None
    assert pilot_groups(ids, r"^(s\d+)_") == {"s01_motion_r1": "s01", "s01_motion_r2": "s01",
                                              "s12_motion_r1": "s12"}
    assert set(pilot_groups(ids, r"_(r\d)|^(?P<pilot>s\d+)").values()) == {"s01", "s12"}
    assert pilot_groups(ids, r"s\d+") == pilot_groups(ids, r"^(s\d+)_")      # the whole match
    with pytest.raises(HesspipeError, match=r"s12_motion_r1: pilot_id pattern '\^s0' does not match"):
        pilot_groups(ids, r"^s0")
    with pytest.raises(HesspipeError, match=r"^/lab/s12_motion_r1.csv: pilot_id pattern '\^s0' does not match "
                                            r"the run id 's12_motion_r1'"):
        pilot_groups(ids, r"^s0", {i: f"/lab/{i}.csv" for i in ids})
    with pytest.raises(HesspipeError, match="not a regular expression"):
        pilot_groups(ids, r"^(s\d+")


def test_a_pilots_runs_are_combined_before_the_cohort_counts_pilots():
    t = lambda p, km=1.0: {**_t(p), "Km": km, "Km_per_Ke": km / 10}  # noqa: E731
    tests = {"a1": t(0.02, 1.0), "a2": t(0.03, 3.0), "b1": t(0.6), "b2": t(0.7), "b3": {"available": False}}
    groups = {"a1": "a", "a2": "a", "b1": "b", "b2": "b", "b3": "b"}
    v = cohort_verdict(tests, groups=groups)
    a = v["per_pilot"]["a"]
    chi = -2 * np.log([0.02, 0.03]).sum()
    assert a["p_value"] == pytest.approx(np.exp(-chi / 2) * (1 + chi / 2))     # Fisher, 2 runs
    assert a["runs"] == 2 and a["significant"] and a["run_ids"] == ["a1", "a2"]
    assert a["Km"] == pytest.approx(2.0) and a["Km_se"] == pytest.approx(1.0)    # mean, its se
    assert a["Km_per_Ke"] == pytest.approx(0.2) and a["Km_per_Ke_se"] == pytest.approx(0.1)
    assert v["per_pilot"]["b"]["untested_runs"] == ["b3"]
    assert v["n_tested"] == 2 and v["n_significant"] == 1
    assert "for at least half of the 2 pilots, 4 runs (each pilot's runs combined first; median-pilot" in v["sentence"]
    assert "1 of 2 pilots" in v["sentence"]
    assert "1 run(s) without forcing lines" in v["sentence"]
    # Ungrouped, the same records would count four "pilots".
    assert cohort_verdict({k: x for k, x in tests.items() if k != "b3"})["n_tested"] == 4
    none = cohort_verdict({"b3": tests["b3"]}, groups=groups)
    assert none["answer"] == "undetermined" and none["per_pilot"]["b"]["untested_runs"] == ["b3"]
    text = "\n".join(verdict_lines(v))
    # Per pilot, each figure says how the runs were combined (the F beside Fisher's p is a median).
    assert f"  a (2 runs): median misfit removed 50.0 %, median F = {a['lr']:.3g}, Fisher's p = " in text
    assert "Fisher's combination" in a["combined"] and "combined" not in v["per_pilot"].get("c", {})
    # A run left out of its pilot's test is named on the pilot's line, with why.
    why = cohort_verdict({**tests, "b3": {"available": False, "reason": "3 multisine forcing lines found (need 4)"}},
                         groups=groups)
    assert "; b3 not tested (3 multisine forcing lines found (need 4))" in "\n".join(verdict_lines(why))
    assert "Km/|Ke| 0.2 +/- 0.1, Km 2 +/- 1" in text


def test_compare_pilots_groups_repeated_runs_by_pilot(tmp_path, capsys):
    # Two SYNTHETIC pilots with motion feedback, three runs each (retests of the pilot).
    folder = tmp_path / "runs"
    plants_path = None
    for i, seed in enumerate((5, 6)):
        spec = draw_trial("roll", seed, task="disturbance", pilot="hess", effects=("motion_feedback",),
                          km_ratio=(0.8, 1.0), name=f"s{i + 1:02d}_r1", **FAST)
        specs = [spec] + [retest(spec, 100 + j, name=f"s{i + 1:02d}_r{j + 1}") for j in (1, 2)]
        for sp in specs:
            plants_path = write_trial(folder, simulate_trial(sp)).parent / "plants.json"
    plants = read_plants(plants_path)
    start = PilotModel().complete({}, 1, gain=gain_scale(plants, 1))

    def job(run):
        return PilotComparison(id=run.id, source=run.source, synthetic=True, original={},
                               expanded_fixed={"parameters": {"Km": 0.1}}, expanded={}, improvement=math.nan,
                               motion_test=motion_test(run, plants, start))

    c = compare_pilots(folder, plants, workers=1, job=job, pilot_id=r"^(s\d+)_", progress=False)
    v = c.verdict()
    assert set(v["per_pilot"]) == {"s01", "s02"} and all(p["runs"] == 3 for p in v["per_pilot"].values())
    assert c.to_dict(psd=False)["n_pilots"] == 2 and c.to_dict(psd=False)["n_runs"] == 6
    with pytest.raises(HesspipeError, match=r"s01_r1\.csv: pilot_id pattern"):
        compare_pilots(folder, plants, workers=1, job=job, pilot_id=r"^x", progress=False)
    # The same file name in two folders is one run id twice: refused, whatever the grouping.
    (other := tmp_path / "other").mkdir()
    (other / "s01_r1.csv").write_bytes((folder / "s01_r1.csv").read_bytes())
    runs, failures = read_runs([folder / "s01_r1.csv", other / "s01_r1.csv"])
    assert len(runs) == 1 and "run id 's01_r1' repeats" in failures[0].error
    # The command line: a pattern that finds no pilot is one line naming the file and the flag.
    code = main(["compare-pilots", str(folder), "--plants", str(plants_path), "--pilot-id", "^x"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1 and len(err) == 1 and f"{folder / 's01_r1.csv'}: --pilot-id '^x' does not match" in err[0], err


def test_the_path_check_needs_half_of_the_pilots():
    from hesspipe.pilots.verdict import path_verdict

    def checked(p, negated):
        return {**_t(p), "path_check": {"p_values": {"negated": negated, "differentiated": 0.5,
                                                     "integrated": 0.9}}}

    # Two of six pilots with the path negated (each p x 3 < 0.01): a static cohort's shared
    # misfit, not named; three of six: named. A run named with the path given keeps its p.
    two = {f"s{i}": checked(0.6, 1e-4 if i < 2 else 0.4) for i in range(6)}
    assert path_verdict(two, {}, 0.01)["named"] == []
    three = {**two, "s2": {**_t(1e-5), "path_check": None}}
    v = path_verdict(three, {}, 0.01)
    assert v["named"] == ["negated"] and v["variants"]["negated"]["n_significant"] == 3
    assert v["variants"]["differentiated"]["n_significant"] == 1      # s2's own p stands for it
    assert path_verdict({"a": _t(0.5)}, {}, 0.01) is None              # no path checked
    # A pilot's runs combine first: two runs at 4e-3 each (Fisher's p 3.8e-4) count once.
    runs = {"a1": checked(0.5, 4e-3), "a2": checked(0.5, 4e-3), "b": checked(0.5, 0.5)}
    g = path_verdict(runs, {"a1": "a", "a2": "a"}, 0.01)
    assert g["variants"]["negated"]["n_pilots"] == 2 and g["named"] == ["negated"]
    assert cohort_verdict(runs, groups={"a1": "a", "a2": "a"})["path_check"] == g
