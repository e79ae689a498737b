"""Motion verdict of ``diagnose`` from the describing function's shape (phase-aware).

A vestibular path changes the pilot's describing function H = U/E in gain *and* phase
around 1-5 rad/s (the canals lead the visual channel there); a control PSD sees only the
level. So motion feedback is judged here on the nonparametric describing function of
:func:`hesspipe.identification.frf.estimate_frf` (at the forcing's lines, with each line's uncertainty):
the pilot model without and with ``motion_feedback`` is fitted by the ``df`` criterion of
:mod:`hesspipe.identification.criteria` (its phase-aware free set: gains, lag corner, delay and
neuromuscular mode free, so a slower or differently equalised pilot is not mistaken for a
vestibular one), and the two are compared by a likelihood-ratio test with the lines'
common model-error variance profiled out::

    Lambda = 2 n ln(J0^2 / J1^2)      (n lines, J: RMS line error in line standard deviations)

chi-square with one degree of freedom under "no motion feedback"; named when
``p < alpha`` and its BIC (``Lambda - ln(2 n)``) improves.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import scipy.stats


@dataclass(frozen=True)
class MotionVerdict:
    """``named``: motion feedback explains the describing function's shape; ``statistic``,
    ``p_value``, ``delta_bic`` of the test; ``J0``/``J1`` the df criterion without/with it;
    ``Km`` fitted; ``n_lines`` used; ``note`` why no verdict was possible (then None tests)."""

    named: bool
    statistic: float = float("nan")
    p_value: float = float("nan")
    delta_bic: float = float("nan")
    J0: float = float("nan")
    J1: float = float("nan")
    Km: float = float("nan")
    n_lines: int = 0
    note: str = ""

    def to_dict(self) -> dict:
        return {"named": self.named, "statistic": self.statistic, "p_value": self.p_value,
                "delta_bic": self.delta_bic, "df_fitness_without": self.J0, "df_fitness_with": self.J1,
                "Km": self.Km, "n_lines": self.n_lines, "note": self.note,
                "criterion": "likelihood ratio on the describing function at the forcing lines "
                             "(df criterion, model-error variance profiled), 1 dof"}


def motion_verdict(run, plants, *, k: int = 1, seed: int = 0, alpha: float = 0.01,
                   starts: int = 2) -> MotionVerdict:
    """Test motion feedback on the describing function (see the module docstring).

    Returns a verdict with ``named = False`` and a ``note`` when the run holds no usable
    describing function (no forcing lines, too few reliable lines).
    """
    from ..core.errors import HesspipeError
    from ..identification.criteria import PHASE_AWARE_FREE, DFObjective, fit_bounds, multistart_fit, smart_start
    from ..identification.frf import estimate_frf
    from ..identification.problem import _resolve
    from ..pilot.hess import PilotModel
    from ..pilot.simulation import Simulator

    try:
        frf = estimate_frf(run, plants, seed=seed)
    except HesspipeError as exc:
        return MotionVerdict(False, note=f"no describing function: {exc}")
    sim = Simulator(plants, run.disturbance, run.dt, reference=run.reference, noise_seed=seed)
    fits = []
    for model in (PilotModel(), PilotModel().with_effect("motion_feedback")):
        free = tuple(PHASE_AWARE_FREE[int(k)]) + (("Km",) if model.effects else ())
        base, free, _, _, gain = _resolve(model, free, None, k, None, plants)
        obj = DFObjective(run, plants, model, base, frf, sim=sim)
        start = smart_start(obj, base, frf)
        if fits:  # the augmented fit starts from the baseline's optimum (nested models)
            start.update(fits[0][0])
            start["Km"] = 0.5
        values, J, stable = multistart_fit(obj, free, fit_bounds(model, free, gain), start,
                                           starts=starts, seed=seed, max_nfev=30)
        fits.append((values, J, stable, obj))
    (v0, J0, s0, obj), (v1, J1, s1, _) = fits
    n = int(obj.H.size)
    if n < 4 or not (s0 and s1):
        return MotionVerdict(False, J0=J0, J1=J1, n_lines=n,
                             note="too few reliable lines or no stable fit for a verdict")
    J1 = min(J1, J0)  # nested: the augmented optimum can only be as good
    stat = 2.0 * n * math.log(max(J0, 1e-12) ** 2 / max(J1, 1e-12) ** 2)
    p = float(scipy.stats.chi2.sf(stat, 1))
    dbic = stat - math.log(2 * n)
    return MotionVerdict(bool(p < alpha and dbic > 0), stat, p, dbic, J0, J1, float(v1.get("Km", 0.0)), n)


def motion_round(run, plants, problem, current, cands, cfg, seed):
    """For :func:`hesspipe.diagnose.workflow.diagnose`: motion feedback judged on the describing
    function's shape (:func:`motion_verdict`): (verdict, step, fit) or None when motion feedback
    is not a candidate or the run has no describing function. A named motion path is
    fitted into the model (Km from the verdict's start, on the PSD criterion) so the later
    rounds extend it; one not named there stays a candidate of the control-PSD rounds."""
    from ..identification.criteria import choose_k
    from .workflow import Step

    if "motion_feedback" not in cands:
        return None
    v = motion_verdict(run, plants, k=choose_k(plants)[0], seed=seed, alpha=cfg.motion_alpha)
    if v.note:
        return None
    aug = current.model.with_effect("motion_feedback")
    fit = problem.fit(aug, {**current.parameters, "Km": max(v.Km, 1e-3)}) if v.named else None
    fitted = bool(fit is not None and fit.stable)
    gap = problem.gap(fit.psd) if fitted else float("nan")
    # The same guard as every named effect: the Eq. 10 gap may not rise. Not significant:
    # nothing to guard (the control-PSD rounds may still try it).
    gap_ok = not fitted or gap <= problem.gap(current.psd)
    step = Step(round=0, candidate="motion_feedback", model=aug.name, status="ok",
                accepted=bool(v.named and fitted and gap_ok), statistic=v.statistic, dof=1,
                p_value=v.p_value, threshold=cfg.motion_alpha, delta_bic=v.delta_bic, gap=gap,
                gap_ok=gap_ok, veto="" if gap_ok else "gap rises",
                log_rms_db=problem.log_rms_db(fit.psd) if fitted else float("nan"),
                parameters=fit.parameters if fitted else {"Km": v.Km},
                evaluations=fit.evaluations if fit is not None else 0)
    return v, step, fit
