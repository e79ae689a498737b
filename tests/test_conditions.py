"""Two conditions of the same persons compared (hesspipe.pilots.conditions, ``hesspipe
conditions``), on runs of the independent generator (hesspipe.humanlike; SYNTHETIC)."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

from hesspipe.cli import main
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_plants, read_run, write_run
from hesspipe.core.seeds import derive_seed
from hesspipe.humanlike import draw_trial, simulate_trial, write_trial
from hesspipe.humanlike.pilots import loop_metrics, parts
from hesspipe.humanlike.plants import make_plant
from hesspipe.pilots.conditions import ALPHA, METRICS, compare_conditions, conditions_verdict, paired_tests

KW = dict(task="both", pilot="precision", output="angle", tau_m=0.15)


# Three persons (precision pilots, single integrator, yaw angle), each with one visual strategy
# and the cab's lead on or off: gains (rad/rad), delays (s), neuromuscular modes (rad/s) and
# vestibular gains of the generator's draws, fixed here so that the test draws nothing.
PERSONS = [dict(tau_v=0.28, wn=10.5, zn=0.37, Kp=2.6, TL=0.0, TI=0.0, Km=0.22),
           dict(tau_v=0.31, wn=7.6, zn=0.35, Kp=2.2, TL=0.0, TI=0.03, Km=0.25),
           dict(tau_v=0.20, wn=12.0, zn=0.28, Kp=3.2, TL=0.0, TI=0.05, Km=0.30)]


@pytest.fixture(scope="module")
def cohort(tmp_path_factory):
    """Folders ``static`` and ``motion``: persons p1-p3, one run each, the same file names."""
    root = tmp_path_factory.mktemp("conditions")
    yc = make_plant("1/s", output="angle").yc
    for i, person in enumerate(PERSONS):
        motion = {"structure": "precision", "tau": person["tau_v"], "tau_m": 0.15, **person}
        static = {k: v for k, v in motion.items() if k not in ("Km", "tau_m")}
        m = loop_metrics(lambda w: sum(parts(static, w, None)) * yc(w))
        assert m["n_crossings"] == 1 and 15.0 <= m["phase_margin_deg"] <= 60.0   # a loop a person flies
        for cond, pilot, effects in (("static", static, ()), ("motion", motion, ("motion_feedback",))):
            spec = draw_trial("1/s", derive_seed(7, cond, str(i)), effects=effects, pilot_params=pilot,
                              name=f"p{i + 1}", **KW)
            write_trial(root / cond, simulate_trial(spec))
    return root


def test_the_cabs_lead_raises_every_persons_phase_margin(cohort, capsys):
    # The same visual strategy with the vestibular path added: the loop the disturbance sees
    # gains the cab's lead, so its phase margin rises for each person.
    out = cohort / "c.json"
    code = main(["conditions", str(cohort / "static"), str(cohort / "motion"), "--plants",
                 str(cohort / "static" / "plants.json"), "--json", str(out)])
    printed = capsys.readouterr().out
    assert code == 0
    assert printed.startswith("*** SYNTHETIC DATA") and "CONDITIONS VERDICT: " in printed
    result = json.loads(out.read_text())
    assert result["labels"] == ["static", "motion"] and result["synthetic"] is True
    assert sorted(result["persons"]) == ["p1", "p2", "p3"]
    pm = result["tests"]["phase_margin_deg"]
    assert pm["n"] == 3 and pm["higher"] == 3 and pm["effect"] > 5.0
    # The vestibular path seen apart from the visual one, without a model (frf_channels): on
    # one run each the remnant raises the static persons' ratio too (0.18-0.30 here), and
    # the weakest vestibular path (p3) stands only just above it.
    ch = result["tests"]["output_channel"]
    assert ch["higher"] >= 2 and ch["effect"] > 1.2
    assert "output channel |Hpy|/|Hpe|" in printed
    for person in result["persons"].values():
        for m in person.values():
            assert len(m["runs"]) == 1 and m["error_variance"] > 0 and 0 < m["remnant_share"] < 1


def test_a_target_alone_says_whose_loop_the_crossover_is(cohort, tmp_path):
    # The same persons flying a target alone: the crossover is measured at the target's lines,
    # the loop the target sees, and the comparison says so; with disturbance lines it does not.
    from hesspipe.core.formats import read_plants, read_run

    runs = {}
    for cond, effects in (("static", ()), ("motion", ("motion_feedback",))):
        for i, person in enumerate(PERSONS):
            pilot = {"structure": "precision", "tau": person["tau_v"], "tau_m": 0.15, **person}
            pilot = pilot if effects else {k: v for k, v in pilot.items() if k not in ("Km", "tau_m")}
            spec = draw_trial("1/s", derive_seed(7, cond, str(i)), effects=effects, pilot_params=pilot,
                              name=f"p{i + 1}", **{**KW, "task": "tracking"})
            runs.setdefault(cond, []).append(read_run(write_trial(tmp_path / cond, simulate_trial(spec))))
    plants = read_plants(tmp_path / "static" / "plants.json")
    said = "no run has disturbance lines: the crossover and phase margin of this comparison are the target loop's"
    result = compare_conditions(runs["static"], runs["motion"], plants, labels=("static", "motion"))
    assert any(n.startswith(said) for n in result.notes), result.notes
    both = [read_run(p) for p in sorted((cohort / "static").glob("p*.csv"))]
    other = [read_run(p) for p in sorted((cohort / "motion").glob("p*.csv"))]
    assert not any(n.startswith(said) for n in compare_conditions(both, other, plants).notes)


def test_paired_tests_are_scipys_t_test_holm_adjusted_over_the_primary_metrics():
    rng = np.random.default_rng(3)
    persons = {}
    for i in range(6):
        a = {"crossover_rad_s": 2.0 + rng.normal(0, 0.2), "phase_margin_deg": 40 + rng.normal(0, 5),
             "error_variance": 0.01 * np.exp(rng.normal(0, 0.2)), "control_variance": 1 + rng.random(),
             "remnant_share": 0.2 + 0.1 * rng.random()}
        b = dict(a, crossover_rad_s=a["crossover_rad_s"] + 0.5 + rng.normal(0, 0.05),
                 phase_margin_deg=a["phase_margin_deg"] + rng.normal(0, 5),
                 error_variance=a["error_variance"] * 0.7 * np.exp(rng.normal(0, 0.05)))
        persons[f"s{i}"] = {"static": a, "motion": b}
    persons["only"] = {"motion": dict(b)}    # one condition only: left out
    tests = paired_tests(persons, ("static", "motion"))
    x = np.array([[p["static"]["phase_margin_deg"], p["motion"]["phase_margin_deg"]]
                  for k, p in persons.items() if k != "only"])
    assert tests["phase_margin_deg"]["p_value"] == pytest.approx(stats.ttest_rel(x[:, 1], x[:, 0]).pvalue)
    ev = np.array([[p["static"]["error_variance"], p["motion"]["error_variance"]]
                   for k, p in persons.items() if k != "only"])
    assert tests["error_variance"]["effect"] == pytest.approx(np.exp(np.mean(np.log(ev[:, 1] / ev[:, 0]))))
    primary = sorted((tests[m.key]["p_value"], m.key) for m in METRICS if m.primary)
    assert [tests[k]["p_holm"] for _, k in primary] == pytest.approx(
        np.maximum.accumulate([min(1.0, (3 - i) * p) for i, (p, _) in enumerate(primary)]))
    assert tests["control_variance"]["p_holm"] is None and tests["crossover_rad_s"]["n"] == 6
    verdict = conditions_verdict(tests, ("static", "motion"), 6)
    assert verdict.startswith("the conditions differ: motion against static: disturbance-loop crossover higher")
    assert "error variance lower (x0.6" in verdict and "phase margin" not in verdict


def test_a_forcing_that_differs_between_the_conditions_leaves_the_variances_out_of_the_verdict(cohort):
    # The same runs at half the forcing (a linear loop: every column halves): the loop is the
    # same, the error's variance a quarter. It read "the conditions differ: error variance
    # lower (x0.25)" (a review's same persons at half the forcing: x0.255).
    static = [read_run(p) for p in sorted((cohort / "static").glob("p*.csv"))]
    half = [replace(r, reference=0.5 * r.reference, disturbance=0.5 * r.disturbance, output=0.5 * r.output,
                    control=0.5 * r.control) for r in static]
    result = compare_conditions(static, half, read_plants(cohort / "static" / "plants.json"), labels=("full", "half"))
    assert result.verdict.startswith("no difference found between full and half"), result.verdict
    ev = result.tests["error_variance"]
    assert ev["confounded"] and ev["p_holm"] is None and ev["effect"] == pytest.approx(0.25)
    (note,) = [n for n in result.notes if "forcing differs" in n]
    assert "half against full: reference power x0.25, disturbance power x0.25" in note
    assert "left out of the verdict" in note
    assert result.verdict.endswith("; the error and control variances are not compared: the forcing differs "
                                   "(reference power x0.25, disturbance power x0.25)")


def test_too_few_persons_or_no_difference_say_so():
    same = {f"s{i}": {"A": {m.key: 1.0 + i for m in METRICS}, "B": {m.key: 1.0 + i for m in METRICS}}
            for i in range(4)}
    tests = paired_tests(same, ("A", "B"))
    assert all(t["p_value"] == 1.0 for t in tests.values())
    assert conditions_verdict(tests, ("A", "B"), 4).startswith("no difference found between A and B")
    two = {k: v for k, v in list(same.items())[:2]}
    tests = paired_tests(two, ("A", "B"))
    assert all(t is None for t in tests.values())
    assert conditions_verdict(tests, ("A", "B"), 2).startswith("undetermined: 2 person(s) flew both")


def test_persons_found_by_pattern_and_a_person_in_one_condition(cohort, tmp_path):
    from hesspipe.core.formats import read_plants, read_run

    runs = {c: [read_run(p) for p in sorted((cohort / c).glob("p*.csv"))] for c in ("static", "motion")}
    plants = read_plants(cohort / "static" / "plants.json")
    result = compare_conditions(runs["static"], runs["motion"][:2], plants, labels=("off", "on"),
                                pilot_id=r"^(?P<pilot>p\d)")
    assert result.persons["p3"].keys() == {"off"}
    assert any(n.startswith("p3: flew only off") for n in result.notes)
    assert result.tests["phase_margin_deg"] is None    # two persons with both
    assert result.verdict.startswith("undetermined")
    with pytest.raises(HesspipeError, match="labels: expected two different"):
        compare_conditions(runs["static"], runs["motion"], plants, labels=("x", "x"))
    with pytest.raises(HesspipeError, match="does not match the run id"):
        compare_conditions(runs["static"], runs["motion"], plants, pilot_id=r"^s\d")


@pytest.mark.parametrize("args, words", [
    (["--labels", "a,a"], "--labels: expected two different"),
    (["--labels", "static"], "--labels: expected two different"),
    (["--pilot-id", "^q"], "--pilot-id"),
    (["--json", "FILE/x.json"], "is a file, not a folder"),
])
def test_command_line_errors_are_one_line(cohort, capsys, args, words):
    args = [a.replace("FILE", str(cohort / "static" / "p1.csv")) for a in args]
    code = main(["conditions", str(cohort / "static"), str(cohort / "motion"), "--plants",
                 str(cohort / "static" / "plants.json"), *args])
    err = capsys.readouterr().err.strip().splitlines()
    assert code != 0 and len(err) == 1 and words in err[0] and "Traceback" not in err[0]


def test_missing_folder_names_it(cohort, capsys):
    code = main(["conditions", str(cohort / "static"), str(cohort / "nope"), "--plants",
                 str(cohort / "static" / "plants.json")])
    err = capsys.readouterr().err.strip()
    assert code != 0 and "nope" in err and "not found" in err


def test_alpha_and_metrics_are_documented_in_the_json_and_the_figure_is_written(cohort, tmp_path):
    out = tmp_path / "c.json"
    assert main(["conditions", str(cohort / "static"), str(cohort / "motion"), "--plants",
                 str(cohort / "static" / "plants.json"), "--json", str(out), "--seed", "5",
                 "--figure", str(tmp_path / "c.png")]) == 0
    assert (tmp_path / "c.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    obj = json.loads(out.read_text())
    assert obj["alpha"] == ALPHA and obj["metrics"]["remnant_share"]["primary"] is False
    assert obj["first"][0].endswith("p1.csv") and obj["plants"].endswith("plants.json")
    assert all(math.isfinite(t["p_value"]) for t in obj["tests"].values() if t)


def test_runs_of_different_forcings_are_averaged_run_by_run_and_a_record_twice_is_an_error(cohort, tmp_path):
    # A lab whose person flew two forcing realisations of a condition (another record length
    # and so other lines): not averaged line by line, but still compared, and said so.
    from hesspipe.core.formats import read_plants, read_run

    static = {k: v for k, v in {"structure": "precision", "tau": PERSONS[0]["tau_v"], **PERSONS[0]}.items()
              if k != "Km"}
    spec = draw_trial("1/s", 99, pilot_params=static, name="p1_other", T_m=40.0, **KW)
    other = read_run(write_trial(tmp_path, simulate_trial(spec)))
    runs = {c: [read_run(p) for p in sorted((cohort / c).glob("p*.csv"))] for c in ("static", "motion")}
    plants = read_plants(cohort / "static" / "plants.json")
    result = compare_conditions([*runs["static"], other], runs["motion"], plants, pilot_id=r"^(p\d)")
    p1 = result.persons["p1"]["A"]
    assert p1["averaged"].startswith("run by run: ") and len(p1["runs"]) == 2
    assert math.isfinite(p1["phase_margin_deg"]) and math.isfinite(p1["error_variance"])
    assert any(n.startswith("p1 (A): 2 runs averaged run by run") for n in result.notes)
    assert result.persons["p2"]["A"]["averaged"] == "one run"   # p2 flew one run
    with pytest.raises(HesspipeError, match="the same record as"):
        compare_conditions([*runs["static"], runs["static"][0]], runs["motion"], plants, pilot_id=r"^(p\d)")


def test_no_person_in_both_conditions_is_an_error_that_names_the_persons(cohort, capsys):
    # The lab's files name the condition too (s01_static_r1, s01_motion_r1): without a pattern
    # no file name is in both folders.
    import dataclasses

    from hesspipe.core.formats import read_plants, read_run

    runs = {c: [dataclasses.replace(read_run(p), id=f"{read_run(p).id}_{c}") for p in sorted((cohort / c).glob("p*.csv"))]
            for c in ("static", "motion")}
    plants = read_plants(cohort / "static" / "plants.json")
    with pytest.raises(HesspipeError, match=r"no person flew both 'A' and 'B': the persons \(a run's file name\) "
                                            r"are p1_static, p2_static, p3_static and p1_motion, .*set pilot_id"):
        compare_conditions(runs["static"], runs["motion"], plants)
    assert compare_conditions(runs["static"], runs["motion"], plants, pilot_id=r"^(p\d)").tests["phase_margin_deg"]


def test_one_folder_for_both_conditions_is_an_error_naming_the_record(cohort, capsys, tmp_path):
    # A typo that names one folder twice (or a copied file) compared records with themselves
    # and reported "no difference found" with exit 0.
    import shutil

    shutil.copytree(cohort / "static", tmp_path / "copy")
    for second in (cohort / "static", tmp_path / "copy"):
        code = main(["conditions", str(cohort / "static"), str(second), "--plants",
                     str(cohort / "static" / "plants.json")])
        err = capsys.readouterr().err.strip().splitlines()
        assert code != 0 and len(err) == 1 and "p1.csv: the same record as" in err[0]


def test_a_stick_in_another_unit_is_refused_as_pilots_refuses_it(cohort, capsys, tmp_path):
    # The crossover is of L = H Yc: a control 5.7 times the plants' unit moved every person's
    # crossover and phase margin (to -175 deg) without a word, where `pilots` refused it.
    for cond in ("static", "motion"):
        (tmp_path / cond).mkdir()
        for f in sorted((cohort / cond).glob("p*.csv")):
            run = read_run(f)
            write_run(tmp_path / cond / f.name, replace(run, control=run.control * 5.73))
    code = main(["conditions", str(tmp_path / "static"), str(tmp_path / "motion"), "--plants",
                 str(cohort / "static" / "plants.json")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code != 0 and len(err) == 1 and "control's units differ from the plants'" in err[0]


def test_a_person_whose_crossover_is_ill_defined_is_left_out_of_the_crossover_tests():
    rng = np.random.default_rng(5)
    persons = {}
    for i in range(6):
        a = {"crossover_rad_s": 2.0 + rng.normal(0, 0.2), "phase_margin_deg": 40 + rng.normal(0, 5),
             "error_variance": 0.01, "crossover_ill_defined": False}
        persons[f"s{i}"] = {"static": a, "motion": dict(a, crossover_rad_s=a["crossover_rad_s"] + 0.4,
                                                        error_variance=0.012)}
    persons["s1"]["motion"].update(crossover_rad_s=0.7, phase_margin_deg=115.0, crossover_ill_defined=True)
    tests = paired_tests(persons, ("static", "motion"))
    assert tests["crossover_rad_s"]["n"] == 5 and tests["phase_margin_deg"]["n"] == 5
    assert tests["error_variance"]["n"] == 6
    assert tests["crossover_rad_s"]["effect"] == pytest.approx(0.4)
    for p in ("s2", "s3", "s4"):
        persons[p]["static"]["crossover_ill_defined"] = True
    few = paired_tests(persons, ("static", "motion"))
    assert few["crossover_rad_s"] is None
    assert conditions_verdict(few, ("static", "motion"), 6, ill_defined=4).endswith(
        "; the crossover and phase margin are not compared: ill-defined for 4 of 6 persons (the notes name them)")
    assert "not compared" not in conditions_verdict(tests, ("static", "motion"), 6, ill_defined=1)
    for c in persons.values():
        for v in c.values():
            v.update(control_variance=1.0, remnant_share=0.2)
    from hesspipe.pilots.conditions import ConditionComparison, format_conditions

    table = format_conditions(ConditionComparison(("static", "motion"), persons, tests, "v", True))
    row = next(line for line in table.splitlines() if line.startswith("s1 "))
    assert row.split()[1:5] == [f"{persons['s1']['static']['crossover_rad_s']:.3g}", "~0.7",
                                f"{persons['s1']['static']['phase_margin_deg']:.1f}", "~115.0"]


def test_a_person_with_one_run_reads_as_frf_reads_the_file(cohort, capsys):
    # A reviewer's one-run person crossed at 5.4 rad/s in conditions and at 0.81 in frf: the
    # one run was "averaged", its lines' errors swapped for the remnant levels between them.
    from hesspipe.identification.frf import estimate_frf

    plants = read_plants(cohort / "static" / "plants.json")
    result = compare_conditions([read_run(cohort / "static" / f"p{i}.csv") for i in (1, 2, 3)],
                                [read_run(cohort / "motion" / f"p{i}.csv") for i in (1, 2, 3)], plants,
                                labels=("static", "motion"))
    run = read_run(cohort / "motion" / "p2.csv")
    seed = derive_seed(0, "conditions", "motion", "p2")
    c = estimate_frf(run, plants, seed=seed).crossover
    got = result.persons["p2"]["motion"]
    assert (got["crossover_rad_s"], got["crossover_std"]) == (c.frequency_rad_s, c.frequency_std)
    assert got["averaged"] == "one run"
    assert main(["frf", str(cohort / "motion" / "p2.csv"), "--plants", str(cohort / "static" / "plants.json"),
                 "--seed", str(seed)]) == 0
    assert f"{c.frequency_rad_s:.3f} +- {c.frequency_std:.3f}" in capsys.readouterr().out
