"""Human-like pilots of the independent generator: structures, frequency responses, draws.

Two structures, both written from their equations (SPEC "Stage three",
McRuer's precision model), not from hesspipe's pilot code:

``precision``
    ``u = Y_NM (Kp (1 + TL s)/(1 + TI s) e^(-tau s) e - u_v)`` with
    ``Y_NM = wn^2 / (s^2 + 2 zn wn s + wn^2)`` and the optional vestibular path of
    the multimodal models fitted to motion experiments (e.g. Zaal et al.
    2009, J. Guid. Control Dyn. 32(4)): ``u_v = Km H_SCC e^(-tau_m s) M y`` with the
    canals ``H_SCC = 5.9 s (1 + 0.11 s) / ((1 + 5.9 s)(1 + 0.005 s))`` on the angular
    velocity (unit gain between 0.2 and 9 rad/s, the lead above), a different canal
    model from the hess pilot's on purpose.
``hess``
    ``delta = Y_NM (u_e - u_p - u_v)``, ``u_e = Ke e^(-tau s) e``,
    ``u_p = Y_PF delta`` with ``Y_PF = K1 K2 s / ((s + 1/T1)(s + 1/T2)^(k-1))``,
    and the optional vestibular path ``u_v = Km Y_SCC M y`` (M: output -> cab
    angular velocity, ``Y_SCC = 80*5.73 s^2 / ((1 + 80 s)(1 + 5.73 s))``).

With ``G = Y_NM / (1 + Y_NM Y_PF)`` (inner loop closed):

* visual part ``A = Ke e^(-tau s) G`` (precision: ``Kp (1 + TL s)/(1 + TI s) e^(-tau s) Y_NM``),
* vestibular part ``B = Km Y_SCC M G`` (precision: ``Km H_SCC e^(-tau_m s) M Y_NM``;
  zero without motion).

On a disturbance line (r = 0 there, so y = -e) the control is
``u = (A + B) e``: the describing function a U/E estimate measures is
``H_pe = A + B``. On a target line ``U/E = A / (1 + B Yc)``. All angles here
are in degrees; frequencies in rad/s; delays in s.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from .lti import freqresp, polymul, series

SCC = ([80 * 5.73, 0.0, 0.0], [80 * 5.73, 80 + 5.73, 1.0])
"""Hess pilot's canals (SPEC): per unit angular velocity
``80*5.73 s^2 / ((1 + 80 s)(1 + 5.73 s))``, descending powers of s."""

SCC_MULTIMODAL = ([5.9 * 0.11, 5.9, 0.0], [5.9 * 0.005, 5.9 + 0.005, 1.0])
"""Precision pilot's canals (Zaal et al. 2009): per unit angular velocity
``5.9 s (1 + 0.11 s) / ((1 + 5.9 s)(1 + 0.005 s))``, descending powers of s."""


def nm_tf(wn: float, zn: float) -> tuple:
    """Neuromuscular system ``wn^2 / (s^2 + 2 zn wn s + wn^2)``.

    Parameters
    ----------
    wn : float
        Natural frequency, rad/s.
    zn : float
        Damping ratio.

    Returns
    -------
    (num, den)
        Descending powers of s.
    """
    return [wn * wn], [1.0, 2 * zn * wn, wn * wn]


def pf_tf(p: dict) -> tuple:
    """Proprioceptive feedback ``K1 K2 s / ((s + 1/T1)(s + 1/T2)^(k-1))``.

    Parameters
    ----------
    p : dict
        ``K1``, ``K2`` (gains), ``inv_T1``, ``inv_T2`` (1/s), ``k`` (1 or 2).

    Returns
    -------
    (num, den)
        Descending powers of s.
    """
    num = [p["K1"] * p["K2"], 0.0]
    den = [1.0, p["inv_T1"]]
    if p["k"] == 2:
        den = polymul(den, [1.0, p["inv_T2"]]).tolist()
    return num, den


def equaliser_nm_tf(p: dict) -> tuple:
    """Precision pilot without delay: ``Kp (1 + TL s)/(1 + TI s) Y_NM`` (one block).

    Parameters
    ----------
    p : dict
        ``Kp`` (control per error unit), ``TL``, ``TI`` (s), ``wn`` (rad/s), ``zn``.

    Returns
    -------
    (num, den)
        Descending powers of s.
    """
    return series(([p["Kp"] * p["TL"], p["Kp"]], [p["TI"], 1.0]), nm_tf(p["wn"], p["zn"]))


def vestibular_nm_tf(motion_tf, p: dict) -> tuple:
    """Precision pilot's vestibular path without gain and delay: ``H_SCC M Y_NM`` (one block).

    Parameters
    ----------
    motion_tf : (num, den)
        Cab angular velocity per unit plant output, descending powers of s.
    p : dict
        ``wn`` (rad/s), ``zn``.

    Returns
    -------
    (num, den)
        Descending powers of s, per unit plant output.
    """
    return series(tuple(motion_tf), SCC_MULTIMODAL, nm_tf(p["wn"], p["zn"]))


FF_LAG_S = 0.2
"""Time constant of the feedforward path's second-order low-pass, s (Drop et al.'s pursuit
model: a smoothed inverse of the controlled element, 0.1-0.3 s)."""


def feedforward_nm_tf(plant_yc, kff: float, p: dict) -> tuple:
    """Pursuit feedforward on the target without delay: ``Kff Yc^-1 Y_NM / (1 + T s)^2``
    (one block; T = :data:`FF_LAG_S`).

    A pursuit display shows the target beside the output, and humans then add a path from
    the target that approximates the controlled element's inverse (Wasicko et al. 1966;
    Drop et al. 2013). Compensatory displays (the error alone) have none.

    Parameters
    ----------
    plant_yc : (num, den)
        The controlled element the pilot inverts (its nominal model), descending powers of s.
    kff : float
        Feedforward gain, a share of the full inverse (1: perfect inversion).
    p : dict
        ``wn`` (rad/s), ``zn``.

    Returns
    -------
    (num, den)
        Descending powers of s, control per unit target.
    """
    num, den = (np.atleast_1d(np.asarray(c, float)) for c in plant_yc)
    lag = polymul([FF_LAG_S, 1.0], [FF_LAG_S, 1.0])
    return series((kff * den, num), nm_tf(p["wn"], p["zn"]), ([1.0], lag))


def inner_loop(p: dict, w) -> np.ndarray:
    """``G = Y_NM / (1 + Y_NM Y_PF)`` of the hess pilot at `w`.

    Parameters
    ----------
    p : dict
        The pilot's parameters (see :func:`pf_tf`, :func:`nm_tf`).
    w : array
        Angular frequencies, rad/s.
    """
    nm = freqresp(*nm_tf(p["wn"], p["zn"]), w)
    return nm / (1.0 + nm * freqresp(*pf_tf(p), w))


def parts(p: dict, w, motion_tf=None) -> tuple[np.ndarray, np.ndarray]:
    """Visual part A(jw) and vestibular part B(jw) of a pilot (see module doc).

    `p["tau"]` is the total visual delay (pilot plus any display delay).

    Parameters
    ----------
    p : dict
        The pilot's parameters (``structure`` "precision" or "hess").
    w : array
        Angular frequencies, rad/s.
    motion_tf : (num, den), optional
        Cab motion per unit plant output (None: no vestibular part).

    Returns
    -------
    A, B : ndarray of complex
        Control per unit error (visual) and per unit output (vestibular, its sign
        as it enters the control).
    """
    w = np.asarray(w, dtype=float)
    delay = np.exp(-1j * w * p["tau"])
    if p["structure"] == "precision":
        n, d = equaliser_nm_tf(p)
        if p.get("Km", 0.0) and motion_tf is not None:
            b = p["Km"] * freqresp(*vestibular_nm_tf(motion_tf, p), w) \
                * np.exp(-1j * w * p.get("tau_m", 0.0))
        else:
            b = np.zeros(w.shape, dtype=complex)
        return freqresp(n, d, w) * delay, b
    g = inner_loop(p, w)
    a = p["Ke"] * delay * g
    if p.get("Km", 0.0) and motion_tf is not None:
        b = p["Km"] * freqresp(*SCC, w) * freqresp(*motion_tf, w) \
            * np.exp(-1j * w * p.get("tau_m", 0.0)) * g
    else:
        b = np.zeros(w.shape, dtype=complex)
    return a, b


def loop_metrics(L, w_lo: float = 0.02, w_hi: float = 200.0) -> dict:
    """Crossover and margins of an open loop given as a callable ``L(w)``.

    The crossover is the first frequency (scanning up) where |L| falls through 1;
    the phase margin ``180 + angle L(j wc)`` wrapped into (-180, 180] degrees.

    Parameters
    ----------
    L : callable
        Open loop of angular frequency (rad/s), complex values.
    w_lo, w_hi : float
        Scan range, rad/s.

    Returns
    -------
    dict
        ``frequency_rad_s``, ``phase_margin_deg``, ``n_crossings`` (downward
        crossings of |L| = 1 in the scan), ``gain_margin`` (1/|L| at the first
        phase crossover of -180 deg above wc; inf if none).
    """
    w = np.geomspace(w_lo, w_hi, 3000)
    mag = np.log(np.abs(L(w)))
    down = np.nonzero((mag[:-1] >= 0) & (mag[1:] < 0))[0]
    if not down.size:
        return {"frequency_rad_s": float("nan"), "phase_margin_deg": float("nan"),
                "n_crossings": 0, "gain_margin": float("nan")}
    i = down[0]
    wc = brentq(lambda x: np.log(np.abs(L(np.array([x]))[0])), w[i], w[i + 1], xtol=1e-10)
    pm = 180.0 + np.degrees(np.angle(L(np.array([wc]))[0]))
    pm = pm - 360.0 if pm > 180.0 else pm
    ph = np.unwrap(np.angle(L(w)))
    ph = ph - 2 * np.pi * np.round((ph[i] - np.angle(L(np.array([wc]))[0])) / (2 * np.pi))
    above = w > wc
    cross = np.nonzero(above[:-1] & (np.floor((ph[:-1] + np.pi) / (2 * np.pi))
                                      != np.floor((ph[1:] + np.pi) / (2 * np.pi))))[0]
    gm = float(np.exp(-mag[cross[0]])) if cross.size else float("inf")
    return {"frequency_rad_s": float(wc), "phase_margin_deg": float(pm),
            "n_crossings": int(down.size), "gain_margin": gm}


def _wrap180(x):
    return (x + 180.0) % 360.0 - 180.0


def _common(rng, ranges) -> dict:
    return {"tau_v": float(rng.uniform(*ranges["tau"])), "wn": float(rng.uniform(*ranges["wn"])),
            "zn": float(rng.uniform(*ranges["zn"]))}


def _accept(p, yc, motion_tf, ranges, wc, pm) -> dict | None:
    a, b = parts(p, np.array([wc]), motion_tf)
    m = loop_metrics(lambda w: sum(parts(p, w, motion_tf)) * yc(w))
    ok = (m["n_crossings"] == 1 and abs(m["frequency_rad_s"] / wc - 1) < 1e-6
          and abs(m["phase_margin_deg"] - pm) < 1e-3 and m["gain_margin"] > 1.0)
    return m if ok else None


def _equaliser(p: dict, x_deg: float, wc: float) -> None:
    """Set a precision pilot's TL/TI so the equaliser adds `x_deg` of phase at `wc`."""
    if x_deg >= 0.0:
        p["TL"], p["TI"] = float(np.tan(np.radians(x_deg)) / wc), 0.0
    else:
        p["TL"], p["TI"] = 0.0, float(np.tan(np.radians(-x_deg)) / wc)


def draw_precision(rng, yc, sign: int, order: int, ranges: dict, extra_delay: float,
                   fixed: dict, motion_tf=None, km_ratio: float = 0.0, tau_m: float = 0.0,
                   angle: bool = False) -> dict | None:
    """Draw a precision pilot whose loop crosses over at a drawn wc with a drawn PM.

    The equalisation is chosen as a human would for the plant: a lag (or
    nothing) when the plant is K/s-like near crossover (`order` <= 1), a lead
    when it is K/s^2-like. With a vestibular path (`km_ratio` > 0) the
    equaliser is whichever lead or lag (-60 to 75 deg at wc) meets the phase
    margin with the least equalisation: the cab's motion supplies lead, so
    the visual lead shrinks, as measured in motion experiments. ``Km`` is
    ``km_ratio * Kp`` (per ``wc`` on an angle display, as for the hess pilot).
    Returns None when no draw in the budget fits.

    Parameters
    ----------
    rng : numpy.random.Generator
    yc : callable
        The plant's control path of angular frequency (rad/s).
    sign : {1, -1}
        Sign that makes the plant's steady response positive.
    order : int
        The plant's slope order near crossover (1: K/s, 2: K/s^2).
    ranges : dict
        Parameter ranges, (low, high).
    extra_delay : float
        Added visual delay, s.
    fixed : dict
        Values that are not drawn.
    motion_tf : (num, den), optional
        Cab angular velocity per unit plant output.
    km_ratio : float
        Km / Kp (0: no vestibular path).
    tau_m : float
        Vestibular delay, s.
    angle : bool
        The displayed output is an angle whose rate the cab turns at.
    """
    motion = bool(km_ratio) and motion_tf is not None
    for _ in range(20):
        p = {"structure": "precision", **_common(rng, ranges), **fixed.get("common", {})}
        p["tau"] = p["tau_v"] + extra_delay
        if motion:
            p["tau_m"] = tau_m
        for _ in range(40):
            wc = float(fixed.get("wc") or rng.uniform(*ranges["wc"]))
            pm = float(fixed.get("pm") or rng.uniform(*ranges["pm"]))
            ycw = sign * yc(np.array([wc]))[0]
            x = np.array([wc])
            if not motion:
                # Closed form: the equaliser alone makes up the phase.
                nm = freqresp(*nm_tf(p["wn"], p["zn"]), x)[0]
                base = np.degrees(np.angle(ycw * nm * np.exp(-1j * wc * p["tau"])))
                need = _wrap180(-180.0 + pm - base)
                if not ((order <= 1 and -60.0 <= need <= 0.0) or (order == 2 and 0.0 < need <= 75.0)):
                    continue
                _equaliser(p, need, wc)
                p["Kp"] = 1.0
            else:
                km_ke = km_ratio / wc if angle else km_ratio
                p.update(Kp=1.0, Km=km_ke)

                def phase_err(x_deg):
                    _equaliser(p, x_deg, wc)
                    return _wrap180(np.degrees(np.angle(sum(parts(p, x, motion_tf))[0] * ycw))
                                    + 180.0 - pm)

                grid = np.linspace(-60.0, 75.0, 28)
                err = np.array([phase_err(g) for g in grid])
                idx = np.nonzero((np.sign(err[:-1]) != np.sign(err[1:]))
                                 & (np.abs(err[:-1] - err[1:]) < 90))[0]
                if not idx.size:
                    continue
                # The least equalisation that meets the margin.
                i = min(idx, key=lambda j: min(abs(grid[j]), abs(grid[j + 1])))
                _equaliser(p, brentq(phase_err, grid[i], grid[i + 1], xtol=1e-10), wc)
            h = sum(parts(p, x, motion_tf))[0]
            p["Kp"] = float(sign / abs(h * ycw))
            if motion:
                p["Km"] = float(km_ke * p["Kp"])
            if _accept(p, yc, motion_tf, ranges, wc, pm) is not None:
                return p
    return None


PF_GAIN_MAX = 30.0
"""Largest proprioceptive loop gain K1*K2 of a drawn hess pilot. Draws whose visual and
vestibular paths nearly cancel at crossover need a K1*K2 of ~150 and a Ke of ~180 to meet
the crossover (120 draws of the benchmarks' cases otherwise had 0.02-16): a stiff inner
loop no human has, which diverged in the fine-step simulation (paper plants, roll rate,
vestibular delay 0.15 s, benchmark seed 2)."""


def draw_hess(rng, yc, sign: int, order: int, ranges: dict, extra_delay: float, fixed: dict,
              motion_tf=None, km_ratio: float = 0.0, tau_m: float = 0.0,
              angle: bool = False) -> dict | None:
    """Draw a hess pilot: sample its sensory and neuromuscular parameters, then solve.

    For a drawn crossover wc and phase margin PM, the proprioceptive gain
    K1*K2 is solved so the loop phase at wc is ``-180 + PM`` and Ke so that
    ``|L(j wc)| = 1``. ``Km = km_ratio * Ke`` (vestibular gain relative to the
    visual one) when the display shows the rate the cab turns at; when it shows
    an angle (`angle`), Ke is per rad and Km per rad/s, and ``Km = km_ratio * Ke / wc``
    so that the vestibular path's share at crossover is the same as on a rate
    display (without it km_ratio 0.2-1.0 made the vestibular rate feedback up to
    4 times the visual path at crossover, whose lead no proprioceptive gain can
    cancel: most angle draws with motion failed). Returns None when no draw in the
    budget fits.

    Parameters
    ----------
    rng : numpy.random.Generator
    yc : callable
        The plant's control path of angular frequency (rad/s).
    sign : {1, -1}
        Sign that makes the plant's steady response positive.
    order : int
        The plant's slope order near crossover.
    ranges : dict
        Parameter ranges, (low, high).
    extra_delay : float
        Added visual delay, s.
    fixed : dict
        Values that are not drawn.
    motion_tf : (num, den), optional
        Cab motion per unit plant output.
    km_ratio : float
        Km / Ke.
    tau_m : float
        Vestibular delay, s.
    angle : bool
        The displayed output is an angle whose rate the cab turns at (see above).
    """
    k = 1 if order <= 1 else 2
    for _ in range(20):
        p = {"structure": "hess", **_common(rng, ranges), "k": k,
             "inv_T1": float(rng.uniform(*ranges["inv_T1"])),
             "inv_T2": float(rng.uniform(*ranges["inv_T2"])) if k == 2 else None,
             **fixed.get("common", {})}
        p["tau"] = p["tau_v"] + extra_delay
        p["tau_m"] = tau_m
        k1 = float(rng.uniform(*ranges["K1"]))
        for _ in range(40):
            wc = float(fixed.get("wc") or rng.uniform(*ranges["wc"]))
            pm = float(fixed.get("pm") or rng.uniform(*ranges["pm"]))
            ycw = sign * yc(np.array([wc]))[0]
            x = np.array([wc])
            nm = freqresp(*nm_tf(p["wn"], p["zn"]), x)[0]
            p.update(K1=1.0, K2=1.0)
            shape = freqresp(*pf_tf(p), x)[0]           # Y_PF with K1*K2 = 1
            km_ke = km_ratio / wc if angle else km_ratio   # Km / Ke
            p.update(Ke=1.0, Km=km_ke)
            outer = (np.exp(-1j * wc * p["tau"]) + (
                km_ke * freqresp(*SCC, x)[0] * freqresp(*motion_tf, x)[0]
                * np.exp(-1j * wc * tau_m) if km_ratio and motion_tf is not None else 0.0))

            def phase_err(logk):
                h = nm / (1.0 + nm * np.exp(logk) * shape) * outer
                return _wrap180(np.degrees(np.angle(h * ycw)) + 180.0 - pm)

            grid = np.linspace(np.log(1e-3), np.log(200.0), 60)
            err = phase_err(grid)
            # A sign change, not a wrap of the phase through +-180 deg.
            idx = np.nonzero((np.sign(err[:-1]) != np.sign(err[1:]))
                             & (np.abs(err[:-1] - err[1:]) < 90))[0]
            if not idx.size:
                continue
            logk = brentq(phase_err, grid[idx[0]], grid[idx[0] + 1], xtol=1e-12)
            if np.exp(logk) > PF_GAIN_MAX:
                continue
            p.update(K1=k1, K2=float(np.exp(logk)) / k1)
            num, den = pf_tf(p)
            nmn, nmd = nm_tf(p["wn"], p["zn"])
            inner = np.polyadd(polymul(nmd, den), polymul(nmn, num))
            if not np.all(np.roots(inner).real < 0):
                continue
            h = sum(parts(p, x, motion_tf))[0]
            p["Ke"] = float(sign / abs(h * ycw))
            p["Km"] = float(km_ke * p["Ke"])
            if _accept(p, yc, motion_tf, ranges, wc, pm) is not None:
                return p
    return None
