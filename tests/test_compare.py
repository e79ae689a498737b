"""compare-pilots: batch machinery, failures, JSON, CLI; and the real identification on a small cohort."""

from __future__ import annotations

import json
import math
import shutil

import control as ct
import numpy as np
import pytest

from hesspipe.cli import main
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import Plants, Run, write_plants, write_run
from hesspipe.core.io import to_json
from hesspipe.core.paper import EQ14, EQ16
from hesspipe.core.seeds import derive_seed
from hesspipe.pilots import compare as compare_mod
from hesspipe.pilots.batch import run_batch
from hesspipe.pilots.compare import CONFIGURATIONS, Comparison, PilotComparison, PilotsConfig, compare_pilots, list_runs


def paper_plants() -> Plants:
    """Yc = 2.436/(s+1.0496) (Table 4 rolling approximation), Yd = SPEC.md Eq. 16."""
    return Plants(ct.tf(*EQ14), ct.tf(*EQ16))


# -- a stand-in for the identification (test double: exercises the batch, not the model) --------

def fake_job(run: Run) -> PilotComparison:
    """Deterministic per-pilot result that depends on the data and on the pilot's derived seed."""
    if "boom" in run.id:
        raise RuntimeError("simulated crash")
    rng = np.random.default_rng(derive_seed(7, run.id))
    base = float(np.std(run.control)) + rng.uniform(0, 1e-3)
    confs = {name: {"parameters": {"Ke": 20.0, "K1": 3.0, "K2": 2.0, **({"Km": 1.0} if "exp" in name else {})},
                    "fitness": base * f, "crossover": {"frequency_rad_s": 3.0, "phase_margin_deg": 50.0}}
             for name, f in zip(CONFIGURATIONS, (1.0, 1.0, 0.5))}
    return PilotComparison(id=run.id, source=run.source, synthetic=run.synthetic, improvement=0.5,
                           freq_hz=np.linspace(0, 5, 4), measured_psd=np.ones(4),
                           simulated_psd={k: np.ones(4) for k in CONFIGURATIONS}, **confs)


def _square(x):
    return x * x


def _write_runs(folder, n=4, samples=1100, synthetic=True):
    folder.mkdir(parents=True, exist_ok=True)
    for i in range(n):
        rng = np.random.default_rng(i)
        t = 0.02 * np.arange(samples)
        write_run(folder / f"p{i}.csv", Run(time=t, disturbance=rng.standard_normal(samples),
                                            output=rng.standard_normal(samples),
                                            control=(1 + i) * rng.standard_normal(samples),
                                            reference=np.zeros(samples), id=f"p{i}", synthetic=synthetic))
    return folder


def test_run_batch_keeps_item_order_for_any_worker_count():
    items = list(range(7))
    assert run_batch(_square, items, workers=1) == [i * i for i in items]
    assert run_batch(_square, items, workers=2) == [i * i for i in items]
    assert run_batch(_square, items, workers=0) == [i * i for i in items]   # 0: all cores, as in TOML
    with pytest.raises(HesspipeError, match=r"^workers: expected an integer >= 0 \(0: all cores\), got -1"):
        run_batch(_square, items, workers=-1)


def test_results_do_not_depend_on_worker_count(tmp_path):
    folder = _write_runs(tmp_path / "runs")
    one = compare_pilots(folder, paper_plants(), workers=1, job=fake_job)
    two = compare_pilots(folder, paper_plants(), workers=2, job=fake_job)
    assert [p.id for p in one.pilots] == ["p0", "p1", "p2", "p3"]
    assert to_json(one.to_dict()) == to_json(two.to_dict())


def test_dask_local_cluster_gives_the_local_results(tmp_path, capsys, monkeypatch):
    distributed = pytest.importorskip("distributed")
    folder = _write_runs(tmp_path / "runs", n=3)
    local = compare_pilots(folder, paper_plants(), workers=1, job=fake_job)
    plants = write_plants(tmp_path / "plants.json", paper_plants())
    monkeypatch.setattr(compare_mod, "compare_run", lambda run, plants, settings: fake_job(run))
    # In-process cluster: no subprocesses, no TCP port (inproc:// transport).
    with distributed.LocalCluster(processes=False, n_workers=1, threads_per_worker=2,
                                  dashboard_address=None) as cluster:
        remote = compare_pilots(folder, paper_plants(), scheduler=cluster.scheduler_address, job=fake_job)
        code = main(["compare-pilots", str(folder), "--plants", str(plants), "--scheduler",
                     cluster.scheduler_address, "--json", str(tmp_path / "dask.json")])
    assert to_json(remote.to_dict()) == to_json(local.to_dict())
    assert code == 0 and "p2" in capsys.readouterr().out
    assert json.loads((tmp_path / "dask.json").read_text())["pilots"] == json.loads(
        to_json(local.to_dict()))["pilots"]
    # The cluster's threads may outlive it; local processes must still work afterwards.
    again = compare_pilots(folder, paper_plants(), workers=2, job=fake_job)
    assert to_json(again.to_dict()) == to_json(local.to_dict())


def test_unreachable_scheduler_is_a_one_line_error():
    pytest.importorskip("distributed")
    with pytest.raises(HesspipeError, match=r"^scheduler tcp://127.0.0.1:9: cannot connect"):
        run_batch(_square, [1], scheduler="tcp://127.0.0.1:9", connect_timeout=1)


def test_bad_files_are_reported_and_the_good_ones_processed(tmp_path):
    folder = _write_runs(tmp_path / "runs", n=3)
    (folder / "broken.csv").write_text("time,disturbance,output\n0,1,2\n0.02,1,2\n")
    shutil.copy(_write_runs(tmp_path / "more", n=4) / "p3.csv", folder / "p_boom.csv")
    (folder / "p0.truth.json").write_text("{}")  # beside the runs, ignored
    result = compare_pilots(folder, paper_plants(), workers=1, job=fake_job)
    assert [p.id for p in result.pilots] == ["p0", "p1", "p2"]
    assert not result.ok
    errors = {f.id: f.error for f in result.failures}
    assert set(errors) == {"broken", "p_boom"}
    assert str(folder / "broken.csv") in errors["broken"] and "column 'control' missing" in errors["broken"]
    assert errors["p_boom"].startswith(str(folder / "p_boom.csv")) and "simulated crash" in errors["p_boom"]
    d = result.to_dict()
    assert [f["id"] for f in d["failures"]] == ["broken", "p_boom"]
    # The unread file is handed over before any identification runs (a command line says it
    # at once instead of minutes later); the crash of a fit is not among them.
    fitted, seen = [], []
    compare_pilots(folder, paper_plants(), workers=1, job=lambda r: (fitted.append(r.id), fake_job(r))[1],
                   on_read=lambda reading, unread: seen.append((len(fitted), [f.id for f in unread])))
    assert seen == [(0, ["broken"])] and len(fitted) == 4


def test_json_keys_improvement_and_synthetic_flags(tmp_path):
    folder = _write_runs(tmp_path / "runs", n=2)
    _write_runs(tmp_path / "measured", n=3, synthetic=False)
    shutil.copy(tmp_path / "measured" / "p2.csv", folder / "real.csv")
    result = compare_pilots(folder, paper_plants(), workers=1, job=fake_job)
    d = json.loads(to_json(result.to_dict()))
    assert d["synthetic"] is True and d["synthetic_pilots"] == 2 and d["measured_pilots"] == 1
    assert [p["synthetic"] for p in d["pilots"]] == [True, True, False]
    for p in d["pilots"]:
        for name in CONFIGURATIONS:
            assert set(p[name]) >= {"parameters", "fitness"}
        assert p["improvement"] == pytest.approx(0.5)
    assert d["mean_improvement"] == pytest.approx(0.5)
    table = result.table()
    assert table.startswith("SYNTHETIC DATA") and "real" in table and "mean 50.0 %" in table
    # Km/|Ke| beside the gains: x where the model has no Km, Km/|Ke| = 1/20 where it has.
    rows = table.splitlines()
    head = next(r for r in rows if r.startswith("pilot "))
    assert head.split()[2:8] == ["Ke", "K1", "K2", "Km", "Km/|Ke|", "fitness"]
    # From the right: PM, wc, fitness (no improvement on these rows), Km/|Ke|, Km.
    original = next(r for r in rows if " original " in r).split()
    fixed = next(r for r in rows if r.lstrip().startswith("expanded_fixed ")).split()
    assert original[-5:-3] == ["x", "x"] and fixed[-5:-3] == ["1", "0.05"]


def test_list_runs_errors(tmp_path):
    with pytest.raises(HesspipeError, match="no run files"):
        list_runs(tmp_path)
    with pytest.raises(HesspipeError, match="not found"):
        list_runs(tmp_path / "nope")


def test_the_table_says_which_fit_its_km_comes_from(tmp_path):
    # A reviewer read 0.048 in the table and 0.142 in the verdict for one run, both "Km/|Ke|".
    folder = _write_runs(tmp_path / "runs", n=2)
    for criterion, words in (("paper", "the control-spectrum fit's (APID, Eq. 10)"),
                             ("df", "the paper's expanded model fitted to the describing function")):
        table = compare_pilots(folder, paper_plants(), workers=1, job=fake_job, criterion=criterion).table()
        assert f"Km and Km/|Ke| in the table are {words}" in table and "motion test's estimate" in table
        assert "wc and PM in the table are each fitted model's loop" in table


def test_a_folders_runs_are_listed_in_natural_order(tmp_path):
    # A lab numbers its subjects s1, s2, ..., s10: a plain sort listed s10 second.
    for name in ("s10_r1.csv", "s2_r10.csv", "s2_r2.csv", "s1_r1.csv", "s01_r1.csv"):
        (tmp_path / name).write_text("time,disturbance,output,control\n")
    assert [p.name for p in list_runs(tmp_path)] == ["s01_r1.csv", "s1_r1.csv", "s2_r2.csv", "s2_r10.csv",
                                                     "s10_r1.csv"]


def test_a_folder_of_text_exports_is_read_and_beside_csv_runs_they_are_not(tmp_path):
    for name in ("s01_r1.txt", "s01_r2.dat", "README.md"):
        (tmp_path / name).write_text("time,disturbance,output,control\n")
    assert [p.name for p in list_runs(tmp_path)] == ["s01_r1.txt", "s01_r2.dat"]
    (tmp_path / "s02_r1.csv").write_text("time,disturbance,output,control\n")
    assert [p.name for p in list_runs(tmp_path)] == ["s02_r1.csv"]


def test_a_record_copied_into_the_folder_is_refused(tmp_path):
    # Two copies of one record are not two runs: their tests would count the same evidence
    # twice (Fisher's rule over a pilot's runs).
    folder = _write_runs(tmp_path / "runs", n=2)
    assert len(compare_pilots(folder, paper_plants(), job=fake_job).pilots) == 2
    shutil.copy(folder / "p1.csv", folder / "p1_copy.csv")
    with pytest.raises(HesspipeError, match=r"p1_copy.csv: the same record as .*p1.csv"):
        compare_pilots(folder, paper_plants(), job=fake_job)


def test_cli_bad_file_exit_status_and_message(tmp_path, capsys, monkeypatch):
    folder = _write_runs(tmp_path / "runs", n=2)
    (folder / "bad.csv").write_text("time,disturbance,output,control\n0,1,2,x\n")
    plants = write_plants(tmp_path / "plants.json", paper_plants())
    monkeypatch.setattr(compare_mod, "compare_run", lambda run, plants, settings: fake_job(run))
    out_json = tmp_path / "out.json"
    code = main(["compare-pilots", str(folder), "--plants", str(plants), "--workers", "1",
                 "--json", str(out_json)])
    captured = capsys.readouterr()
    assert code == 1
    assert f"hesspipe: error: {folder / 'bad.csv'}: column 'control'" in captured.err
    assert captured.err.strip().splitlines()[-1] == ("hesspipe: error: 1 file(s) could not be read; the others "
                                                     "are in the table")
    assert "p0" in captured.out and "p1" in captured.out
    d = json.loads(out_json.read_text())
    assert [p["id"] for p in d["pilots"]] == ["p0", "p1"] and d["failures"][0]["id"] == "bad"


def test_cli_counts_a_file_it_cannot_read_as_a_file_not_a_run(tmp_path, capsys, monkeypatch):
    # A run that fails its identification is a run; a file that cannot be read is a file,
    # however many runs it holds.
    folder = _write_runs(tmp_path / "runs", n=3)
    (folder / "p1.csv").rename(folder / "boom.csv")
    (folder / "bad.csv").write_text("time,disturbance,output,control\n0,1,2,x\n")
    plants = write_plants(tmp_path / "plants.json", paper_plants())
    monkeypatch.setattr(compare_mod, "compare_run", lambda run, plants, settings: fake_job(run))
    assert main(["pilots", str(folder), "--plants", str(plants), "--workers", "1"]) == 1
    assert capsys.readouterr().err.strip().splitlines()[-1] == (
        "hesspipe: error: 1 of 3 run(s) failed, and 1 file(s) could not be read; the others are in the table")


def test_cli_all_runs_failed_is_an_error_without_a_verdict_or_file(tmp_path, capsys):
    # A misspelt mapped column fails every run: no table, no "undetermined" verdict that
    # blames the forcing, no JSON.
    folder = tmp_path / "runs"
    folder.mkdir()
    for i in range(2):   # a logger's files with a target column named Target
        rows = "".join(f"{0.02 * k:g},{np.sin(k):.4f},{np.cos(k):.4f},{np.sin(2 * k):.4f},{0.1 * k:g}\n"
                       for k in range(1100))
        (folder / f"p{i}.csv").write_text("time,disturbance,output,control,Target\n" + rows)
    plants = write_plants(tmp_path / "plants.json", paper_plants())
    out_json = tmp_path / "out.json"
    code = main(["pilots", str(folder), "--plants", str(plants), "--columns", "reference=Tgt",
                 "--json", str(out_json)])
    captured = capsys.readouterr()
    assert code == 1 and not out_json.exists() and "VERDICT" not in captured.out
    err = captured.err.strip().splitlines()
    assert len(err) == 3 and all(line.startswith("hesspipe: error:") for line in err)
    assert "column 'Tgt' missing (role reference)" in err[0] and "--columns reference=NAME" in err[0]
    assert err[-1] == "hesspipe: error: 2 file(s) could not be read; nothing to compare"


def test_verdict_without_pilots_says_none_was_identified():
    from hesspipe.pilots.verdict import cohort_verdict

    assert cohort_verdict({})["sentence"] == "undetermined: no pilot was identified"
    no_lines = cohort_verdict({"p1": {"available": False, "reason": "no lines"}})
    assert no_lines["answer"] == "undetermined" and "multisine forcing lines" in no_lines["sentence"]


@pytest.mark.parametrize("argv, code, words", [
    (["pilots", "{runs}", "--plants", "{plants}", "--workers", "-1"], 1, "--workers: expected"),
    (["pilots", "{tmp}/none", "--plants", "{plants}"], 1, "not found"),
    (["pilots", "{runs}", "--plants", "{tmp}/missing.json"], 1, "missing.json: file not found"),
    (["pilots", "{runs}"], 2, "--plants"),
    (["pilots", "{runs}", "--plants", "{plants}", "--columns", "stick=control"], 1,
     "--columns: unknown role 'stick'"),
])
def test_cli_argument_errors(tmp_path, capsys, argv, code, words):
    runs = _write_runs(tmp_path / "runs", n=1)
    plants = write_plants(tmp_path / "plants.json", paper_plants())
    argv = [a.format(runs=runs, plants=plants, tmp=tmp_path) for a in argv]
    with pytest.raises(SystemExit) if code == 2 else _nothing() as info:
        result = main(argv)
    err = capsys.readouterr().err
    if code == 2:
        assert info.value.code == 2
    else:
        assert result == 1 and err.startswith("hesspipe: error:") and err.count("\n") == 1
    assert words in err


class _nothing:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def test_pilots_config_defaults_and_errors():
    cfg = PilotsConfig.from_table({}, "default.toml")
    assert cfg.n == 6 and cfg.effects == ("motion_feedback",) and cfg.optimizer == "apid"
    cfg = PilotsConfig.from_table({"n": 3, "seed": 5, "effects": [], "workers": 2}, "x.toml")
    assert (cfg.n, cfg.seed, cfg.effects, cfg.workers) == (3, 5, (), 2)
    cfg = PilotsConfig.from_table({"data": "runs", "plants": "yaw.json", "pilot_id": "^(s[0-9]+)_"}, "x.toml")
    assert (cfg.plants, cfg.pilot_id) == ("yaw.json", "^(s[0-9]+)_")
    for table, words in [({"n": 0}, "field 'pilots.n': expected an integer >= 1, got 0"),
                         ({"optimizer": "ga"}, "field 'pilots.optimizer'"),
                         ({"effects": "motion_feedback"}, "field 'pilots.effects': expected a list"),
                         ({"nn": 3}, "field 'pilots.nn': unknown field"),
                         ({"duration_s": 5.0}, "field 'pilots.duration_s': duration_s 5 s at dt_s 0.02 s is "
                                               "250 samples; expected 1024 to"),
                         ({"duration_s": 1e9}, "field 'pilots.duration_s': duration_s 1e\\+09 s"),
                         ({"seed": -1}, "field 'pilots.seed': expected an integer >= 0"),
                         ({"seed": 2 ** 63}, "field 'pilots.seed': expected an integer >= 0 <= 9223372036854775807"),
                         ({"resample": "yes"}, "field 'pilots.resample': expected true or false"),
                         ({"columns": "stick"}, "field 'pilots.columns': columns: expected ROLE=NAME"),
                         ({"plants": "yaw.json"}, "field 'pilots.plants': a plants file is for the runs of a "
                                                  "data folder"),
                         ({"data": "runs", "pilot_id": "^(s[0-9]+_"}, "field 'pilots.pilot_id': expected a "
                                                                       "regular expression, got ")]:
        with pytest.raises(HesspipeError, match=words.replace(".", r"\.").replace("(", r"\(")):
            PilotsConfig.from_table(table, "x.toml")


def test_the_table_says_when_the_motion_test_and_the_expanded_fit_disagree():
    p = fake_job(Run(0.02 * np.arange(3.0), *(np.zeros(3),) * 4, id="a"))
    test = {"available": True, "p_value": 1e-6, "Km": 0.3, "Km_per_Ke": 0.2, "forcing": "disturbance and target",
            "gain": 0.5, "lr": 30.0, "Km_se": 0.1, "Km_per_Ke_se": 0.05, "significant": True}
    flat = PilotComparison(**{**p.__dict__, "id": "b", "motion_test": test,
                              "expanded": {**p.expanded, "parameters": {**p.expanded["parameters"], "Km": 0.0}}})
    named = PilotComparison(**{**p.__dict__, "id": "c", "motion_test": test})
    assert "motion test and table: on 1 of the 2 run(s)" in Comparison(pilots=(flat, named)).table()
    other = PilotComparison(**{**named.__dict__, "id": "d"})
    assert "motion test and table" not in Comparison(pilots=(named, other)).table()


def test_the_table_marks_a_crossover_in_a_wide_flat_band():
    p = fake_job(Run(0.02 * np.arange(3.0), *(np.zeros(3),) * 4, id="a"))
    assert "~" not in Comparison(pilots=(p,)).table()
    wide = {"frequency_rad_s": 0.9, "phase_margin_deg": 104.0,
            "flat_band": {"low_rad_s": 0.6, "high_rad_s": 4.1, "wide": True}}
    flat = PilotComparison(**{**p.__dict__, "id": "b", "original": {**p.original, "crossover": wide}})
    table = Comparison(pilots=(flat,)).table()
    row = next(line for line in table.splitlines() if line.startswith("b "))
    assert row.split()[-2:] == ["~0.9", "~104"]
    assert "~ wc, PM: the model's |L| stays within a factor 1.25 of 1" in table


def test_improvement_stats_ignore_nan():
    p = fake_job(Run(0.02 * np.arange(3.0), *(np.zeros(3),) * 4, id="a"))
    nan = PilotComparison(**{**p.__dict__, "id": "b", "improvement": math.nan})
    s = Comparison(pilots=(p, nan)).improvement_stats()
    assert s["n"] == 1 and s["mean"] == pytest.approx(0.5) and math.isnan(s["std"])


# -- the real identification on a small synthetic cohort ----------------------------------------

@pytest.fixture(scope="module")
def cohorts(tmp_path_factory):
    from hesspipe.pilots.cohort import CohortSpec, synth_cohort

    root = tmp_path_factory.mktemp("cohorts")
    # 1200 samples (one spectral segment, fast) and little remnant (2 % of the control power), so
    # that 3 short records show the pattern; benchmarks/bench_compare.py runs the default cohort.
    spec = CohortSpec(duration_s=24.0, remnant_share=0.02)
    synth_cohort(paper_plants(), 3, 1, ["motion_feedback"], root / "mf", spec=spec)
    synth_cohort(paper_plants(), 3, 1, [], root / "none", spec=spec)
    return root


def test_motion_feedback_cohort_pattern(cohorts):
    # A light search (1 climb of 6 passes + polish) keeps the test fast; the benchmark uses defaults.
    result = compare_pilots(cohorts / "mf", paper_plants(), workers=2, seed=0, restarts=1, passes=6)
    assert result.ok and result.synthetic and len(result.pilots) == 3
    from hesspipe.pilot.crossover import gain_scale

    km_fixed = 0.1 * gain_scale(paper_plants())  # Table 1's, scaled to the plants like every loop gain
    assert result.settings.km_fixed == pytest.approx(km_fixed)
    for p in result.pilots:
        orig, fixed, exp = (p.configuration(n) for n in CONFIGURATIONS)
        assert set(orig["parameters"]) >= {"Ke", "K1", "K2"} and "Km" not in orig["parameters"]
        assert fixed["parameters"]["Km"] == pytest.approx(km_fixed)
        assert {k: fixed["parameters"][k] for k in ("Ke", "K1", "K2")} == \
            {k: orig["parameters"][k] for k in ("Ke", "K1", "K2")}
        # Paper pattern: original ~ expanded with fixed Km; the expanded model contains the
        # original (Km = 0) and the warm-started searches exchange optima, so it is never worse.
        assert fixed["fitness"] == pytest.approx(orig["fitness"], rel=0.25)
        assert exp["fitness"] <= orig["fitness"]
        assert p.improvement == pytest.approx(1 - exp["fitness"] / orig["fitness"])
        assert math.isfinite(exp["crossover"]["frequency_rad_s"])
        assert p.freq_hz[-1] <= 5.0 and p.simulated_psd["expanded"].shape == p.measured_psd.shape
    # Measured 25 % (pilots adapted to the plant's gain, Ke ~ 0.44 x Table 1, 2 % remnant); the
    # same search on pilots without motion feedback finds next to nothing.
    assert result.mean_improvement > 0.2, result.table()
    none = compare_pilots(cohorts / "none", paper_plants(), workers=2, seed=0, restarts=1, passes=6)
    assert none.ok and none.mean_improvement < 0.05, none.table()


def test_cli_end_to_end_with_figures(cohorts, tmp_path, capsys):
    plants = write_plants(tmp_path / "plants.json", paper_plants())
    folder = tmp_path / "runs"
    folder.mkdir()
    for name in ("pilot01.csv", "pilot01.truth.json"):
        shutil.copy(cohorts / "none" / name, folder / name)
    code = main(["pilots", str(folder), "--plants", str(plants), "--workers", "1", "--passes", "2",
                 "--restarts", "1", "--criterion", "paper",
                 "--json", str(tmp_path / "c.json"), "--figures", str(tmp_path / "fig")])
    out = capsys.readouterr().out
    assert code == 0
    assert out.startswith("SYNTHETIC DATA") and "pilot01 *" in out and "expanded_fixed" in out
    d = json.loads((tmp_path / "c.json").read_text())
    assert d["synthetic"] is True and [p["id"] for p in d["pilots"]] == ["pilot01"]
    assert d["settings"]["passes"] == 2 and d["pilots"][0]["original"]["passes"] == 2
    assert (tmp_path / "fig" / "pilot01.png").stat().st_size > 10_000


def test_short_run_is_reported_not_fatal(tmp_path):
    from hesspipe.identification.spectra import PaperWelch

    assert compare_mod.MIN_SAMPLES == PaperWelch().nperseg
    folder = _write_runs(tmp_path / "runs", n=2)
    _write_runs(tmp_path / "short", n=1, samples=1000)
    shutil.copy(tmp_path / "short" / "p0.csv", folder / "short.csv")
    result = compare_pilots(folder, paper_plants(), workers=1, job=fake_job)
    assert [p.id for p in result.pilots] == ["p0", "p1"]
    assert "1000 samples; expected at least 1024" in result.failures[0].error


def test_seeds_are_stable_and_distinct():
    assert derive_seed(0, "pilot01") == derive_seed(0, "pilot01")
    assert len({derive_seed(0, "pilot01"), derive_seed(1, "pilot01"), derive_seed(0, "pilot02"),
                derive_seed(0, "pilot01", "original")}) == 4
    assert 0 <= derive_seed(2 ** 40, "x") < 2 ** 63


def test_progress_is_quiet_when_not_a_terminal(capsys):
    import io

    from hesspipe.core.progress import progress_bar, progress_enabled

    assert not progress_enabled(io.StringIO())
    with progress_bar(3, "pilots") as bar:  # stderr is captured here: not a tty
        bar.update(3)
    assert capsys.readouterr().err == ""
    assert run_batch(_square, [2], workers=1, progress=False) == [4]


def test_run_study_writes_the_pilots_stage_outputs(tmp_path):
    from hesspipe.pilots.compare import run_study

    config = PilotsConfig.from_table({"n": 2, "duration_s": 21.0, "passes": 2, "restarts": 1, "workers": 1,
                                      "effects": ["motion_feedback"]}, "test.toml")
    from hesspipe.viz.compare import draw_comparison

    result = run_study(config, paper_plants(), tmp_path, seed=4, progress=False, draw=draw_comparison)
    assert result.ok and result.synthetic and [p.id for p in result.pilots] == ["pilot01", "pilot02"]
    names = sorted(str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*") if p.is_file())
    assert names == ["cohort/.hesspipe-output", "cohort/cohort.json", "cohort/pilot01.csv", "cohort/pilot01.truth.json",
                     "cohort/pilot02.csv", "cohort/pilot02.truth.json", "comparison.json", "comparison.md",
                     "figures/pilot01.png", "figures/pilot01_df.png", "figures/pilot02.png",
                     "figures/pilot02_df.png"]
    d = json.loads((tmp_path / "comparison.json").read_text())
    assert d["synthetic"] is True and d["settings"]["seed"] == 4
    assert "SYNTHETIC DATA" in (tmp_path / "comparison.md").read_text()


def test_progress_bar_is_drawn_on_a_terminal(monkeypatch):
    pty = pytest.importorskip("pty")
    import fcntl
    import os
    import select
    import struct
    import sys
    import termios

    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))
    with open(slave, "w", closefd=True) as tty:
        monkeypatch.setattr(sys, "stderr", tty)
        assert run_batch(_square, [1, 2, 3], workers=1, desc="pilots", unit="pilot") == [1, 4, 9]
        tty.flush()
    out = b""
    while select.select([master], [], [], 0.5)[0]:
        try:
            chunk = os.read(master, 65536)
        except OSError:
            break
        if not chunk:
            break
        out += chunk
    os.close(master)
    assert b"pilots:" in out and b"/3 [" in out  # drawn (fast updates are throttled by tqdm)


def test_scheduler_without_dask_names_the_extra(monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "distributed", None)  # import fails as if not installed
    with pytest.raises(HesspipeError, match=r"pip install 'hesspipe\[dask\]'"):
        run_batch(_square, [1], scheduler="tcp://127.0.0.1:8786")


def test_compare_pilots_command_spells_the_librarys_settings_as_its_flags():
    # The library says "workers:" / "scheduler ADDRESS:"; the command's messages name its flags.
    from hesspipe.cli import build_parser
    from hesspipe.cli._options import cli_message

    args = build_parser().parse_args(["compare-pilots", "runs", "--plants", "p.json"])
    assert cli_message("workers: expected an integer >= 0 (0: all cores), got -1", args) == \
        "--workers: expected an integer >= 0 (0: all cores), got -1"
    assert cli_message("scheduler tcp://127.0.0.1:9: cannot connect to a Dask scheduler (x)", args) == \
        "--scheduler tcp://127.0.0.1:9: cannot connect to a Dask scheduler (x)"
    assert cli_message("runs/p1.csv: column 'control' missing", args) == "runs/p1.csv: column 'control' missing"


def test_pilots_command_keeps_compare_pilots_as_an_alias(tmp_path, capsys):
    """The stage's command is `pilots`; old scripts calling `compare-pilots` get the same command."""
    from hesspipe.cli import build_parser
    from hesspipe.cli._options import cli_message

    new = build_parser().parse_args(["pilots", "runs", "--plants", "p.json", "--passes", "3"])
    old = build_parser().parse_args(["compare-pilots", "runs", "--plants", "p.json", "--passes", "3"])
    assert new.func is old.func and new.passes == old.passes == 3
    # The settings are checked by the library (CompareSettings) and named as flags here.
    assert cli_message("CompareSettings: field 'passes': expected an integer >= 1, got 0", new) == \
        "--passes: expected an integer >= 1, got 0"
    for cmd in ("pilots", "compare-pilots"):
        assert main([cmd, str(tmp_path), "--plants", str(tmp_path / "p.json"), "--restarts", "0"]) == 1
        assert capsys.readouterr().err.strip() == "hesspipe: error: --restarts: expected an integer >= 1, got 0"


def test_a_note_every_file_shares_is_said_once():
    """A folder written by one lab gives one line per note, not one per file and note; a note
    only some files have keeps its files' names."""
    from hesspipe.cli._options import reading_lines

    deg = "column 'Yaw [deg]' (output): deg converted to rad (SPEC.md's units, x 0.0174533)"
    reading = {f"lab/s{i:02d}.csv": ["semicolon-separated with decimal commas", deg] for i in range(1, 19)}
    reading["lab/s07.csv"] = reading["lab/s07.csv"] + ["2 incomplete row(s) at the end dropped"]
    assert reading_lines(reading) == [
        "hesspipe: note: 18 files (lab/s01.csv … lab/s18.csv): semicolon-separated with decimal commas",
        f"hesspipe: note: 18 files (lab/s01.csv … lab/s18.csv): {deg}",
        "hesspipe: note: lab/s07.csv: 2 incomplete row(s) at the end dropped",
    ]
    assert reading_lines({"one.csv": ["a", "a"]}) == ["hesspipe: note: one.csv: a"]
    assert reading_lines({"one.csv": []}) == []
