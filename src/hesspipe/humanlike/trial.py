"""Draw and simulate one human-like trial (the generator's public core).

A trial is a compensatory task: ``e = r - y`` shown to the pilot, the pilot's
control ``u``, the controlled output ``y = Yc (Act(u) + d)`` for a
plant-input disturbance (or ``y = Yc Act(u) + Yd w`` for side wind), a
multisine disturbance and/or target, and the pilot's remnant. See
:func:`draw_trial` for every knob and :func:`simulate_trial` for the truth.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.signal import lfilter
from scipy.special import erfc

from ..core.errors import HesspipeError
from ..core.seeds import derive_seed
from . import forcing, pilots

# draw_trial's knobs and their checks live in ._options; re-exported here.
from ._options import EFFECT_REMNANT, EFFECTS, OPTIONS, RANGES, _checked_options  # noqa: F401
from .lti import discretise, freqresp, ss_from_tf, tf, zoh
from .plants import Plant, make_plant
from .simulate import Wiring, compile_loop, delay_steps
from .truth import build_truth, ff_delay_steps, outer_holds
from .writer import draw_style


@dataclass(frozen=True)
class TrialSpec:
    """A fully drawn trial: everything :func:`simulate_trial` needs, nothing random left.

    Attributes
    ----------
    name : str
        Trial id (file stem when written).
    seed : int
        Base seed; sub-seeds are derived from it by name.
    plant : Plant
        True and nominal dynamics.
    task : {"disturbance", "tracking", "both"}
    pilot : dict
        Pilot parameters (see :mod:`hesspipe.humanlike.pilots`); ``tau`` is the
        total visual delay in s (``tau_v`` the pilot's own plus ``extra_delay``).
    effects : tuple of str
    options : dict
        Sampling (fs Hz, T_m s, run_in s, fine_ratio), forcing and remnant settings.
    disturbance, target : Multisine or None
    remnant : dict
        ``share`` (drawn fraction of control variance), ``Tn`` (s), ``at``.
    actuator : dict
        ``tau`` (s, 0 = none), ``rate_limit_factor`` (None = no limit).
    motion_tf : (num, den) or None
        Output -> cab angular velocity: the ``motion_path`` asked for, else the plant's own
        where the pilot has motion feedback, else None.
    """

    name: str
    seed: int
    plant: Plant
    task: str
    pilot: dict
    effects: tuple
    options: dict
    disturbance: forcing.Multisine | None
    target: forcing.Multisine | None
    remnant: dict
    actuator: dict
    motion_tf: tuple | None = None
    style: dict | None = None

    def yc_effective(self, w) -> np.ndarray:
        """True control -> output response the pilot flies (actuator included).

        Parameters
        ----------
        w : array
            Angular frequencies, rad/s.
        """
        tau = self.actuator["tau"]
        return self.plant.yc(w) / (1.0 + 1j * np.asarray(w, dtype=float) * tau)

    def pilot_parts(self, w) -> tuple[np.ndarray, np.ndarray]:
        """Visual part A and vestibular part B of the pilot at `w` (rad/s).

        Parameters
        ----------
        w : array
            Angular frequencies, rad/s.
        """
        return pilots.parts(self.pilot, w, self.motion_tf)


@dataclass(frozen=True)
class Trial:
    """A simulated trial: logged signals over the measurement window and the truth.

    Arrays (length fs*T_m, with the logged run-in's samples before them and the run-out's after
    when the trial was drawn with ``logged_run_in`` or ``logged_run_out``): ``time`` (s from the
    record's start), ``disturbance``
    (input of Yd: control units for a plant-input disturbance, ft/s for side
    wind), ``output`` (controlled variable), ``control`` (pilot's stick, remnant
    included), ``reference`` (target r; zeros without one).

    Attributes
    ----------
    spec : TrialSpec
        What was drawn.
    time, disturbance, output, control, reference : ndarray
        The logged signals (see above).
    truth : dict
        The true pilot, plant and responses (JSON-ready).
    gain_factor : ndarray
        The visual gain's factor at the logged instants (ones for a steady pilot; not
        written to files: the wander's realisation, for studies of it).
    """

    spec: TrialSpec
    time: np.ndarray
    disturbance: np.ndarray
    output: np.ndarray
    control: np.ndarray
    reference: np.ndarray
    truth: dict = field(repr=False)
    gain_factor: np.ndarray | None = field(default=None, repr=False)

    def to_run(self):
        """The trial as a :class:`hesspipe.core.formats.Run` in memory, labelled synthetic as
        its written files are (the signals as simulated, in the plant's units).

        Returns
        -------
        hesspipe.core.formats.Run
        """
        from ..core.formats import Run
        from .writer import LABEL

        return Run(time=self.time, disturbance=self.disturbance, output=self.output, control=self.control,
                   reference=self.reference, id=self.spec.name, synthetic=True,
                   comments=(f"{LABEL}; trial {self.spec.name}",))


def _slope_order(yc, w: float) -> int:
    """Hess's rule: integer slope of |Yc| over [w/2, 2w] (1: K/s-like, 2: K/s^2-like)."""
    m1, m2 = np.abs(yc(np.array([w / 2.0, 2.0 * w])))
    return int(min(max(round(-np.log(m2 / m1) / np.log(4.0)), 0), 2))


def draw_trial(plant, seed: int, *, task: str = "disturbance", pilot: str = "precision",
               effects=(), **overrides) -> TrialSpec:
    """Draw a human-like trial (pilot, forcing, remnant, effects) from a seed.

    Parameters
    ----------
    plant : str, dict, path or Plant
        See :func:`hesspipe.humanlike.plants.make_plant`.
    seed : int
        Base seed; the same arguments and seed give the same trial.
    task : {"disturbance", "tracking", "both"}
        Disturbance rejection (d only), target tracking (r only) or both on
        interleaved line sets (then the disturbance is output-equivalent, ``d_ratio``
        times the target's RMS at the output, unless ``d_rms`` is given).
    pilot : {"precision", "hess"}
    effects : iterable of str
        Any of ``motion_feedback`` (hess: Hess's canals; precision: the multimodal
        model's, see :mod:`hesspipe.humanlike.pilots`), ``extra_delay``,
        ``remnant`` (elevated remnant, 40-60 %), ``dutch_roll`` (plant "roll" or
        "paper"), ``actuator_lag``, ``rate_limit``.
    **overrides
        Ranges as a value or (low, high): ``tau`` (s), ``wn`` (rad/s), ``zn``,
        ``wc`` (rad/s), ``pm`` (deg), ``inv_T1``, ``inv_T2`` (1/s), ``K1``,
        ``remnant_share``, ``remnant_tn`` (s), ``w_corner`` (rad/s), ``km_ratio`` (Km/Ke;
        per crossover frequency for an angle output, see :func:`~hesspipe.humanlike.pilots.draw_hess`),
        ``extra_delay`` (s), ``actuator_tau`` (s), ``rate_limit_factor``, ``d_ratio``.
        Options: ``fs`` (Hz, 60), ``T_m`` (s, 45; fs*T_m must be whole),
        ``run_in`` (s; 15, or 60 with motion feedback or Dutch roll, whose slow modes
        - canals 5.7 s and 80 s, Dutch roll damping 0.034/s - need longer to
        settle), ``fade`` (s, 5), ``fine_ratio`` (fine steps per
        logged sample, 20), ``n_lines`` (10 per set), ``output`` ("rate"/"angle"),
        ``disturbance`` ("input"/"wind"), ``gain``, ``d_rms``, ``r_rms``,
        ``remnant_at`` ("control"/"error"), ``tau_m`` (vestibular delay, s, 0),
        ``motion_path`` ((num, den): the cab's path from the output, felt by a pilot with
        ``motion_feedback`` and stated in the plants file of every trial), ``name``, ``style``
        (CSV style; see :mod:`hesspipe.humanlike.writer`), ``pilot_params`` (a complete pilot
        dict: no pilot is drawn; its Km is dropped without ``motion_feedback``), ``gain_drift`` (0: a time-invariant pilot; else the
        coefficient of variation of the visual gain within the run, a first-order
        Gauss-Markov process of correlation time ``drift_tc``, s, 10: humans' gains wander
        over tens of seconds; a describing function averages the wander, whose sidebands
        fall on the bins next to each line), ``line_bins`` (None: :func:`~.forcing.line_sets`'
        log-spaced disturbance lines with each target line one bin above; else a pair of
        increasing line numbers, disturbance then target, multiples of ``1 / T_m`` Hz:
        a sparser layout of one's own, as two-input experiments use; a tracking-only task
        takes the first set), ``feedforward`` (0: a compensatory display; else a pursuit
        display's feedforward gain on the target, a share of the controlled element's
        inverse, :func:`~.pilots.feedforward_nm_tf`; precision pilots with a target only;
        the truth's describing function and crossover leave it out), ``ff_delay`` (s, None:
        the visual delay; else the feedforward's own delay in [0, 1] s, whole fine steps, only
        with ``feedforward``: humans' feedforward is often delayed less than their error path,
        0.05-0.25 s, Drop et al. 2013; the truth's pilot states the realised one as
        ``tau_ff_realised``, with ``Kff`` and ``T_ff``), ``threshold`` (0: none;
        else an indifference threshold on the perceived error, a dead zone whose half-width
        is this share, in [0, 1), of the displayed error's RMS in the same loop without it:
        McRuer and Jex's indifference threshold, one of the remnant's nonlinear sources; the
        truth's describing function is the linear pilot's, and the truth gives the dead
        zone's Gaussian-input gain beside it), ``logged_run_in`` (s, 0: the record is the
        measurement window; else that much of the run-in's end is logged before it, as a lab's
        logger writes the whole trial: e.g. 8.08 s before 81.92 s), ``logged_run_out`` (s, 0;
        else the logger runs on that long after the window while the forcing fades out to zero
        over it, raised cosine, and the loop answers).

    Raises
    ------
    HesspipeError
        For an unknown option, effect, task or pilot, or when no pilot in the
        draw budget meets the crossover and phase-margin ranges.
    """
    effects = tuple(effects)
    ranges, opts, line_bins, drift, drift_tc = _checked_options(effects, task, pilot, overrides)
    if not isinstance(plant, Plant):
        plant = make_plant(plant, output=opts["output"], disturbance=opts["disturbance"],
                           gain=opts["gain"], dutch_roll="dutch_roll" in effects)
    rng = {k: np.random.default_rng(derive_seed(seed, k))
           for k in ("pilot", "forcing", "remnant", "effects", "style")}
    g_eff = rng["effects"]
    extra = float(g_eff.uniform(*ranges["extra_delay"])) if "extra_delay" in effects else 0.0
    act_tau = float(g_eff.uniform(*ranges["actuator_tau"])) if "actuator_lag" in effects else 0.0
    rl = float(g_eff.uniform(*ranges["rate_limit_factor"])) if "rate_limit" in effects else None
    km_ratio = float(g_eff.uniform(*ranges["km_ratio"])) if "motion_feedback" in effects else 0.0
    motion_tf = None
    if opts["motion_path"] is not None:
        # The cab moves whether or not the pilot uses it: a no-motion trial's plants file
        # states the simulator's path too, as a laboratory's one file for both conditions does.
        motion_tf = tuple(opts["motion_path"])
    elif "motion_feedback" in effects:
        motion_tf = plant.motion()
    actuator = {"tau": act_tau, "rate_limit_factor": rl}

    def yc(w):
        return plant.yc(w) / (1.0 + 1j * np.asarray(w, dtype=float) * act_tau)

    w_ref = float(np.sqrt(ranges["wc"][0] * ranges["wc"][1]))
    ycr = yc(np.array([w_ref]))[0]
    order = _slope_order(yc, w_ref)
    sign = 1 if np.real(ycr * (1j * w_ref) ** order) >= 0 else -1
    fixed = {}
    if ranges["wc"][0] == ranges["wc"][1]:
        fixed["wc"] = ranges["wc"][0]
    if ranges["pm"][0] == ranges["pm"][1]:
        fixed["pm"] = ranges["pm"][0]
    if opts["pilot_params"] is not None:
        p = dict(opts["pilot_params"])
        if "motion_feedback" not in effects:
            p.pop("Km", None)   # a pilot without the effect feels no cab, whatever path it has
        p.setdefault("structure", pilot)
        p.setdefault("tau", p.get("tau_v", 0.0) + extra)
        p.setdefault("tau_v", p["tau"] - extra)
    elif pilot == "precision":
        p = pilots.draw_precision(rng["pilot"], yc, sign, order, ranges, extra, fixed,
                                  motion_tf, km_ratio, float(opts["tau_m"]),
                                  angle=plant.output == "angle")
    else:
        p = pilots.draw_hess(rng["pilot"], yc, sign, order, ranges, extra, fixed,
                             motion_tf, km_ratio, float(opts["tau_m"]), angle=plant.output == "angle")
    if p is None:
        raise HesspipeError(f"draw_trial: no {pilot} pilot for plant {plant.name!r} meets "
                            f"crossover {ranges['wc']} rad/s and phase margin {ranges['pm']} deg "
                            f"with delay {ranges['tau']} s (+{extra:.3g} s extra)")
    p["extra_delay"] = extra
    p["km_ratio"] = km_ratio
    k_d, k_t = line_bins or forcing.line_sets(opts["T_m"], int(opts["n_lines"]))
    g_f = rng["forcing"]
    corner = float(g_f.uniform(*ranges["w_corner"]))
    d_rms = opts["d_rms"] if opts["d_rms"] is not None else plant.d_rms
    through = None
    if task == "both":
        # Target about as large at the output as the plant's nominal disturbance would make it.
        def yd(w):
            return freqresp(*plant.nominal_yd, w)
        r_rms = opts["r_rms"] if opts["r_rms"] is not None else float(d_rms * abs(yd(np.array([0.5]))[0]))
        if opts["d_rms"] is None:
            # A two-input experiment is designed so that both line sets stand above the
            # remnant: the disturbance is output-equivalent (its lines divided by the
            # nominal disturbance path, as multisine experiments pre-filter it with the
            # inverse controlled element), d_ratio times the target's RMS at the output.
            # In closed loop it then moves the control as much as the target does at
            # every frequency. (Before, a flat disturbance of the plant's d_rms was
            # rejected by the pilot below crossover: its lines stood 1-3 times above the
            # remnant, the target's 4-15 times, and the vestibular path the two sets
            # reveal together was invisible on angle tasks.)
            ratio = float(np.random.default_rng(derive_seed(seed, "disturbance-ratio"))
                          .uniform(*ranges["d_ratio"]))
            d_rms, through = ratio * r_rms, yd
    dist = forcing.design(k_d, opts["T_m"], d_rms, g_f, w_corner=corner, through=through) \
        if task in ("disturbance", "both") else None
    if task == "both":
        targ = forcing.design(k_t, opts["T_m"], r_rms, g_f, w_corner=corner)
    elif task == "tracking":
        r_rms = opts["r_rms"] if opts["r_rms"] is not None else 1.0
        targ = forcing.design(k_d, opts["T_m"], r_rms, g_f, w_corner=corner)
    else:
        targ = None
    g_r = rng["remnant"]
    remnant = {"share": float(g_r.uniform(*ranges["remnant_share"])),
               "Tn": float(g_r.uniform(*ranges["remnant_tn"])), "at": opts["remnant_at"],
               "noise_seed": int(derive_seed(seed, "remnant-noise"))}
    if remnant["at"] not in ("control", "error"):
        raise HesspipeError(f"remnant_at: expected 'control' or 'error', got {remnant['at']!r}")
    style = opts["style"]
    if style is None:
        style = draw_style(rng["style"])
    name = opts["name"] or f"trial-{seed}"
    options = {k: opts[k] for k in ("fs", "T_m", "run_in", "fade", "fine_ratio", "n_lines",
                                    "output", "tau_m")}
    for key, most in (("logged_run_in", ("run_in", opts["run_in"])), ("logged_run_out", None)):
        if opts[key]:   # only when asked, as the feedforward below
            options[key] = _whole_samples(key, opts[key], opts["fs"], most)
    kff = opts["feedforward"]
    if kff:   # only when asked: the default draws stay byte-identical
        if isinstance(kff, bool) or not isinstance(kff, (int, float)) or not 0.0 < kff <= 1.5:
            raise HesspipeError(f"feedforward: expected a gain in (0, 1.5] (share of the inverse "
                                f"controlled element), got {kff!r}")
        if p["structure"] != "precision" or task == "disturbance":
            raise HesspipeError("feedforward: a pursuit path needs a precision pilot and a target "
                                "(task 'tracking' or 'both')")
        options["feedforward"] = float(kff)
    ffd = opts["ff_delay"]
    if ffd is not None:   # only when given, as the feedforward
        if isinstance(ffd, bool) or not isinstance(ffd, (int, float)) or not 0.0 <= ffd <= 1.0:
            raise HesspipeError(f"ff_delay: expected a delay in [0, 1] s, got {ffd!r}")
        if not kff:
            raise HesspipeError(f"ff_delay: expected a feedforward to delay (option feedforward > 0), "
                                f"got ff_delay={ffd!r} and feedforward={kff!r}")
        options["ff_delay"] = float(ffd)
    thr = opts["threshold"]
    if thr:   # only when asked, as the feedforward
        if isinstance(thr, bool) or not isinstance(thr, (int, float)) or not 0.0 < thr < 1.0:
            raise HesspipeError(f"threshold: expected a share of the error's RMS in [0, 1), got {thr!r}")
        options["threshold"] = float(thr)
    options.update(w_corner=corner, d_rms=dist.rms() if dist is not None else d_rms,
                   pilot_sign=sign, plant_order=order, gain_drift=drift, drift_tc=drift_tc,
                   drift_seed=int(derive_seed(seed, "gain-drift")))
    if line_bins is not None:
        options["line_bins"] = [k.tolist() for k in line_bins]
    return TrialSpec(name=name, seed=int(seed), plant=plant, task=task, pilot=p,
                     effects=effects, options=options, disturbance=dist, target=targ,
                     remnant=remnant, actuator=actuator, motion_tf=motion_tf, style=style)


def _whole_samples(key: str, seconds, fs: float, most: tuple[str, float] | None) -> float:
    """`seconds` (s) of a logged option: > 0, at most `most` (its name and value, s) when given,
    and a whole number of samples at `fs` (Hz)."""
    n = float(seconds) * fs
    if not 0.0 < float(seconds) <= (np.inf if most is None else most[1]) or abs(n - round(n)) > 1e-9:
        within = "> 0 s" if most is None else f"in (0, {most[0]} = {most[1]:g}] s"
        raise HesspipeError(f"{key}: expected a whole number of samples {within}, got {seconds!r}")
    return float(seconds)


def _wiring(spec: TrialSpec, h: float, rate_limit: float | None,
            threshold: float | None = None) -> Wiring:
    p = spec.pilot
    rem = ss_from_tf([1.0], [spec.remnant["Tn"], 1.0])
    blocks = {"rem": zoh(rem, h), "plant": zoh(spec.plant.true, h)}
    if spec.actuator["tau"] > 0:
        blocks["act"] = zoh(ss_from_tf([1.0], [spec.actuator["tau"], 1.0]), h)
    steps = delay_steps(p["tau"], h, outer_holds(spec))
    if p["structure"] == "precision":
        blocks["eqnm"] = zoh(ss_from_tf(*pilots.equaliser_nm_tf(p)), h)
        if p.get("Km") and spec.motion_tf is not None:
            num, den = tf(*pilots.vestibular_nm_tf(spec.motion_tf, p), "motion_path")
            if num.size >= den.size:
                raise HesspipeError("motion_path: the vestibular path canals x motion path x "
                                    "neuromuscular must be strictly proper; the motion path "
                                    "has too many zeros")
            blocks["vnm"] = zoh(ss_from_tf(num, den), h)
        if spec.options.get("feedforward"):
            ff = pilots.feedforward_nm_tf(spec.plant.nominal_yc, spec.options["feedforward"], p)
            blocks["ffnm"] = zoh(ss_from_tf(*ff), h)
    else:
        blocks["nm"] = zoh(ss_from_tf(*pilots.nm_tf(p["wn"], p["zn"])), h)
        blocks["pf"] = discretise(ss_from_tf(*pilots.pf_tf(p)), h)
        if p.get("Km") and spec.motion_tf is not None:
            blocks["motion"] = discretise(ss_from_tf(*spec.motion_tf), h)
            blocks["scc"] = discretise(ss_from_tf(*pilots.SCC), h)
    return Wiring(h=h, delay_steps=steps, pilot=p["structure"], blocks=blocks,
                  Ke=p.get("Ke", 0.0), Km=p.get("Km", 0.0),
                  motion_delay_steps=int(round(p.get("tau_m", 0.0) / h)),
                  remnant_at=spec.remnant["at"], rate_limit=rate_limit,
                  disturbance=spec.plant.disturbance,
                  gain_drift=spec.options.get("gain_drift", 0.0) > 0.0, threshold=threshold,
                  ff_delay_steps=ff_delay_steps(spec, h))


def gain_factor(spec: TrialSpec, t: np.ndarray) -> np.ndarray:
    """The visual gain's factor at times `t` (s; a regular grid): 1 without drift, else
    ``1 + cv x(t)``, x a unit-variance first-order Gauss-Markov process of correlation time
    ``drift_tc`` (exact discretisation), started in its stationary state and kept >= 0.2.

    Parameters
    ----------
    spec : TrialSpec
        Its options ``gain_drift``, ``drift_tc`` (s) and ``drift_seed``.
    t : ndarray
        Times, s, on a regular grid.
    """
    cv = spec.options.get("gain_drift", 0.0)
    if cv <= 0.0:
        return np.ones(t.size)
    a = float(np.exp(-(t[1] - t[0]) / spec.options["drift_tc"]))
    z = np.random.default_rng(spec.options["drift_seed"]).standard_normal(t.size)
    z[1:] *= np.sqrt(1.0 - a * a)
    x = lfilter([1.0], [1.0, -a], z)
    return np.maximum(1.0 + cv * x, 0.2)


def _solve_gain(uf: np.ndarray, un: np.ndarray, share: float) -> float:
    """Remnant gain g so that var(g un) / var(uf + g un) = share exactly.

    Solves ``g^2 Vn (1 - s) - 2 g C s - s Vf = 0`` (C the covariance) for g >= 0.
    """
    if share <= 0.0:
        return 0.0
    uf, un = uf - uf.mean(), un - un.mean()
    vf, vn, c = float(uf @ uf), float(un @ un), float(uf @ un)
    a, b, cc = vn * (1.0 - share), -2.0 * c * share, -share * vf
    return float((-b + np.sqrt(b * b - 4 * a * cc)) / (2 * a))


def simulate_trial(spec: TrialSpec, *, fine_ratio: int | None = None) -> Trial:
    """Simulate a drawn trial at the fine step and log it at ``spec.options["fs"]``.

    Parameters
    ----------
    spec : TrialSpec
        From :func:`draw_trial`.
    fine_ratio : int, optional
        Fine steps per logged sample (default ``spec.options["fine_ratio"]``, 20:
        1.2 kHz at 60 Hz).

    Returns
    -------
    Trial
        Logged signals over the measurement window (whole periods of every line,
        after the run-in, of which only ``logged_run_in`` s are logged) and the truth dict (see
        :func:`hesspipe.humanlike.truth.build_truth`).

    Raises
    ------
    HesspipeError
        If the simulated loop diverges (it should not for a drawn pilot).
    """

    o = spec.options
    fs, ratio = float(o["fs"]), int(fine_ratio or o["fine_ratio"])
    h = 1.0 / (fs * ratio)
    n_run = int(round(o["run_in"] * fs))
    n_log = int(round(o["T_m"] * fs))
    n_out = int(round(o.get("logged_run_out", 0.0) * fs))
    n = (n_run + n_log + n_out) * ratio
    t = (np.arange(n) - n_run * ratio) * h

    def envelope(tt):   # faded in over the run-in's start; out after the window when asked
        env = forcing.fade(tt, -n_run / fs, o["fade"])
        return env * (1.0 - forcing.fade(tt, n_log / fs, n_out / fs)) if n_out else env

    ramp = envelope(t)
    d_log = spec.disturbance(t) * ramp if spec.disturbance is not None else np.zeros(n)
    # The plant holds its input over [t_k, t_k + h): the midpoint value carries no half-step lag.
    d = spec.disturbance(t + h / 2) * envelope(t + h / 2) if spec.disturbance is not None else np.zeros(n)
    r = spec.target(t) * ramp if spec.target is not None else np.zeros(n)
    # Remnant noise is white at a fixed 10x the logging rate, held between its samples, so
    # the realisation does not depend on the fine step.
    noise_rate = 10.0 * fs
    n_noise = int(np.ceil(n * h * noise_rate)) + 1
    white = np.random.default_rng(spec.remnant["noise_seed"]).standard_normal(n_noise)
    w = white[np.floor(np.arange(n) * (h * noise_rate) + 1e-9).astype(int)]
    zeros = np.zeros(n)
    idx = n_run * ratio + np.arange(n_log) * ratio

    factor = gain_factor(spec, t)
    kv = factor.tolist() if spec.options.get("gain_drift", 0.0) > 0.0 else None   # read only then

    def sim(fn, rr, dd, ww, g):
        ys, us, acts = fn(rr.tolist(), dd.tolist(), ww.tolist(), float(g), n, kv)
        sim.actuator = np.asarray(acts)
        return np.asarray(ys), np.asarray(us)

    rate = None
    fn = compile_loop(_wiring(spec, h, None))
    y_f, u_f = sim(fn, r, d, zeros, 0.0)
    if spec.actuator["rate_limit_factor"] is not None:
        # The limit is a multiple of the RMS rate the actuator output would have without it
        # (remnant included): factor 1-2 limits about 30-5 % of the time.
        a_f = sim.actuator
        y_n, u_n = sim(fn, zeros, zeros, w, 1.0)
        g = _solve_gain(u_f[idx], u_n[idx], spec.remnant["share"])
        a_lin = (a_f + g * sim.actuator)[idx[0]:]
        rate = spec.actuator["rate_limit_factor"] * float(np.std(np.diff(a_lin) / h))
        fn = compile_loop(_wiring(spec, h, rate))
        y_f, u_f = sim(fn, r, d, zeros, 0.0)
    y_n, u_n = sim(fn, zeros, zeros, w, 1.0)
    g = _solve_gain(u_f[idx], u_n[idx], spec.remnant["share"])
    if rate is None:
        y, u = y_f + g * y_n, u_f + g * u_n      # the loop is linear: superpose
    else:
        y, u = sim(fn, r, d, w, g)
    threshold = None
    if o.get("threshold"):
        # The half-width is set by the error of the loop without the dead zone; the remnant's
        # gain is kept, so the dead zone's own share of the control shows in the truth.
        sigma_e = float(np.std((r - y)[idx]))
        threshold = {"share_of_error_rms": o["threshold"], "half_width": o["threshold"] * sigma_e,
                     "error_rms_without": sigma_e,
                     "gaussian_gain": float(erfc(o["threshold"] / np.sqrt(2.0)))}
        fn = compile_loop(_wiring(spec, h, rate, threshold["half_width"]))
        y, u = sim(fn, r, d, w, g)
    tenths = np.array([np.std(part) for part in np.array_split(y[idx], 10)])
    if not (np.all(np.isfinite(y)) and np.all(np.isfinite(u))) \
            or np.max(np.abs(y[idx])) > 1e6 * (np.max(np.abs(y_f[idx])) + 1e-12) + 1e6 \
            or np.max(tenths) > 100.0 * np.min(tenths) + 1e-12:
        # The last check: an unstable loop (a pilot re-run without the motion feedback his
        # visual gain relied on) grows alike with and without the remnant, so only its
        # growth within the record tells; no human's record grows a hundredfold. Any tenth
        # against any other: a wandering gain made a review's loop grow a thousandfold and
        # settle again before the record ended (the last tenth against the first passed it).
        raise HesspipeError(f"trial {spec.name}: the simulated loop diverged (an unstable pilot and plant)")
    sim_info = {"fine_step_s": h, "gain_factor": factor[idx],
                "remnant_gain": g, "rate_limit_per_s": rate,
                "u_forcing": u_f[idx], "u": u[idx], "h": h, "ratio": ratio, "threshold": threshold,
                "rate_limited_fraction": (None if rate is None else float(
                    np.mean(np.abs(np.diff(sim.actuator[idx[0]:])) >= rate * h * (1 - 1e-6))))}
    truth = build_truth(spec, sim_info)
    n_keep = int(round(o.get("logged_run_in", 0.0) * fs))
    log = idx[0] + (np.arange(n_keep + n_log + n_out) - n_keep) * ratio   # run-in's end, idx, run-out
    return Trial(spec=spec, time=np.arange(n_keep + n_log + n_out) / fs, disturbance=d_log[log], output=y[log],
                 control=u[log], reference=r[log], truth=truth, gain_factor=factor[log])
