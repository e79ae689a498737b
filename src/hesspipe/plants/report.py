"""The plants stage's report: descriptions of transfer functions, ``plants_report.json``
and ``plants_report.md`` of the ARX fit (:func:`hesspipe.plants.fit.fit_plants`) and of
the analytic aircraft (:func:`hesspipe.plants.fit.analytic_plants`).
"""

from __future__ import annotations

import control as ct
import numpy as np

from ..core.formats import tf_coefficients
from ..core.paper import EQ16 as PAPER_EQ16
from .analytic import AnalyticPlants, dimensional_derivatives, modes

UNITS = {"control_to_output": "aileron_cmd (normalised -1..1, positive -> positive roll rate) "
                              "-> roll rate (rad/s)",
         "disturbance_to_output": "lateral wind (ft/s, positive towards the right wing) "
                                  "-> roll rate (rad/s)"}


# -- descriptions of transfer functions ---------------------------------------------------

def roots_table(roots) -> list[dict]:
    """Continuous roots with natural frequency (rad/s) and damping ratio.

    Parameters
    ----------
    roots : array_like of complex
        Roots in the s-plane, rad/s (poles or zeros of a continuous tf).

    Returns
    -------
    list of dict
        One per real root or conjugate pair (the pair listed once, by its
        root with ``im >= 0``), sorted by ``|root|``: ``re``, ``im`` (rad/s),
        ``wn_rad_s`` = ``|root|`` and ``zeta`` = ``-re / wn`` (positive =
        stable; None for a root at the origin).
    """
    out = []
    for r in sorted(np.atleast_1d(roots), key=lambda z: (abs(z), z.imag)):
        if r.imag < -1e-12:
            continue  # conjugate listed once
        wn = abs(r)
        out.append({"re": float(r.real), "im": float(r.imag), "wn_rad_s": float(wn),
                    "zeta": float(-r.real / wn) if wn > 0 else None})
    return out


def describe_tf(sys: ct.TransferFunction) -> dict:
    """Coefficients, poles, zeros (with wn, zeta) and DC gain of a continuous SISO tf.

    Parameters
    ----------
    sys : control.TransferFunction
        Continuous-time, single-input single-output.

    Returns
    -------
    dict
        ``num``, ``den`` (descending powers of s), ``poles`` and ``zeros``
        (:func:`roots_table` rows) and ``dc_gain`` (the tf's units; None if
        infinite, e.g. a pole at s = 0).
    """
    co = tf_coefficients(sys)
    num, den = np.array(co["num"]), np.array(co["den"])
    zeros = np.roots(np.trim_zeros(num, "f")) if np.any(num) else np.array([])
    dc = ct.dcgain(sys)
    return {**co, "poles": roots_table(np.roots(den)), "zeros": roots_table(zeros),
            "dc_gain": float(np.real(dc)) if np.isfinite(dc) else None}


def format_tf(sys_or_coeffs) -> str:
    """``(num) / (den)`` in descending powers of s, of a tf or a ``{"num", "den"}`` mapping.

    Parameters
    ----------
    sys_or_coeffs : control.TransferFunction or dict
        A continuous SISO tf, or a dict with ``num`` and ``den`` coefficient
        lists in descending powers of s.

    Returns
    -------
    str
        E.g. ``(1.5 s + 2) / (s^2 + 0.4 s + 1)``; coefficients to 4
        significant digits, zero terms left out.
    """
    co = sys_or_coeffs if isinstance(sys_or_coeffs, dict) else tf_coefficients(sys_or_coeffs)

    def poly(c):
        c = list(c)
        n = len(c) - 1
        terms = []
        for i, v in enumerate(c):
            if v == 0:
                continue
            p = n - i
            s = "" if p == 0 else ("s" if p == 1 else f"s^{p}")
            coef = "" if (v == 1 and s) else ("-" if (v == -1 and s) else f"{v:.4g} ")
            terms.append((coef + s).strip())
        return " + ".join(terms).replace("+ -", "- ") or "0"

    return f"({poly(co['num'])}) / ({poly(co['den'])})"


def _roots_md(rows: list[dict]) -> str:
    if not rows:
        return "none"
    parts = []
    for r in rows:
        z = f"{r['re']:.4g}" + (f" ± {abs(r['im']):.4g}j" if abs(r["im"]) > 1e-12 else "")
        zeta = "" if r["zeta"] is None else f", ζ {r['zeta']:.3f}"
        parts.append(f"{z} (ωn {r['wn_rad_s']:.4g} rad/s{zeta})")
    return "; ".join(parts)


def _channel_report(fit, config) -> dict:  # a fit.ChannelFit and its fit.PlantsConfig
    m = fit.model
    sel = fit.selection
    poles_d = np.roots(m.polynomials()[1])
    return {
        "file": fit.source, "input": fit.channel.input, "output": fit.channel.output,
        "units": UNITS[fit.channel.key],
        "trim": {"input": fit.trim_input, "output": fit.trim_output},
        "raw_dt_s": fit.raw_dt, "decimate": config.decimate, "model_dt_s": m.dt,
        "samples": {"estimation": fit.n_estimation, "validation": len(fit.time) - fit.n_estimation,
                    "validation_start_s": fit.validation_start_s},
        "orders": {"na": m.na, "nb": m.nb, "nk": m.nk},
        "criterion": {"name": sel.criterion, "value": sel.best.criterion, "focus": config.focus,
                      "variance": ("simulation error" if config.focus == "simulation"
                                   else "one-step prediction error") + " on the estimation data",
                      "n_samples": sel.n_samples, "grid_size": len(sel.candidates),
                      "max_growth_1_per_s": fit.slow_roots.limit, "growth_rate_1_per_s": m.growth_rate(),
                      "ranked": [c.to_dict() for c in sel.ranked(10)]},
        "excitation_order": sel.excitation_order,
        "fit_percent": {"estimation": fit.fit_estimation, "validation": fit.fit_validation,
                        "validation_continuous": fit.fit_validation_continuous,
                        "definition": "100 (1 - ||y - y_sim|| / ||y - mean(y)||), simulated output"},
        "residual_tests": fit.residuals.to_dict(),
        "discrete": {**m.to_dict(), "poles_z": [{"re": float(p.real), "im": float(p.imag)}
                                               for p in poles_d]},
        "continuous": describe_tf(fit.continuous),
        "conversion": {"method": "tustin (inverse bilinear)", "notes": list(fit.conversion_notes),
                       "check": fit.check.to_dict()},
        "slow_roots": fit.slow_roots.to_dict(),
    }


def _eq16_report() -> dict:
    sys = ct.tf(*PAPER_EQ16)
    return {**describe_tf(sys), "what": "paper Eq. 16: lateral wind -> roll rate, Boeing 757 "
            "(NASA Langley model), ARX fit, units as printed (not stated)"}


def _markdown(report: dict, synthetic: bool) -> str:
    lines = ["# Stage two: plants identified from the flight records", ""]
    if synthetic:
        lines += ["**SYNTHETIC DATA**: the flight records were generated by a model, not measured.", ""]
    lines += [f"Flight folder: `{report['source']['flight_dir']}`.", "",
              f"Validation data: {report['validation_data']}.", "",
              "Residual tests use the one-step residuals on the validation tail. On noise-free "
              "simulated records the residuals are model error, not noise, so they are rarely white: "
              "a failed test there says the model is not exact, the fit percent says how close it is.", ""]
    for key, ch in report["channels"].items():
        o, fp, rt = ch["orders"], ch["fit_percent"], ch["residual_tests"]
        chk = ch["conversion"]["check"]
        lines += [f"## {key}: {ch['units']}", "",
                  f"Record `{ch['file']}`, input `{ch['input']}`, output `{ch['output']}`; sample "
                  f"interval {ch['raw_dt_s']:.6g} s decimated by {ch['decimate']} to {ch['model_dt_s']:.6g} s; "
                  f"{ch['samples']['estimation']} estimation and {ch['samples']['validation']} validation "
                  f"samples (validation from t = {ch['samples']['validation_start_s']:.2f} s).", "",
                  f"- ARX orders: na = {o['na']}, nb = {o['nb']}, nk = {o['nk']} "
                  f"(chosen by {ch['criterion']['name'].upper()} = {ch['criterion']['value']:.6g} of the "
                  f"{ch['criterion']['variance']}, over {ch['criterion']['grid_size']} candidates, "
                  f"eligible if their poles grow slower than ln 2 / duration = "
                  f"{ch['criterion']['max_growth_1_per_s']:.3g} 1/s (stable on the record), "
                  f"{ch['criterion']['focus']} focus; input excitation order "
                  f"{ch['excitation_order']}; the chosen model's fastest pole: "
                  f"{ch['criterion']['growth_rate_1_per_s']:.3g} 1/s)",
                  f"- Fit (simulated output): estimation {fp['estimation']:.2f} %, **validation "
                  f"{fp['validation']:.2f} %**, continuous model on validation "
                  f"{fp['validation_continuous']:.2f} %",
                  f"- Residual whiteness ({rt['whiteness']['test']}, {100 * rt['confidence']:g} %): "
                  f"{'pass' if rt['whiteness']['pass'] else 'FAIL'} (p = {rt['whiteness']['p_value']:.3g}; "
                  f"max |r| {rt['whiteness']['max_abs']:.3g}, bound ±{rt['whiteness']['bound']:.3g}, "
                  f"{rt['whiteness']['lags_outside_bound']} of {rt['max_lag']} lags outside)",
                  f"- Residual/input independence: {'pass' if rt['independence']['pass'] else 'FAIL'} "
                  f"(p = {rt['independence']['p_value']:.3g}; max |r| {rt['independence']['max_abs']:.3g}, "
                  f"bound ±{rt['independence']['bound']:.3g}, {rt['independence']['lags_outside_bound']} "
                  f"of {2 * rt['max_lag'] + 1} lags outside)",
                  f"- Continuous vs discrete ({chk['band_hz'][0]:g}-{chk['band_hz'][1]:g} Hz): "
                  f"max {chk['max_gain_error_db']:.3f} dB, {chk['max_phase_error_deg']:.2f} deg "
                  f"(limits {chk['gain_limit_db']:g} dB, {chk['phase_limit_deg']:g} deg): "
                  f"{'pass' if chk['pass'] else 'FAIL'}",
                  "", f"Continuous: `{format_tf(ch['continuous'])}`", "",
                  f"- poles: {_roots_md(ch['continuous']['poles'])}",
                  f"- zeros: {_roots_md(ch['continuous']['zeros'])}",
                  f"- DC gain: {ch['continuous']['dc_gain']}", ""]
        sr = ch["slow_roots"]
        if sr["roots"]:
            moved = "; ".join(f"{r['kind']} {r['before']['re']:.4g}"
                              + (f" ± {abs(r['before']['im']):.4g}j" if r["before"]["im"] else "")
                              for r in sr["roots"])
            lines += [f"Right-half-plane roots slower than the record resolves (|s| < ln 2 / duration "
                      f"= {sr['limit_1_per_s']:.3g} 1/s): {moved}. Continuous validation fit as fitted "
                      f"{sr['fit_validation_continuous_as_fitted']:.2f} %, reflected into the left half "
                      f"plane {sr['fit_validation_continuous_reflected']:.2f} % (phase change up to "
                      f"{sr['max_phase_change_deg']:.2f} deg on the check band, gain unchanged); "
                      f"plants.json holds them **{'as fitted' if sr['applied'] == 'keep' else 'reflected'}** "
                      "(`slow_roots`).", ""]
        if ch["conversion"]["notes"]:
            lines += ["Conversion notes:", ""] + [f"- {n}" for n in ch["conversion"]["notes"]] + [""]
        ranked = ch["criterion"]["ranked"]
        lines += ["Best candidates:", "", "| na | nb | nk | criterion | residual variance |",
                  "|---|---|---|---|---|"]
        lines += [f"| {c['na']} | {c['nb']} | {c['nk']} | {c['criterion']:.6g} | {c['noise_variance']:.4g} |"
                  for c in ranked[:5]] + [""]
        if key == "disturbance_to_output":
            e = report["paper_eq16"]
            lines += ["For comparison, the paper's Eq. 16 (Boeing 757, NASA Langley model; its units "
                      "are not stated):", "", f"`{format_tf(e)}`", "",
                      f"- poles: {_roots_md(e['poles'])}", f"- zeros: {_roots_md(e['zeros'])}",
                      f"- DC gain: {e['dc_gain']:.4g}", ""]
    return "\n".join(lines) + "\n"


def _analytic_report(ap: AnalyticPlants, config) -> dict:  # config: fit.AnalyticConfig
    ac = ap.aircraft
    d = dimensional_derivatives(ac)
    m = modes(ac)
    eq15 = None
    if ac.paper_eq15:
        eq15 = {**describe_tf(ct.tf(*ac.paper_eq15)),
                "what": "paper Eq. 15 as printed; it does not follow from Table 4 (Eq. 14 with "
                        "Table 3 gives the rolling approximation reported here)"}
    return {
        "stage": "analytic", "synthetic": False, "aircraft": ac.name, "file": ac.path,
        "units": {"control_to_output": "aileron (rad, positive -> positive roll rate) -> roll rate (rad/s)",
                  "disturbance_to_output": UNITS["disturbance_to_output"]},
        "choice": {"control_to_output": config.control, "disturbance_to_output": config.disturbance},
        "mass_slug": ac.mass_slug,
        "dimensional_derivatives": d,
        "modes": {k: {"re": v.real, "im": v.imag} for k, v in m.items()},
        "models": {"full_control": describe_tf(ap.full_control),
                   "full_disturbance": describe_tf(ap.full_disturbance),
                   "rolling_control": describe_tf(ap.rolling_control),
                   "rolling_disturbance": describe_tf(ap.rolling_disturbance)},
        "paper_eq15": eq15,
    }


def _analytic_markdown(r: dict) -> str:
    d = r["dimensional_derivatives"]
    mo = r["modes"]
    lines = [f"# Analytic aircraft `{r['aircraft']}` (paper Tables 3-4, Eqs. 11-14)", "",
             f"From `{r['file']}`. Mass {r['mass_slug']:.1f} slug (Table 4's \"564000 slug\" is the "
             "weight in lb).", "",
             f"- q = {d['q']:.4g} lb/ft², Lδa = {d['Lda']:.4g} 1/s², Lp = {d['Lp']:.5g} 1/s, "
             f"Lβ = {d['Lb']:.4g} 1/s², Nβ = {d['Nb']:.4g} 1/s², Nr = {d['Nr']:.4g} 1/s, "
             f"Yβ = {d['Yb']:.4g} ft/s²",
             f"- Roll mode {mo['roll']['re']:.4g} 1/s; Dutch roll {mo['dutch_roll']['re']:.4g} ± "
             f"{abs(mo['dutch_roll']['im']):.4g}j 1/s; spiral {mo['spiral']['re']:.4g} 1/s", "",
             "| plant | transfer function | in plants.json |", "|---|---|---|"]
    chosen = {f"{r['choice']['control_to_output']}_control": "control_to_output",
              f"{r['choice']['disturbance_to_output']}_disturbance": "disturbance_to_output"}
    for k, v in r["models"].items():
        lines.append(f"| {k} | `{format_tf(v)}` | {chosen.get(k, '')} |")
    lines += ["", f"Units: {r['units']['control_to_output']}; {r['units']['disturbance_to_output']}.", ""]
    if r["paper_eq15"]:
        e = r["paper_eq15"]
        lines += [f"The paper's Eq. 15 prints p/δa = `{format_tf(e)}`; computed from Table 4 with Eq. 14 "
                  f"it is `{format_tf(r['models']['rolling_control'])}`. **The paper's Eq. 15 does not "
                  "follow from its Table 4**; it is shown here only for comparison and not used.", ""]
    return "\n".join(lines) + "\n"
