"""`hesspipe run` end to end on a small configuration: re-run logic and resumption.

The configuration is the default one made smaller (shorter records, two
synthetic pilots) so the whole pipeline runs in seconds; what is tested is
which stages run, not the science (each stage's own tests do that).
"""

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from hesspipe.cli import main
from hesspipe.pipeline.engine import MANIFEST

SMALL = """
seed = 3
[flight]
duration_s = 45.0
[pilots]
n = 2
duration_s = 40.0
passes = 4
restarts = 1
workers = 1
figures = false
forcing = "paper"
[diagnose]
max_effects = 1
"""
# SMALL flies the paper's forcing: these tests are about which stages run, and the two-input
# default's motion tests on the lines would triple their time (43 s -> 118 s for the module).
# The default forcing's own end-to-end run is test_the_default_forcing_answers_the_question.

STAGES = ["flight", "plants", "analytic", "pilots", "diagnose", "report"]


def _ran(capsys) -> list[str]:
    err = capsys.readouterr().err
    return [line.split()[1].rstrip(":") for line in err.splitlines() if ": running (" in line]


def _outputs(root: Path) -> dict[str, bytes]:
    """Every published file but the manifests (which hold wall times)."""
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*"))
            if p.is_file() and p.name != MANIFEST}


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """One uninterrupted run of the small configuration, kept for comparison."""
    base = tmp_path_factory.mktemp("run")
    cfg = base / "small.toml"
    cfg.write_text(SMALL)
    out = base / "out"
    assert main(["run", "--config", str(cfg), "--out", str(out)]) == 0
    return cfg, out, _outputs(out)


def test_first_run_writes_every_stage_and_report(reference):
    cfg, out, files = reference
    for stage in STAGES:
        assert (out / stage / MANIFEST).exists(), stage
    assert "report.md" in files
    report = files["report.md"].decode()
    assert "SYNTHETIC" in report  # the default cohort is synthetic and must say so
    assert "does not follow" in report  # the paper's Eq. 15 note
    # the default cohort is drawn within the crossover-model limits and the report shows the
    # pilots' true crossover beside the identified one
    import json

    for pid in ("pilot01", "pilot02"):
        truth = json.loads(files[f"pilots/cohort/{pid}.truth.json"].decode())
        assert truth["crossover"]["within_limits"] and truth["simulator"] == "jsbsim"
    assert "truth of the synthetic pilot" in report and "Within the limits (expanded model):" in report
    # the paper's 50 % is of its PSD fitness: the df criterion's improvement is not set beside it bare
    assert "the paper reports about 50 % on average of its Eq. 10 PSD fitness, not of criterion 'df'." in report


def test_the_default_forcing_answers_the_question(tmp_path):
    """The built-in forcing (two-input) gives every record its lines, so the report's first
    line is the motion verdict's answer, and diagnose tests motion on the lines."""
    import json

    cfg = tmp_path / "small.toml"
    cfg.write_text(SMALL.replace('forcing = "paper"\n', ""))
    out = tmp_path / "out"
    assert main(["run", "--config", str(cfg), "--out", str(out)]) == 0
    verdict = json.loads((out / "pilots" / "comparison.json").read_text())["motion_verdict"]
    assert verdict["answer"] == "yes"  # a cohort with motion feedback (the default effects)
    assert all(t["forcing"] == "disturbance and target" for t in verdict["per_pilot"].values())
    report = (out / "report.md").read_text()
    assert "**Does the pilot need motion? (SYNTHETIC DATA)** Yes:" in report
    assert "Forcing: two-input" in report and 'forcing = \"paper\"' not in report
    steps = json.loads((out / "diagnose" / "diagnosis.json").read_text())["steps"]
    assert steps[0]["round"] == 0 and steps[0]["candidate"] == "motion_feedback"


def test_second_run_reruns_nothing(reference, capsys):
    cfg, out, files = reference
    capsys.readouterr()
    assert main(["run", "--config", str(cfg), "--out", str(out)]) == 0
    assert _ran(capsys) == []
    assert main(["status", "--config", str(cfg), "--out", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[1] for line in lines] == ["fresh"] * len(STAGES)


def _copy_with_config(reference, tmp_path, text: str):
    """A copy of the reference run's folder and a configuration of `text` beside it."""
    work, cfg = tmp_path / "out", tmp_path / "edited.toml"
    shutil.copytree(reference[1], work)
    cfg.write_text(text)
    return work, cfg


def test_editing_the_wind_profile_reruns_flight_and_downstream_only(reference, tmp_path, capsys):
    work, edited = _copy_with_config(reference, tmp_path,
                                     SMALL.replace("[flight]\n", "[flight]\nside_wind = { speed_end_fps = 15.0 }\n"))
    assert main(["status", "--config", str(edited), "--out", str(work)]) == 0
    status = {line.split()[0]: line for line in capsys.readouterr().out.splitlines()}
    assert "configuration changed" in status["flight"] and "fresh" in status["analytic"]
    assert main(["run", "--config", str(edited), "--out", str(work)]) == 0
    assert _ran(capsys) == ["flight", "plants", "pilots", "diagnose", "report"]


def test_workers_change_how_not_what(reference, tmp_path, capsys):
    # Two worker processes give the same bytes as one, so changing the number leaves every
    # stage up to date (it re-ran the pilots stage and all after it, "configuration changed").
    cfg, out, files = reference
    work, two = _copy_with_config(reference, tmp_path, SMALL.replace("workers = 1", "workers = 2"))
    capsys.readouterr()
    assert main(["status", "--config", str(two), "--out", str(work)]) == 0
    assert [line.split()[1] for line in capsys.readouterr().out.splitlines()] == ["fresh"] * len(STAGES)
    assert main(["run", "--config", str(two), "--out", str(work), "--from", "pilots"]) == 0
    assert _ran(capsys) == ["pilots", "diagnose", "report"]
    # The same bytes but for where the run and its configuration are (paths in the outputs).
    moved = {k: v.replace(str(work).encode(), str(out).encode()).replace(str(two).encode(), str(cfg).encode())
             for k, v in _outputs(work).items()}
    assert moved == files


def test_from_stage_regenerates_the_wind_model(reference, capsys):
    cfg, out, files = reference
    capsys.readouterr()
    assert main(["run", "--config", str(cfg), "--out", str(out), "--from", "plants"]) == 0
    # plants re-ran; its outputs are deterministic, so they are the same bytes, and
    # pilots/diagnose re-ran only because --from asked for everything downstream.
    assert _ran(capsys) == ["plants", "pilots", "diagnose", "report"]
    assert _outputs(out) == files


def test_staging_left_in_a_fresh_stage_is_removed(reference, capsys):
    """A run killed after a stage's manifest landed but before its emptied staging folder
    was removed: the next run finds that stage fresh and must still clear the leftover."""
    from hesspipe.core.io import STAGING_PREFIX

    cfg, out, files = reference
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()  # its process id now belongs to no one: the "killed run"
    left = out / "plants" / f"{STAGING_PREFIX}{proc.pid}-abc"
    left.mkdir()
    capsys.readouterr()
    assert main(["run", "--config", str(cfg), "--out", str(out)]) == 0
    assert _ran(capsys) == []
    assert not left.exists()
    assert _outputs(out) == files


def test_killed_run_resumes_to_the_same_outputs(reference, tmp_path):
    cfg, out, files = reference
    work = out.parent / "out-killed"
    # Same folder name as the reference so paths written into reports match.
    shutil.move(out, out.parent / "out-saved")
    try:
        proc = subprocess.Popen([sys.executable, "-m", "hesspipe.cli", "run", "--config", str(cfg),
                                 "--out", str(out)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 120
        # Kill it as soon as the plants stage is complete: mid-way through the rest.
        while not (out / "plants" / MANIFEST).exists():
            assert proc.poll() is None, "run ended before it could be interrupted"
            assert time.monotonic() < deadline
            time.sleep(0.05)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        assert not (out / "report.md").exists()
        assert main(["run", "--config", str(cfg), "--out", str(out)]) == 0
        assert _outputs(out) == files
        assert not [p for p in out.rglob(".hesspipe-staging-*")]
    finally:
        if out.exists():
            shutil.move(out, work)
        shutil.move(out.parent / "out-saved", out)


def test_unknown_stage_and_bad_config_are_one_line_errors(reference, tmp_path, capsys):
    cfg, out, files = reference
    capsys.readouterr()
    assert main(["run", "--config", str(cfg), "--out", str(out), "--from", "wind"]) == 1
    err = capsys.readouterr().err.strip()
    assert err == ("hesspipe: error: unknown stage 'wind'; expected one of "
                   "flight, plants, analytic, pilots, diagnose, report")
    bad = tmp_path / "bad.toml"
    # A mistake in the last stage's table fails before the first stage runs.
    bad.write_text("[diagnose]\nalpha = 2\n")
    assert main(["run", "--config", str(bad), "--out", str(tmp_path / "o")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bad.toml: field 'diagnose.alpha'" in err[0], err
    assert not (tmp_path / "o").exists()
    # `status` checks the file as `run` does (it said "stale: configuration changed")
    assert main(["status", "--config", str(bad), "--out", str(out)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bad.toml: field 'diagnose.alpha'" in err[0], err
    # So does a data folder or plants file of the pilots stage that is not there or not plants.
    (tmp_path / "lab").mkdir()
    (tmp_path / "notplants.json").write_text('{"source": "x"}')
    (tmp_path / "lab2").mkdir()   # and a column mapping that names a column the runs do not have
    (tmp_path / "lab2" / "s01_r1.csv").write_text("time,disturbance,output,control,Target\n"
                                                   + "".join(f"{0.02 * k:g},0,0,0,0\n" for k in range(100)))
    for table, field, says in (('data = "nolab"', "pilots.data", "nolab not found"),
                               ('data = "lab2"\ncolumns = "reference=Tgt"', "pilots.columns",
                                "s01_r1.csv: column 'Tgt' missing (role reference)"),
                               ('data = "lab"\nplants = "none.json"', "pilots.plants", "none.json: file not found"),
                               ('data = "lab"\nplants = "notplants.json"', "pilots.plants",
                                "notplants.json: field 'control_to_output' missing"),
                               # a folder without runs, a pattern that misses a file name: before
                               # the flight, not after three stages
                               ('data = "lab"', "pilots.data", "no run files"),
                               ('data = "lab2"\npilot_id = "^(S[0-9]+)_"', "pilots.pilot_id",
                                "does not match the run id 's01_r1'")):
        bad.write_text(f"[pilots]\n{table}\n")
        assert main(["run", "--config", str(bad), "--out", str(tmp_path / "o")]) == 1
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and f"bad.toml: field '{field}': " in err[0] and says in err[0], err
        assert not (tmp_path / "o").exists()


def test_a_csv_put_beside_the_cohort_is_not_diagnosed(reference, tmp_path, capsys):
    """The diagnose stage reads the run the pilots stage declared, by id, not the first
    *.csv of the folder; the file put there by hand changes nothing."""
    import json

    cfg, out, files = reference
    work = tmp_path / "out"
    shutil.copytree(out, work)
    cohort = work / "pilots" / "cohort"
    shutil.copy(cohort / "pilot02.csv", cohort / "a_by_hand.csv")  # sorts first, valid run
    capsys.readouterr()
    assert main(["run", "--config", str(cfg), "--out", str(work), "--force", "diagnose"]) == 0
    assert json.loads((work / "diagnose" / "diagnosis.json").read_text())["run"] == "pilot01"
    # Same diagnosis as the reference's (paths differ only by the root folder).
    again = (work / "diagnose" / "diagnosis.json").read_bytes().replace(str(work).encode(), str(out).encode())
    assert again == files["diagnose/diagnosis.json"]
    assert "a_by_hand" not in (work / "report.md").read_text()
    capsys.readouterr()
    assert main(["status", "--config", str(cfg), "--out", str(work)]) == 0
    assert [line.split()[1] for line in capsys.readouterr().out.splitlines()] == ["fresh"] * len(STAGES)


def test_sigterm_during_the_pilots_stage_leaves_no_worker_and_no_half_stage(tmp_path):
    from proc_helpers import sigterm_when_ready

    cfg = tmp_path / "two.toml"
    cfg.write_text(SMALL.replace("workers = 1", "workers = 2").replace("passes = 4", "passes = 10"))
    out, err_file = tmp_path / "out", tmp_path / "stderr.txt"
    code, orphans = sigterm_when_ready(
        [sys.executable, "-m", "hesspipe.cli", "run", "--config", str(cfg), "--out", str(out)], err_file,
        lambda workers, err: len(workers) >= 2 and "pilots: running" in err, timeout_s=120)
    err = err_file.read_text()
    assert not orphans and code == 128 + signal.SIGTERM, err
    assert err.strip().splitlines()[-1] == "hesspipe: terminated" and "Traceback" not in err
    assert not (out / "pilots" / MANIFEST).exists() and (out / "plants" / MANIFEST).exists()
    assert not [p for p in out.rglob(".hesspipe-staging-*")] + [p for p in out.rglob(".hesspipe-tmp-*")]


def test_own_recordings_with_their_own_plants_and_persons(reference, tmp_path, capsys):
    """`[pilots] data`, `plants`, `columns` and `pilot_id`: a lab's runs (semicolons, decimal
    commas, degrees) of another task than the aircraft flown here are identified and
    diagnosed with their own plants, each person's runs counted as one pilot; a change of
    the plants file makes the pilots and diagnose stages stale (SYNTHETIC: the independent
    generator's precision pilots on 1/s)."""
    import json

    from hesspipe.humanlike import csv_bytes, draw_trial, simulate_trial
    from hesspipe.humanlike.writer import LAB, plants_dict

    cfg, out, _ = reference
    work = tmp_path / "out"
    shutil.copytree(out, work)
    lab = tmp_path / "lab"
    lab.mkdir()
    for person in (1, 2):
        for r in (1, 2):
            spec = draw_trial("1/s", 10 * person + r, task="both", pilot="precision", output="angle",
                              name=f"s{person}_r{r}")
            (lab / f"{spec.name}.csv").write_bytes(csv_bytes(simulate_trial(spec), LAB))
    (tmp_path / "yaw.json").write_text(json.dumps(plants_dict(spec)))
    own = tmp_path / "own.toml"
    own.write_text(cfg.read_text().replace("[pilots]\n", '[pilots]\ndata = "lab"\nplants = "yaw.json"\n'
                   'pilot_id = "^(s[0-9]+)_"\ncolumns = "reference=Target,disturbance=Disturbance,output=Yaw,'
                   'control=Stick"\n'))
    capsys.readouterr()
    assert main(["run", "--config", str(own), "--out", str(work)]) == 0
    assert _ran(capsys) == ["pilots", "diagnose", "report"]
    comp = json.loads((work / "pilots" / "comparison.json").read_text())
    assert comp["plants"]["control_to_output"] == plants_dict(spec)["control_to_output"]
    verdict = comp["motion_verdict"]
    assert verdict["n_tested"] == 2 and "2 pilots, 4 runs" in verdict["sentence"]
    assert json.loads((work / "diagnose" / "diagnosis.json").read_text())["run"] == "s1_r1"
    report = (work / "report.md").read_text()
    assert "Plants the runs were identified with: Yc = `" in report
    assert f"Runs: 4 from `{lab}` (`[pilots] data`)" in report
    assert comp["plants"]["motion_path"] == plants_dict(spec)["motion_path"]
    assert "the cab's motion path `" in report and "motion_path_note" not in comp["plants"]
    # What the stage does not read changes nothing: a notes file, a Finder file, a folder (an
    # output folder put there kept the stage stale for ever)
    (lab / "notes.txt").write_text("s2 sneezed in r2")
    (lab / ".DS_Store").write_bytes(b"\0\1")
    (lab / "old-out").mkdir()
    (lab / "old-out" / "report.md").write_text("#")
    assert main(["status", "--config", str(own), "--out", str(work)]) == 0
    assert {ln.split()[1] for ln in capsys.readouterr().out.splitlines()} == {"fresh"}
    assert main(["run", "--config", str(own), "--out", str(lab)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "own.toml: field 'pilots.data': " in err[0] and "is the output folder too" in err[0]
    (tmp_path / "yaw.json").write_text(json.dumps({**plants_dict(spec), "source": "edited"}))
    assert main(["status", "--config", str(own), "--out", str(work)]) == 0
    state = {ln.split()[0]: ln.split()[1] for ln in capsys.readouterr().out.splitlines()}
    assert [s for s in STAGES if state[s] != "fresh"] == ["pilots", "diagnose", "report"]
    # A misspelt data folder over outputs that exist: the file and field, not "input file not found"
    gone = tmp_path / "gone.toml"
    gone.write_text(own.read_text().replace('data = "lab"', 'data = "lba"'))
    for command in ("run", "status"):
        assert main([command, "--config", str(gone), "--out", str(work)]) == 1
        err = [ln for ln in capsys.readouterr().err.strip().splitlines() if not ln.startswith("[hesspipe]")]
        assert len(err) == 1 and "gone.toml: field 'pilots.data': " in err[0] and "lba not found" in err[0], err


def test_the_report_cautions_beside_the_verdict_when_the_plants_are_not_the_runs(tmp_path):
    """DI plants on single-integrator runs: a confident "yes" above 18 fits at a phase margin
    of -0.5 deg, the failed plant check four sections below (a reviewer's finding)."""
    import json

    from hesspipe.pipeline.report import _caution, _synthetic_note

    pilots, diagnose = tmp_path / "pilots", tmp_path / "diagnose"
    pilots.mkdir()
    diagnose.mkdir()
    outside = {"primary_crossover": {"frequency_rad_s": 9.0, "phase_margin_deg": -0.5, "within_limits": False}}
    (pilots / "comparison.json").write_text(json.dumps({"pilots": [{"expanded": outside}] * 3}))
    (diagnose / "diagnosis.json").write_text(json.dumps({"run": "s01_r1", "plant_check": {"fit_percent": -6984.0},
                                                         "plant_finding": {"verdict": "unexplained"}}))
    text = " ".join(_caution(pilots, diagnose))
    assert text.startswith("**Caution:** the plants do not reproduce the diagnosed run `s01_r1` (fit -6984 %")
    assert "none of the 3 identified runs is within the crossover model's limits" in text
    # a Dutch roll behind the plants is diagnose's finding, not a wrong plants file; fits within limits
    inside = {"primary_crossover": {"within_limits": True}}
    (pilots / "comparison.json").write_text(json.dumps({"pilots": [{"expanded": inside}] * 3}))
    (diagnose / "diagnosis.json").write_text(json.dumps({"run": "r", "plant_check": {"fit_percent": -2652.0},
                                                         "plant_finding": {"verdict": "aircraft"}}))
    assert _caution(pilots, diagnose) == []
    # a data folder's synthetic runs are not "generated by hesspipe's own pilot model"
    assert "[pilots] data" in _synthetic_note(pilots) and "own pilot model" not in _synthetic_note(pilots)
    (pilots / "cohort").mkdir()
    (pilots / "cohort" / "cohort.json").write_text("{}")
    assert "own pilot model" in _synthetic_note(pilots)


def test_the_reports_crossover_table_marks_a_wide_flat_band(tmp_path):
    from hesspipe.pipeline.report import _pilots

    def conf(flat):
        c = {"frequency_rad_s": 0.8, "phase_margin_deg": 110.0, "within_limits": False,
             "flat_band": {"low_rad_s": 0.5, "high_rad_s": 4.0, "wide": flat}}
        return {"parameters": {"Ke": 1.0, "K1": 0.1, "K2": 2.0, "Km": 0.2}, "fitness": 1.0, "primary_crossover": c}

    comp = {"pilots": [{"id": "s1", "original": conf(True), "expanded_fixed": conf(False), "expanded": conf(False),
                        "improvement": 0.1}]}
    (tmp_path / "comparison.json").write_text(json.dumps(comp))
    rows = [line for line in _pilots(tmp_path, tmp_path) if line.startswith(("| s1 | original", "| s1 | expanded"))]
    assert rows == ["| s1 | original | ~0.8 | ~110 | no |", "| s1 | expanded | 0.8 | 110 | no |"]
    comp["pilots"][0]["original"]["primary_crossover"].update(frequency_rad_s=None, phase_margin_deg=None)
    (tmp_path / "comparison.json").write_text(json.dumps(comp))
    assert "| s1 | original | — | — | no |" in _pilots(tmp_path, tmp_path)   # no crossover: nothing to mark
