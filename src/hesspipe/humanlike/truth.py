"""The truth of a generated trial, from the generator's own formulas.

Everything here is computed analytically from the drawn parameters (the
continuous-time pilot and plant the stepper discretises), with the delay the
stepper realised (a whole number of fine steps).

Describing function: ``H_pe(jw) = A(jw) + B(jw)``, the pilot from the
displayed error e to the control u (stick) with its inner loops closed and
the vestibular path (if any) closed through the plant by y = -e, which is what
U/E measures at the disturbance lines (the target is zero there). At the
target lines U/E measures ``A / (1 + B Yc)`` (equal to H_pe without motion);
it is reported separately. Crossover: ``L = H_pe Yc`` with Yc the true
control path (actuator lag and full aircraft included; the rate limit
ignored); also with the nominal (plants-file) Yc. With ``gain_drift`` the pilot's
visual gain wanders within the run; the describing function is that of its mean
gain, and ``gain_drift`` reports the realised factor's spread over the logged window.
"""

from __future__ import annotations

import numpy as np

from . import pilots
from .lti import freqresp, tf_dict
from .simulate import delay_steps

#: Name and version of this generator, written in every truth file.
GENERATOR = "hesspipe.humanlike 1"


def outer_holds(spec) -> int:
    """Zero-order holds on the outer loop: pilot input, plant input, actuator input.

    Parameters
    ----------
    spec : TrialSpec
    """
    return 2 + (1 if spec.actuator["tau"] > 0 else 0)


def ff_delay_steps(spec, h: float) -> int | None:
    """Fine steps of the pursuit feedforward's own delay, ``round(ff_delay / h)``; None when
    the trial has no ``ff_delay`` (the feedforward then shares the visual delay's buffer).

    Parameters
    ----------
    spec : TrialSpec
    h : float
        Fine step, s.
    """
    return int(round(spec.options["ff_delay"] / h)) if "ff_delay" in spec.options else None


def _points(w, h) -> dict:
    h = np.asarray(h, dtype=complex)
    return {"frequency_rad_s": np.asarray(w).tolist(), "re": h.real.tolist(),
            "im": h.imag.tolist(), "magnitude": np.abs(h).tolist(),
            "phase_deg": np.degrees(np.unwrap(np.angle(h))).tolist()}


def realised_pilot(spec, h: float) -> dict:
    """Pilot parameters with the visual (and vestibular) delay the stepper realised.

    Parameters
    ----------
    spec : TrialSpec
    h : float
        Fine step, s.
    """
    p = dict(spec.pilot)
    holds = outer_holds(spec)
    p["tau"] = (delay_steps(p["tau"], h, holds) + holds / 2.0) * h
    p["tau_m"] = round(p.get("tau_m", 0.0) / h) * h
    return p


def pilot_frf(spec, w, h: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(H_pe, U/E at a target line)`` of the trial's pilot at `w` (rad/s).

    With `h` (fine step, s) the delays are those the stepper realised.

    Parameters
    ----------
    spec : TrialSpec
    w : array
        Angular frequencies, rad/s.
    h : float, optional
        Fine step, s.
    """
    p = realised_pilot(spec, h) if h else spec.pilot
    a, b = pilots.parts(p, np.asarray(w, dtype=float), spec.motion_tf)
    return a + b, a / (1.0 + b * spec.yc_effective(w))


def closed_loop(spec, w, h: float | None = None) -> dict:
    """Analytic steady-state responses of the loop at `w` (no remnant, linear).

    Returns complex arrays ``u_d``, ``y_d`` (per unit disturbance at its input:
    control units for a plant-input disturbance, ft/s for wind) and ``u_r``,
    ``y_r`` (per unit target).

    Parameters
    ----------
    spec : TrialSpec
    w : array
        Angular frequencies, rad/s.
    h : float, optional
        Fine step, s (delays as realised).
    """
    p = realised_pilot(spec, h) if h else spec.pilot
    w = np.asarray(w, dtype=float)
    a, b = pilots.parts(p, w, spec.motion_tf)
    yc = spec.yc_effective(w)
    yd = yc * (1.0 + 1j * w * spec.actuator["tau"]) if spec.plant.disturbance == "input" \
        else spec.plant.true.freqresp(w, 1)
    den = 1.0 + (a + b) * yc
    return {"u_d": -(a + b) * yd / den, "y_d": yd / den,
            "u_r": a / den, "y_r": a * yc / den}


def build_truth(spec, sim: dict) -> dict:
    """The truth dict written beside each trial (JSON-ready; see module doc).

    Parameters
    ----------
    spec : TrialSpec
    sim : dict
        What the stepper returned (``h``, the fine step in s, and signals).
    """
    h = sim["h"]
    p = realised_pilot(spec, h)
    lines = []
    if spec.disturbance is not None:
        lines += [(w, "disturbance") for w in spec.disturbance.w]
    if spec.target is not None and spec.task == "both":
        lines += [(w, "target") for w in spec.target.w]
    elif spec.target is not None:
        lines += [(w, "target") for w in spec.target.w]
    lines.sort()
    w = np.array([x[0] for x in lines])
    H, ue_t = pilot_frf(spec, w, h)
    df = _points(w, H)
    df["line_set"] = [x[1] for x in lines]
    t_idx = [i for i, x in enumerate(lines) if x[1] == "target"]

    def L(x):
        a, b = pilots.parts(p, x, spec.motion_tf)
        return (a + b) * spec.yc_effective(x)

    def L_nom(x):
        a, b = pilots.parts(p, x, spec.motion_tf)
        return (a + b) * freqresp(*spec.plant.nominal_yc, x)

    u, uf = sim["u"], sim["u_forcing"]
    rem = u - uf
    total = float(np.var(u))
    spectrum = np.abs(np.fft.rfft(u - u.mean())) ** 2
    forced = np.zeros(spectrum.size, dtype=bool)
    for ms in (spec.disturbance, spec.target):
        if ms is not None:
            forced[ms.k] = True
    off = float(spectrum[1:][~forced[1:]].sum() / spectrum[1:].sum())
    pilot_out = {k: v for k, v in spec.pilot.items() if v is not None}
    pilot_out["tau_realised"] = p["tau"]
    if p["structure"] == "hess":
        pilot_out["K1K2"] = p["K1"] * p["K2"]
    if spec.options.get("feedforward"):
        # The feedforward is not a drawn pilot parameter: stated here so a fit of it can be
        # scored. Its delay is its buffer's, steps x h, as tau_m (the half-step hold at the
        # block's input left out).
        steps = ff_delay_steps(spec, h)
        if steps is None:
            steps = delay_steps(spec.pilot["tau"], h, outer_holds(spec))
        pilot_out.update(Kff=spec.options["feedforward"], T_ff=pilots.FF_LAG_S, tau_ff_realised=steps * h)
    plant = spec.plant
    return {
        "synthetic": True,
        "generator": GENERATOR,
        "name": spec.name,
        "seed": spec.seed,
        "task": spec.task,
        "effects": list(spec.effects),
        "units": {"frequency": "rad/s", "delay": "s", "angle": "deg", "share": "fraction of control variance"},
        "plant": {"name": plant.name, "disturbance": plant.disturbance, "output": plant.output,
                  "nominal_control_to_output": tf_dict(plant.nominal_yc),
                  "nominal_disturbance_to_output": tf_dict(plant.nominal_yd),
                  "integrators": plant.integrators, **plant.info},
        "pilot": pilot_out,
        "motion_path": tf_dict(spec.motion_tf) if spec.motion_tf is not None else None,
        "actuator": {"tau_s": spec.actuator["tau"],
                     "rate_limit_factor": spec.actuator["rate_limit_factor"],
                     "rate_limit_per_s": sim["rate_limit_per_s"],
                     "rate_limited_fraction": sim["rate_limited_fraction"]},
        "forcing": {"fs_hz": spec.options["fs"], "T_m_s": spec.options["T_m"],
                    "run_in_s": spec.options["run_in"], "fine_step_s": h,
                    "base_frequency_rad_s": 2 * np.pi / spec.options["T_m"],
                    "w_corner_rad_s": spec.options["w_corner"],
                    "disturbance": spec.disturbance.as_dict() if spec.disturbance is not None else None,
                    "target": spec.target.as_dict() if spec.target is not None else None},
        "describing_function": df,
        "target_lines_u_over_e": _points(w[t_idx], ue_t[t_idx]) if t_idx else None,
        "crossover": pilots.loop_metrics(L),
        "crossover_nominal_plant": pilots.loop_metrics(L_nom),
        "remnant": {"share_drawn": spec.remnant["share"],
                    "share_realised": float(np.var(rem) / total) if total > 0 else 0.0,
                    "control_power_off_lines_share": off,
                    "Tn_s": spec.remnant["Tn"], "injected_at": spec.remnant["at"],
                    "gain": sim["remnant_gain"]},
        "gain_drift": {"cv": spec.options.get("gain_drift", 0.0),
                       "correlation_time_s": spec.options.get("drift_tc"),
                       "realised_mean": float(np.mean(sim["gain_factor"])),
                       "realised_sd": float(np.std(sim["gain_factor"])),
                       "realised_range": [float(np.min(sim["gain_factor"])),
                                          float(np.max(sim["gain_factor"]))]},
        **({"threshold": sim["threshold"]} if sim.get("threshold") else {}),
        "seeds": {"base": spec.seed, "remnant_noise": spec.remnant["noise_seed"],
                  "gain_drift": spec.options.get("drift_seed")},
        "style": spec.style,
    }
