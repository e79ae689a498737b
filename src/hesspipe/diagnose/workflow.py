"""The discrepancy workflow: locate where a pilot model and measured data disagree, name
the missing effect, add it, re-identify and show the gap shrink (SPEC.md "The discrepancy
workflow").

Steps
-----
1. **Locate.** The control PSD of the identified baseline model is compared with the
   measured control PSD band by band (where the model has too much or too little power,
   by how many dB, and which bands carry most of the mismatch). The plant check drives
   the plants with the measured control and disturbance and compares the result with
   the measured output (fit percent, residual whiteness and residual/input
   independence). The same residual tests are applied to the time-domain control error
   of the model where they apply (deterministic models only: a model with a random
   remnant cannot predict the control sample by sample).
2. **Candidates.** Each candidate effect of :data:`hesspipe.pilot.effects.EFFECTS` not yet in
   the model is added and the augmented model is re-identified (core free gains plus
   all of the effect's parameters) by a grid over the new parameters followed by
   bounded least squares.
3. **Decide.** Each candidate is scored against the current model with a likelihood-
   ratio test on log-spectral residuals (see *The criterion*). The best candidate is
   named only if it is significant after a Bonferroni correction for the number of
   candidates tried in that round, its BIC improves and it is not vetoed: its Eq. 10
   gap may not rise (see *Two measures*). It is added and the round repeats until nothing
   significant is left. Aircraft-side effects are not tried here: they are judged on the
   output, by refits of the plant check (:mod:`hesspipe.diagnose.aircraft`), and motion
   feedback first on the describing function's shape (:mod:`hesspipe.diagnose.motion`).
4. **Report.** Gap (SPEC.md Eq. 10 fitness) before and after, the bands that closed.

The criterion and the two measures of the gap are described in
:mod:`hesspipe.diagnose.likelihood`.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Mapping, Sequence

import numpy as np
import scipy.optimize
import scipy.signal
import scipy.special
import scipy.stats

from ..core.errors import HesspipeError
from ..core.formats import Plants, Run, as_plants, as_runs
from ..core.paper import WELCH_SEGMENT
from ..core.seeds import check_seed
from ..identification.criteria import choose_k
from ..identification.fit import check_control
from ..identification.frf_average import check_repeats
from ..identification.lines import window_note
from ..pilot.crossover import gain_scale
from ..pilot.effects import EFFECTS, get_effect
from ..pilot.hess import PilotModel, model_from_name
from ..plants.validation import residual_tests
from .aircraft import corrected, plant_finding
from .checks import RESIDUAL_TEST_LEVEL, PlantCheck, plant_check
from .fitting import Problem, _effect, _Fit
from .motion import delay_step, df_evidence, motion_step, remnant_step
from .results import Diagnosis, Step
from .settings import DiagnoseConfig
from .spectra import _DB

# -- the workflow ---------------------------------------------------------------------------

def _check_inputs(run: Run, plants: Plants, cfg: DiagnoseConfig) -> None:
    where = run.source or run.id
    if len(run) < WELCH_SEGMENT:
        raise HesspipeError(f"{where}: {len(run)} samples; expected at least {WELCH_SEGMENT} (one Welch "
                            f"segment, {WELCH_SEGMENT * run.dt:g} s at dt {run.dt:g} s) for the control spectra")
    for key, role in (("control", "control_to_output"), ("disturbance", "disturbance_to_output")):
        declared = plants.meta.get("inputs", {}).get(role) if isinstance(plants.meta.get("inputs"), Mapping) \
            else None
        if declared is not None and declared != key:
            raise HesspipeError(f"plants: field 'inputs.{role}': expected input column '{key}' of the "
                                f"run, got {declared!r}")
    lo, hi = cfg.band_hz
    if hi > run.fs / 2:
        raise HesspipeError(f"{where}: band up to {hi:g} Hz is above the Nyquist frequency "
                            f"{run.fs / 2:g} Hz of the record")


def _untested(reason: str) -> str:
    # Said where the describing function's tests could not run: without it a truncated record
    # (half a period of the forcing) read "remnant named" and nothing about motion.
    if not reason:
        return ""
    return (f"motion feedback, extra delay and remnant not tested on the describing function: {reason}; "
            "the control-spectrum rounds below still ran")


def _veto(step: "Step", gap_now: float, check: PlantCheck) -> str:
    """Why `step`'s candidate may not be named whatever its score ("" if it may).

    * Its Eq. 10 gap is larger than the current model's (module docstring, *Two
      measures*).
    * It changes the aircraft (``where == "aircraft"``, e.g. dutch_roll) while the plant
      check passes: the plants then reproduce the measured output from the measured
      control and disturbance with a residual independent of both, which an aircraft
      mode missing from them would not allow (the check fails on such data). The
      control spectrum alone cannot always tell a lightly damped aircraft pair from a
      pilot effect of similar shape; the output can.
    """
    if not step.gap <= gap_now:
        return "gap rises"
    if _effect(step.candidate).where == "aircraft" and check.passes:
        return "aircraft effect, but the plant check passes"
    return ""


def _control_error_tests(problem: Problem, fit: _Fit) -> dict | None:
    """Residual tests on the time-domain control error ``measured - model`` (the model
    driven by the measured disturbance), for deterministic models only: with a remnant
    the error is coloured by design. Whiteness: Ljung-Box of
    :func:`hesspipe.plants.validation.residual_tests`, with its (prewhitened) independence of the
    disturbance, at :data:`.checks.RESIDUAL_TEST_LEVEL`."""
    if not fit.stable or problem.spectrum.stochastic(fit.model, fit.parameters):
        return None
    err = problem.run.control - problem.spectrum.control(fit.model, fit.parameters)
    tests = residual_tests(err, problem.run.disturbance, max_lag=problem.cfg.max_lag)
    p_ind = tests.independence_p
    return {"whiteness_p": tests.whiteness_p, "white": tests.white, "independence_p": p_ind,
            "independent": p_ind >= RESIDUAL_TEST_LEVEL, "rms": float(np.sqrt(np.mean(err ** 2)))}


def _resolve_model(model):

    if isinstance(model, PilotModel):
        return model
    if isinstance(model, str):
        return model_from_name(model)
    raise HesspipeError(f"diagnose: model: expected 'original', 'expanded' or a PilotModel, got {model!r}")


def resolve_candidates(model, candidates, cfg: DiagnoseConfig) -> tuple[str, ...]:
    """The candidate effects a diagnosis tries, checked.

    Parameters
    ----------
    model : hesspipe.pilot.hess.PilotModel
        The baseline model; its own effects are left out.
    candidates : sequence of str, str or None
        Effect ids (a comma-separated string too); None: ``cfg.candidates``, else every
        registered effect.
    cfg : DiagnoseConfig

    Returns
    -------
    tuple of str
        The ids, in order, without repeats.

    Raises
    ------
    HesspipeError
        An unknown id (naming the known ones).
    """
    if isinstance(candidates, str):
        candidates = [c.strip() for c in candidates.split(",") if c.strip()]
    chosen = candidates if candidates is not None else cfg.candidates
    if chosen is None:
        chosen = tuple(EFFECTS)
    for c in chosen:
        get_effect(c)  # unknown id -> HesspipeError naming the known ids
    return tuple(dict.fromkeys(c for c in chosen if c not in model.effects))


def _fit_baseline(run: Run, plants: Plants, cfg: DiagnoseConfig, seed: int, base: PilotModel,
                  dynamics: Mapping[str, float], k_df: int) -> tuple[_Fit, Problem, DiagnoseConfig]:
    # The baseline model fitted to the control spectrum, and the problem and settings whose
    # order k closed the loop. Starts, in order: the describing function's dynamics (the
    # pilot's own), then the defaults, first with the configured order and then with Hess's
    # rule's. The describing function's dynamics need not close the loop (an original model
    # fitted to a motion pilot's lines can land on a 3 rad/s neuromuscular mode), and the
    # configured order may not close it at all (k = 1 on a K/s^2-like plant); the
    # baseline's own parameters get the same grid start as a candidate's (the output-error
    # surface has several valleys in Ke and K1).
    for k in dict.fromkeys((cfg.k, k_df)):
        cfg = cfg if k == cfg.k else replace(cfg, k=k)
        problem = Problem(run, plants, cfg, seed)
        starts = ([{**base.defaults(k=k, gain=problem.gain), **dynamics}] if dynamics else []) + [
            base.defaults(k=k, gain=problem.gain)]
        for start in starts:
            current = problem.fit(base, start, grid=problem.free_parameters(base))
            if current.stable:
                break
        if current.stable:
            break
    if not current.stable:
        raise HesspipeError(f"{run.source or run.id}: no stable {base.name} pilot found for these data "
                            "and plants; cannot diagnose")
    return current, problem, cfg


def _spectral_rounds(problem: Problem, current: _Fit, remaining: list, named: list, steps: list,
                     max_named: int, check: PlantCheck) -> _Fit:
    # The candidates judged on the control spectrum, round by round: each fitted onto the
    # current model, the best eligible one (Bonferroni over the round, delta BIC > 0, no
    # veto) added, until none is or `named` holds `max_named`. Appends to `named` and
    # `steps`; returns the final fit.
    cfg = problem.cfg
    rnd = 0
    while remaining and len(named) < max_named:
        rnd += 1
        tried: list[tuple[Step, _Fit | None]] = []
        for cand in remaining:
            aug = current.model.with_effect(cand)
            try:
                new = tuple(p for p in _effect(cand).parameters)
                fit = problem.fit(aug, current.parameters, grid=new)
                if not fit.stable:
                    raise HesspipeError("no stable parameter set found")
            except Exception as exc:  # noqa: BLE001 — a failed candidate must not stop the others
                tried.append((Step(round=rnd, candidate=cand, model=aug.name, status="failed",
                                   error=f"{type(exc).__name__}: {exc}".splitlines()[0]), None))
                continue
            dof = len(fit.free) - len(current.free)
            stat = (current.nll - fit.nll) / problem.likelihood.enbw
            tried.append((Step(round=rnd, candidate=cand, model=aug.name, status="ok", statistic=stat,
                               dof=dof, p_value=float(scipy.stats.chi2.sf(stat, max(dof, 1))),
                               delta_bic=stat - dof * math.log(problem.likelihood.n_eff), gap=problem.likelihood.gap(fit.psd),
                               log_rms_db=problem.likelihood.log_rms_db(fit.psd), parameters=fit.parameters,
                               evaluations=fit.evaluations), fit))
        ok = [(s, f) for s, f in tried if s.status == "ok"]
        threshold = cfg.alpha / max(len(ok), 1)
        # The Eq. 10 gap a candidate may not exceed: the current model's (see the module
        # docstring, "Two measures").
        gap_now = problem.likelihood.gap(current.psd)
        tried = [(replace(s, threshold=threshold, gap_ok=bool(s.gap <= gap_now),
                          veto=_veto(s, gap_now, check)) if s.status == "ok" else s, f)
                 for s, f in tried]
        eligible = [(s, f) for s, f in tried
                    if s.status == "ok" and s.p_value < threshold and s.delta_bic > 0 and not s.veto]
        best = min(eligible, key=lambda sf: (sf[0].p_value, -sf[0].delta_bic)) if eligible else None
        accept = best is not None
        for s, f in tried:
            steps.append(replace(s, accepted=bool(accept and s is best[0])))
        if not accept:
            break
        current = best[1]
        named.append(best[0].candidate)
        remaining.remove(best[0].candidate)
    return current


def diagnose(run: Run, plants: Plants, *, model="original", candidates: Sequence[str] | str | None = None,
             seed: int = 0, config: DiagnoseConfig | None = None,
             baseline_run: Run | Sequence[Run] | None = None,
             repeat_runs: Sequence[Run] = ()) -> Diagnosis:
    """Locate the model/measurement disagreement, name missing effects, show the gap shrink.

    Parameters
    ----------
    run : Run
        Measured (or synthetic) run: disturbance (ft/s), output (rad/s), control.
    plants : Plants
        Yc (control → output) and Yd (disturbance → output).
    model : str or PilotModel
        Baseline pilot model ("original", "expanded" or a PilotModel).
    candidates : sequence of str, comma-separated str or None
        Effect ids to try (default: ``config.candidates`` or all registered effects).
    seed : int
        Base seed of any random part. The remnant is evaluated in expectation, so today
        the result does not depend on it; same inputs + seed → identical outputs.
    config : DiagnoseConfig, optional
    baseline_run : Run or sequence of Run, optional
        The same pilot flying the same aircraft in the baseline condition (a within-
        subject design). With multisine forcing in both records the visual delay is then
        tested against this run's (``config.retest_delay_sd`` allowing for a pilot's
        run-to-run spread): only so can a simulator's extra delay be told from a slow
        pilot's own, which a single record shows as one delay. A sequence: repeated
        baseline runs, whose mean delay is the pilot's.
    repeat_runs : sequence of Run
        More runs of `run`'s pilot in `run`'s condition (the same forcing). With one forcing
        function the motion test pools their describing-function lines with `run`'s, each
        run with its own gain (a human's gains move by 5-15 % between runs); with
        `baseline_run` the delay test compares the condition's mean delay with the
        baseline's (the run-to-run spread allowed shrinks with the number of runs). The
        rest of the diagnosis is `run`'s.

    Returns
    -------
    Diagnosis

    Raises
    ------
    HesspipeError
        Unknown candidate id, data too short for the spectra. Plants that do not match the
        data's columns are a finding (``plant_finding``), not an error.
    """
    cfg = config or DiagnoseConfig()
    base = _resolve_model(model)
    cands = resolve_candidates(base, candidates, cfg)
    cfg = replace(cfg, candidates=cands)  # what was actually tried, for the record

    check_seed(seed)
    if not isinstance(run, Run):
        raise HesspipeError(f"run: expected a Run (read_run reads a file), got {type(run).__name__}")
    check_control(run)
    plants = as_plants(plants)
    _check_inputs(run, plants, cfg)
    bases = [] if baseline_run is None else as_runs(baseline_run)
    repeats = as_runs(list(repeat_runs)) if repeat_runs else []
    for other in bases + repeats:
        check_control(other)
        _check_inputs(other, plants, cfg)
    persons = list(dict.fromkeys(r.person for r in (run, *repeats) if r.person))
    if len(persons) > 1:   # a long table of several persons: repeats are one person's runs
        raise HesspipeError(f"{run.source or run.id} and its repeats: runs of {len(persons)} persons "
                            f"({', '.join(persons[:4])}{', ...' if len(persons) > 4 else ''}); expected one "
                            "person's runs: diagnose every run alone")
    check_repeats([run, *repeats], others=bases)
    check = plant_check(run, plants, max_lag=cfg.max_lag)
    # A failed plant check is a finding, never a refusal: the aircraft-side candidate that
    # closes it (or the file error it proves) is named and the pilot identified around it.

    finding = plant_finding(run, plants, check, fit_ok=cfg.plant_fit_ok, alpha=cfg.alpha)
    before = None
    if finding.verdict == "aircraft":
        # "Before" is the pilot identified around the plants as given (same measured
        # spectrum), so the report shows what naming the aircraft effect closed.
        before = Problem(run, plants, cfg, seed)
        before = (before, before.fit(base, base.defaults(k=cfg.k, gain=before.gain),
                                     grid=before.free_parameters(base)))
    # The same aircraft: the same correction.
    bases = [corrected(b, plants, finding)[0] for b in bases]
    repeats = [corrected(r, plants, finding)[0] for r in repeats]
    run, plants = corrected(run, plants, finding)
    cands = tuple(c for c in cands if _effect(c).where != "aircraft")  # judged on the output above

    # Multisine lines: the describing function judges motion and delay and gives the
    # pilot's own dynamics (phase-aware); the baseline starts from them.
    k_df = choose_k(plants)[0]
    ev, no_df = df_evidence(run, plants, base.defaults(k=k_df, gain=gain_scale(plants, k_df)), k=k_df,
                            cfg=cfg, baseline_run=bases or None, repeat_runs=repeats) \
        if {"motion_feedback", "extra_delay", "remnant"} & set(cands) else (None, "")
    dynamics = {n: v for n, v in (ev.dynamics if ev else {}).items() if n not in cfg.free}
    k_df = ev.k if ev is not None and ev.k else k_df   # the order the motion test kept
    current, problem, cfg = _fit_baseline(run, plants, cfg, seed, base, dynamics, k_df)
    baseline = current
    steps: list[Step] = []
    named: list[str] = [finding.named] if finding.verdict == "aircraft" else []
    n_aircraft = len(named)
    if ev is not None:
        # The describing function's verdicts are final: the control-spectrum rounds see
        # only levels, where a baseline's other mismatches pass for a vestibular path or
        # a delay.
        for cand, judge in (("motion_feedback", motion_step), ("extra_delay", delay_step),
                            ("remnant", remnant_step)):
            if cand not in cands:
                continue
            step, fit = judge(ev, problem, current, cfg)
            steps.append(step)
            if step.accepted:
                named.append(cand)
                current = fit if fit is not None else current
            cands = tuple(c for c in cands if c != cand)
        # The otolith path is a vestibular path too, and its only evidence in the rounds
        # below would be spectral levels: on the independent generator's runs (which never
        # have one) it was named on baselines and in place of a delay. Not judged here.
        cands = tuple(c for c in cands if c != "otoliths")
    current = _spectral_rounds(problem, current, list(cands), named, steps, cfg.max_effects + n_aircraft, check)

    # Band verdicts are relative to the scatter the final model leaves (or the resolution):
    # a band disagrees if its mismatch is beyond what the rest of the record shows.
    scatter = problem.likelihood.variance(current)
    p0, baseline = (problem, baseline) if before is None or not before[1].stable else before
    return Diagnosis(
        run_id=run.id, synthetic=run.synthetic, baseline_model=base.name, final_model=current.model.name,
        named_effects=tuple(named), gap_before=p0.likelihood.gap(baseline.psd), gap_after=problem.likelihood.gap(current.psd),
        log_rms_db_before=p0.likelihood.log_rms_db(baseline.psd), log_rms_db_after=problem.likelihood.log_rms_db(current.psd),
        parameters_before=baseline.parameters, parameters_after=current.parameters, steps=tuple(steps),
        bands_before=p0.likelihood.bands(baseline.psd, scatter), bands_after=problem.likelihood.bands(current.psd, scatter),
        plant_check=check, control_error_before=_control_error_tests(p0, baseline),
        control_error_after=_control_error_tests(problem, current),
        criterion={"name": "likelihood-ratio test on log-spectral residuals over Welch bins "
                           "(Bonferroni per round), delta BIC as the score",
                   "weighting": cfg.weighting,
                   "vetoes": ["the Eq. 10 gap may not rise"],
                   "aircraft_side": "judged on the output by refits of the plant check "
                                    "(hesspipe.diagnose.aircraft), not on the control spectrum",
                   "motion_feedback": "judged first on the describing function's shape "
                                      "(hesspipe.diagnose.motion)",
                   "alpha": cfg.alpha, "n_bins": int(problem.likelihood.mask.sum()), "n_eff": problem.likelihood.n_eff,
                   "enbw_bins": problem.likelihood.enbw, "welch_dof": problem.likelihood.nu, "resolution_db": cfg.resolution_db,
                   "scatter_db": _DB * math.sqrt(scatter),
                   "welch_scatter_db": _DB * math.sqrt(problem.likelihood.var_floor)},
        config=cfg, freq_hz=problem.likelihood.freq, measured_psd=problem.likelihood.measured, baseline_psd=baseline.psd,
        final_psd=current.psd, seed=seed, source=run.source, plant_finding=finding.to_dict(),
        motion_verdict=None if ev is None else ev.motion.to_dict(),
        delay_verdict=None if ev is None else ev.delay,
        remnant_verdict=None if ev is None else ev.remnant,
        # The record's own faults first (hesspipe.core._quality): a clipped stick was named
        # a rate limit or a Dutch roll without a word in the report.
        notes=tuple(n for n in (*(m for m in run.notes if m.startswith("data check")),
                                window_note(run) if ev is not None else None, _untested(no_df),
                                *problem.run.notes[len(run.notes):]) if n),
        untested=no_df)
