"""Phase-aware identification (hesspipe.identification.criteria) on independent generated trials.

Trials come from hesspipe.humanlike, the independent fine-step time-domain generator
(SYNTHETIC data; it shares no modelling code with the identification).
"""

import control as ct
import numpy as np
import pytest

from hesspipe.core.formats import Plants, Run
from hesspipe.humanlike import draw_trial, plants_dict, simulate_trial
from hesspipe.identification.criteria import DEFAULT_CRITERION, choose_k
from hesspipe.identification.fit import identify
from hesspipe.identification.frf import estimate_frf


def _trial(plant, seed, pilot="precision", task="disturbance", **kw):
    spec = draw_trial(plant, seed, task=task, pilot=pilot, **kw)
    tr = simulate_trial(spec)
    run = Run(time=tr.time, disturbance=tr.disturbance, output=tr.output, control=tr.control,
              reference=tr.reference, id=spec.name or "trial", synthetic=True)
    pd = plants_dict(spec)
    plants = Plants(ct.tf(pd["control_to_output"]["num"], pd["control_to_output"]["den"]),
                    ct.tf(pd["disturbance_to_output"]["num"], pd["disturbance_to_output"]["den"]))
    return run, plants, tr.truth


@pytest.mark.parametrize("num,den,k", [([1], [1, 0], 1), ([1], [1, 0, 0], 2), ([1], [1, 1, 0], 2),
                                       ([3], [1, 0, 0], 2), ([2.436], [1, 1.05], 1)])
def test_k_rule(num, den, k):
    got, why = choose_k(ct.tf(num, den))
    assert got == k and f"k = {k}" in why


def test_frf_recovers_the_generators_describing_function():
    run, plants, truth = _trial("1/s", 101)
    f = estimate_frf(run, plants)
    t = truth["describing_function"]
    true = np.array(t["re"]) + 1j * np.array(t["im"])
    assert np.allclose(f.feedback.freq_rad_s, t["frequency_rad_s"])
    inside = np.abs(f.feedback.H - true) <= 2 * f.feedback.sigma
    assert inside.mean() >= 0.8, (np.abs(f.feedback.H - true) / f.feedback.sigma).round(2)
    share = truth["remnant"]["control_power_off_lines_share"]
    assert f.remnant_share == pytest.approx(share, rel=0.05)


def test_interleaved_sets_on_a_generated_trial():
    run, plants, truth = _trial("1/s", 102, task="both")
    f = estimate_frf(run, plants)
    k_d = truth["forcing"]["disturbance"]["k"]
    k_r = truth["forcing"]["target"]["k"]
    assert f.feedback.bins.tolist() == k_d and f.reference.bins.tolist() == k_r


def test_default_criterion_identification_within_tolerances():
    # Five drawn trials (remnant 10-40 %, one 45 s period each: single trials can miss by
    # the data's own noise), at least four within x1.25 and 12 deg of the truth.
    hits = []
    for i, pilot in enumerate(("hess", "precision", "hess", "precision", "hess")):
        run, plants, truth = _trial("1/s", 103 + i, pilot=pilot)
        res = identify(run, plants, "original", seed=0, with_identifiability=False,
                       criterion=DEFAULT_CRITERION, with_benchmark=False)
        wc, pm = truth["crossover"]["frequency_rad_s"], truth["crossover"]["phase_margin_deg"]
        c = res.primary_crossover
        hits.append(abs(np.log(c.frequency_rad_s / wc)) <= np.log(1.25) and abs(c.phase_margin_deg - pm) <= 12)
        assert res.stable and len(res.free) == 6 and res.k_rule.startswith("k = 1 by Hess's rule")
    assert sum(hits) >= 4, hits


def test_paper_criterion_is_the_default_of_the_library_and_unchanged():
    run, plants, _ = _trial("1/s", 104)
    a = identify(run, plants, "original", seed=1, passes=2, restarts=1, with_benchmark=False,
                 with_identifiability=False)
    b = identify(run, plants, "original", seed=1, passes=2, restarts=1, with_benchmark=False,
                 with_identifiability=False, criterion="paper", k=1)
    assert a.criterion == "paper" and a.fitness == b.fitness and a.parameters == b.parameters
    assert a.free == ("Ke", "K1", "K2")


def test_criterion_reaches_compare_and_the_pipeline(monkeypatch, tmp_path):
    import hesspipe.identification.fit as ident
    from hesspipe.core.formats import write_run
    from hesspipe.pilots.compare import PilotsConfig, compare_pilots

    run, plants, _ = _trial("1/s", 105, T_m=24.0, run_in=5.0)
    write_run(tmp_path / "p1.csv", run, ("synthetic: hesspipe.humanlike",))
    seen = []
    real = ident.identify

    def spy(*args, **kw):
        seen.append(kw.get("criterion", "paper"))
        return real(*args, **kw)

    monkeypatch.setattr(ident, "identify", spy)
    # resample: write_run's 60 Hz times are refused as non-uniform until issue 8 lands
    result = compare_pilots(tmp_path, plants, workers=1, criterion="df", restarts=1, resample=True)
    assert result.ok and seen and set(seen) == {"df"}
    p = result.pilots[0]
    assert p.original["criterion"] == "df" and p.expanded_fixed["criterion"] == "df"
    assert result.to_dict()["settings"]["criterion"] == "df" and p.frf is not None
    assert PilotsConfig.from_table({"criterion": "output"}, "x.toml").criterion == "output"
    assert PilotsConfig().criterion == DEFAULT_CRITERION


def test_identify_cli_prints_the_choices_and_the_df_figure(tmp_path, capsys):
    import json

    from hesspipe.cli import main
    from hesspipe.humanlike import write_trial

    spec = draw_trial("1/(s(s+1))", 106, pilot="precision", style="plain", name="cli")
    path = write_trial(tmp_path, simulate_trial(spec))
    rc = main(["identify", str(path), "--plants", str(tmp_path / "plants.json"),
               "--json", str(tmp_path / "r.json"), "--figure", str(tmp_path / "f.png")])
    out = capsys.readouterr().out
    assert rc == 0, out
    assert "k = 2 by Hess's rule" in out and "criterion df" in out and "nonparametric" in out
    assert "same criterion and units" in out
    d = json.loads((tmp_path / "r.json").read_text())
    assert d["criterion"] == "df" and d["nonparametric"]["crossover"]["frequency_rad_s"] > 0
    assert (tmp_path / "f.png").stat().st_size > 0
    with pytest.raises(SystemExit) as exc:
        main(["identify", str(path), "--plants", str(tmp_path / "plants.json"), "--criterion", "nope"])
    assert exc.value.code == 2
