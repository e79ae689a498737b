"""The pilot's nonparametric describing function, from a measured run.

Multisine experiments (SPEC.md "Describing functions"): the disturbance d and
the reference r each excite their own set of lines. At the lines of a set the
pilot's describing function from displayed error e = r - y to control u is::

    H(j w_k) = U(w_k) / E(w_k)

with U, E the discrete Fourier coefficients over a window that holds an
integer number of the forcing's periods. The disturbance lines give the
feedback (error) response; reference lines give their own response (equal
to it for a purely compensatory pilot). The remnant n is everything else in
u: its share of the control power is the power at non-excited bins.

A slow drift in a forcing (the paper's turning side wind) leaks into the low
bins like 1/k: it can hide low lines, and in a closed loop its responses in e
and u leak into the lines' bins with a ratio that is not H. Lines hidden so
are found on the forcing less its straight-line trend, and every signal loses
a quadratic trend fitted jointly with the sinusoids at the lines (Frisch-Waugh:
the lines' bins zeroed before the trend's fit), which leaves the lines'
amplitudes unbiased.

Uncertainty per line: with ``U = H E + N`` near a line, ``U_j - H_k E_j`` at
the non-excited neighbours j of line k samples the remnant, so
``sigma_k^2 = mean_j |U_j - H_k E_j|^2 / |E_k|^2`` is the variance of the
complex error of H_k (circular Gaussian to first order).

Broadband inputs (the paper's side wind plus gusts) have no lines: then
``H = S_du / S_de`` from Welch cross-spectra with the disturbance as
instrument (unbiased by the remnant, which is uncorrelated with d), at the
Welch bins where d explains e and u (coherence), with the coherence-based
error ``sigma/|H| = sqrt((1 - g_du)/(2 n g_du) + (1 - g_de)/(2 n g_de))``.

Crossover of ``L = H Yc`` (:mod:`.frf_crossover`), times the exact plant:
the headline is a smoothed estimate, a low-order describing function fitted
to all lines at once, magnitude and phase jointly (:mod:`.frf_smooth`), when
its residuals are consistent with the lines' variances; otherwise a local
regression of the reliable lines around the raw crossing. Both, and the raw
crossing interpolated between the two bracketing lines, are kept in the
result, the headline's method stated in words. H at a line is ``U/E``: over one whole period this equals the
instrumental-variable form ``(U/D) / (E/D)`` with the disturbance as
instrument (D cancels bin by bin), so the remnant feedback adds scatter but
no bias there; only averaging over periods or bins would tell them apart.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from scipy import signal

from ..core.errors import HesspipeError
from ..core.formats import Run
from ._window import MIN_LINES, _lines, _window, period_note
from .frf_channels import Channels, separate_channels
from .frf_crossover import FrfCrossover, nonparametric_crossover  # noqa: F401  (re-exported)

NEIGHBOURS = 10
"""Non-excited bins each side of a line used for its remnant variance."""
MIN_COHERENCE = 0.3
"""Welch fallback: bins kept where d explains both e and u at least this much."""
@dataclass(frozen=True)
class Response:
    """A describing function at a set of frequencies.

    Attributes
    ----------
    freq_rad_s : ndarray
    H : ndarray, complex
        U/E (control units per unit of displayed error).
    sigma : ndarray
        Standard deviation of the complex error of H (same units; ``E|dH|^2``).
    bins : ndarray
        FFT bin of each line in the analysis window (Welch bins for "welch").
    error_per_forcing : ndarray, complex, optional
        E/F at the lines, F the forcing that owns them (disturbance or reference), so that
        repeated runs average U/F and E/F before the ratio
        (:func:`~hesspipe.identification.frf_average.average_frf`); None for "welch".
    """

    freq_rad_s: np.ndarray
    H: np.ndarray
    sigma: np.ndarray
    bins: np.ndarray
    error_per_forcing: np.ndarray | None = None

    def to_dict(self) -> dict:
        """JSON-ready: frequencies (rad/s), magnitude (linear and dB), phase (deg), H and sigma."""
        mag = np.abs(self.H)
        rel = np.where(mag > 0, self.sigma / np.maximum(mag, 1e-300), np.inf)
        return {"frequency_rad_s": self.freq_rad_s.tolist(),
                "magnitude": mag.tolist(), "magnitude_db": (20 * np.log10(mag)).tolist(),
                "phase_deg": np.degrees(np.unwrap(np.angle(self.H))).tolist(),
                "real": self.H.real.tolist(), "imag": self.H.imag.tolist(),
                "sigma": self.sigma.tolist(),
                "magnitude_db_std": (20 / np.log(10) * rel).tolist(),
                "phase_deg_std": np.degrees(np.arcsin(np.clip(rel, 0, 1))).tolist()}


@dataclass(frozen=True)
class Frf:
    """Result of :func:`estimate_frf`.

    Attributes
    ----------
    method : {"multisine", "welch"}
    feedback : Response
        At the disturbance lines (or Welch bins): the pilot's error response.
    reference : Response or None
        At the reference lines, when the reference has its own lines.
    remnant_share : float
        Share of the control power (mean removed) at non-excited bins, 0..1;
        for "welch", the share the disturbance does not explain,
        ``sum((1 - coh_du) S_uu) / sum(S_uu)``.
    crossover : FrfCrossover
    window : (start, length)
        Samples of the run analysed.
    repeats : dict or None
        For an average over repeated runs
        (:func:`~hesspipe.identification.frf_average.average_frf`): ``runs`` and the Birge
        ratio of each line set (``feedback``, ``reference``: the runs' scatter over what
        their remnant explains, about 1 for runs that differ by their remnant alone).
    """

    method: str
    feedback: Response
    reference: Response | None
    remnant_share: float
    crossover: FrfCrossover
    window: tuple
    dt: float
    run_id: str = ""
    synthetic: bool = False
    notes: tuple = field(default=())
    repeats: dict | None = None

    @cached_property   # the table, the JSON and the figure each ask for it
    def channels(self) -> Channels | None:
        """The error and output channels apart (:func:`~.frf_channels.separate_channels`), for
        a record with target and disturbance on their own lines; else None."""
        if self.method != "multisine" or self.reference is None:
            return None
        try:
            return separate_channels(self)
        except HesspipeError:
            return None

    def to_dict(self) -> dict:
        """JSON-ready: the method, both responses, the two channels (None without both line
        sets), the remnant share and the crossover."""
        channels = self.channels
        return {"run_id": self.run_id, "synthetic": self.synthetic, "method": self.method,
                "definition": "H = U/E, E = reference - output; feedback response at the "
                              "disturbance's lines",
                "feedback": self.feedback.to_dict(),
                "reference": None if self.reference is None else self.reference.to_dict(),
                "channels": None if channels is None else channels.to_dict(),
                "remnant_share_of_control_power": self.remnant_share,
                "crossover": self.crossover.to_dict(),
                "window": {"start_sample": int(self.window[0]), "samples": int(self.window[1]),
                           "duration_s": self.window[1] * self.dt},
                "repeats": self.repeats,
                "notes": list(self.notes)}


def _check_run(run, where: str):
    # A Run's signals are checked where it is built (one length, finite, uniform time:
    # hesspipe.core._signals); what a describing function needs beyond that is a few samples.
    if not isinstance(run, Run):
        raise HesspipeError(f"run: expected a Run (read_run reads a file), got {type(run).__name__}")
    if len(run) < 8:
        raise HesspipeError(f"{where}: {len(run)} samples; expected a record of at least 8")
    return run.dt


def _neighbour_residual_power(U, E, H, lines, all_lines, within: int | None = None,
                              bins: list | None = None) -> np.ndarray:
    """Mean ``|U_j - H_k E_j|^2`` over the NEIGHBOURS non-excited bins j each side of every
    line k (the nearest ones, skipping every excited bin): the remnant's power in U near the
    line, with ``H_k`` (one complex value per line) the response that relates U to E there.

    Parameters
    ----------
    U, E : ndarray, complex
        Fourier coefficients of control and displayed error over the analysis window.
    H : ndarray, complex
        One describing-function value per line (control units per error unit).
    lines, all_lines : ndarray of int
        Bins of the lines to evaluate; every excited bin (excluded as a neighbour).
    within : int, optional
        Only bins at most this many bins from the line (fewer neighbours where lines are
        dense, none from far above a low line); default: walk out until 2 NEIGHBOURS.
    bins : list of ndarray, optional
        The neighbours already chosen (:func:`_neighbour_bins`), one array per line.

    Returns
    -------
    ndarray
        One power per line, squared control units (per Fourier coefficient).
    """
    power = np.empty(len(lines))
    for i, nb in enumerate(bins if bins is not None else _neighbour_bins(U.size, lines, all_lines, within)):
        power[i] = np.mean(np.abs(U[nb] - H[i] * E[nb]) ** 2) if nb.size else np.nan
    return power


def _neighbour_bins(n_bins: int, lines, all_lines, within: int | None = None) -> list[np.ndarray]:
    """The unforced bins :func:`_neighbour_residual_power` averages over, one array per line."""
    excited = np.zeros(n_bins, dtype=bool)
    excited[all_lines] = True
    excited[0] = True
    out = []
    for k in lines:
        nb = []
        step = 1
        reach = 4 * NEIGHBOURS + 20 if within is None else within + 1
        while len(nb) < 2 * NEIGHBOURS and step < reach:
            for j in (k - step, k + step):
                if 0 < j < n_bins and not excited[j]:
                    nb.append(j)
            step += 1
        out.append(np.array(nb[: 2 * NEIGHBOURS], dtype=int))
    return out


def _response(U, E, F, lines, all_lines, omega) -> Response:
    H = U[lines] / E[lines]
    power = _neighbour_residual_power(U, E, H, lines, all_lines)
    sig = np.sqrt(power) / np.maximum(np.abs(E[lines]), 1e-300)
    return Response(omega[lines], H, sig, np.asarray(lines), E[lines] / F[lines])


def _welch(d, e, u, dt, where) -> Response:
    n = d.size
    nper = int(min(n // 4, 2 ** int(np.floor(np.log2(max(n // 4, 16))))))
    nper = max(nper, 64)
    if n < 2 * nper:
        raise HesspipeError(f"{where}: {n} samples is too short for the broadband (Welch) "
                            "estimate; expected at least 4 segments of 64 samples")
    kw = dict(fs=1.0 / dt, nperseg=nper, noverlap=nper // 2, window="hann", detrend="constant")
    f, sdd = signal.welch(d, **kw)
    _, see = signal.welch(e, **kw)
    _, suu = signal.welch(u, **kw)
    _, sdu = signal.csd(d, u, **kw)
    _, sde = signal.csd(d, e, **kw)
    with np.errstate(divide="ignore", invalid="ignore"):
        g_du = np.abs(sdu) ** 2 / (sdd * suu)
        g_de = np.abs(sde) ** 2 / (sdd * see)
        H = sdu / sde
    segments = 1 + (n - nper) // (nper // 2)
    keep = (f > 0) & (g_du >= MIN_COHERENCE) & (g_de >= MIN_COHERENCE) & np.isfinite(H)
    keep &= f <= 5.0  # the pilot-vehicle band (SPEC: 0-5 Hz)
    if not keep.any():
        raise HesspipeError(f"{where}: disturbance: no power at any detectable multisine line, and "
                            f"its broadband coherence with the error and the control stays below "
                            f"{MIN_COHERENCE}; expected a disturbance that drives the loop")
    rel = np.sqrt((1 - g_du[keep]) / (2 * segments * g_du[keep])
                  + (1 - g_de[keep]) / (2 * segments * g_de[keep]))
    # Remnant: the part of the control power the disturbance does not explain.
    g = np.nan_to_num(g_du[1:], nan=0.0)
    share = float(np.sum((1 - g) * suu[1:]) / np.sum(suu[1:])) if np.sum(suu[1:]) > 0 else float("nan")
    return Response(2 * np.pi * f[keep], H[keep], rel * np.abs(H[keep]), np.nonzero(keep)[0]), share


def _less_trend(x: np.ndarray, lines: np.ndarray, order: int = 2) -> np.ndarray:
    """`x` less a polynomial trend of `order`, fitted jointly with sinusoids on the FFT bins
    `lines` (so the lines' own amplitudes stay unbiased: a sinusoid over whole periods is not
    orthogonal to a ramp)."""
    n = x.size
    poly = np.vander(np.arange(n) / n - 0.5, order + 1, increasing=True)

    def off_lines(v):
        # The sinusoids on the lines' bins are the FFT's own components there: projecting
        # them out (Frisch-Waugh) is zeroing those bins, however many lines there are.
        V = np.fft.rfft(v, axis=0)
        V[lines] = 0.0
        return np.fft.irfft(V, n, axis=0)

    c = np.linalg.lstsq(off_lines(poly), off_lines(x), rcond=None)[0]
    return x - poly @ c


def _drift_lines(d: np.ndarray, r: np.ndarray | None, d_lines, r_lines):
    """The line sets found on the forcings less their straight-line trends when that reveals
    lines at bin 3 or above that the forcings as recorded hid (a drift's 1/k leakage raising
    their neighbours); else None. Bins 1-2 are not judged here: a drift and a line one or two
    periods long look alike once the trend is removed."""
    found = []
    for x, ref in ((d, d_lines), (r, r_lines)):
        if x is None or not np.ptp(x) > 0:
            found.append(ref)
            continue
        t = np.arange(x.size) - 0.5 * (x.size - 1)
        flat = x - x.mean() - t * (t @ x) / (t @ t)
        found.append(_lines(np.abs(np.fft.rfft(flat)) ** 2))
    revealed = any(np.setdiff1d(a[a >= 3], b).size for a, b in zip(found, (d_lines, r_lines)))
    return (found[0], found[1]) if revealed else None


def estimate_frf(run, plants=None, *, seed: int = 0) -> Frf:
    """The pilot's nonparametric describing function H = U/E from a run.

    Parameters
    ----------
    run : hesspipe.core.formats.Run
        Time (s, uniform), disturbance, output, control, reference.
    plants : Plants or control.TransferFunction, optional
        The control plant Yc, for the crossover of ``L = H Yc`` (NaN without).
    seed : int
        Seed of the crossover's uncertainty draws.

    Returns
    -------
    Frf

    Raises
    ------
    HesspipeError
        Gaps or non-finite values; a disturbance with no detectable line and
        no broadband coherence; a record holding fewer than two periods of
        its lowest line.
    """
    where = getattr(run, "source", "") or getattr(run, "id", "run")
    dt = _check_run(run, where)
    d = np.asarray(run.disturbance, dtype=float)
    r = np.asarray(run.reference, dtype=float)
    y = np.asarray(run.output, dtype=float)
    u = np.asarray(run.control, dtype=float)
    if not np.ptp(d) > 0 and not np.ptp(r) > 0:
        raise HesspipeError(f"{where}: disturbance: constant (no power at any frequency) and no "
                            "reference; expected a forcing function that excites the loop")
    has_r = np.ptp(r) > 0
    start, length, purity = _window(d, r if has_r else None)
    sl = slice(start, start + length)
    D = np.fft.rfft(d[sl] - d[sl].mean())
    R = np.fft.rfft(r[sl] - r[sl].mean()) if has_r else np.zeros_like(D)
    pd_, pr_ = np.abs(D) ** 2, np.abs(R) ** 2
    d_lines = _lines(pd_) if np.ptp(d) > 0 else np.zeros(0, int)
    r_lines = _lines(pr_) if has_r else np.zeros(0, int)
    # A slow drift in a forcing (the paper's turning side wind) leaks into the low bins like
    # 1/k: it can hide low lines below LINE_RATIO, and in a closed loop its responses in e and
    # u leak into the lines' bins with a ratio that is not H there. So every signal loses a
    # quadratic trend fitted jointly with the lines (the lines' amplitudes stay unbiased).
    drift = _drift_lines(d[sl], r[sl] if has_r else None, d_lines, r_lines)
    if drift is not None:
        d_lines, r_lines = drift
    u_w, e_w = u[sl], (r - y)[sl]
    both_sets = np.union1d(d_lines, r_lines).astype(int)
    if both_sets.size and both_sets.min() >= 1:
        d_w, r_w, u_w, e_w = (_less_trend(x, both_sets) for x in (d[sl], r[sl], u_w, e_w))
        D, R = np.fft.rfft(d_w - d_w.mean()), (np.fft.rfft(r_w - r_w.mean()) if has_r else np.zeros_like(D))
        pd_, pr_ = np.abs(D) ** 2, np.abs(R) ** 2
    # Interleaved sets share no bin. A bin found in both (leakage of one signal's drift, or
    # sets that do overlap) goes to the signal in which it stands out more, judged on each
    # signal's own scale: the disturbance (ft/s, or the control's units) and the target (the
    # output's units) are not comparable in raw power.
    both = np.intersect1d(d_lines, r_lines)
    if both.size:
        rel_d = pd_[both] / pd_[1:].sum()
        rel_r = pr_[both] / pr_[1:].sum()
        d_lines = np.setdiff1d(d_lines, both[rel_r > rel_d])
        r_lines = np.setdiff1d(r_lines, both[rel_r <= rel_d])
    e = r - y
    yc = None if plants is None else getattr(plants, "control_to_output", plants)
    notes = []
    if d_lines.size == 0 and r_lines.size == 0:
        fb, share = _welch(d - d.mean(), e - e.mean(), u - u.mean(), dt, where)
        notes.append("no multisine lines: Welch cross-spectra S_du/S_de (broadband disturbance)")
        cross = (nonparametric_crossover(fb, yc, seed=seed) if yc is not None else
                 FrfCrossover(*(float("nan"),) * 4, "no plants given"))
        return Frf("welch", fb, None, share, cross, (0, d.size), dt,
                   getattr(run, "id", ""), bool(getattr(run, "synthetic", False)), tuple(notes))
    lowest = min(int(x.min()) for x in (d_lines, r_lines) if x.size)
    if lowest < 2:
        f0 = lowest / (length * dt)
        raise HesspipeError(f"{where}: the record ({length * dt:.4g} s analysed) holds fewer than two "
                            f"periods of its lowest excited line ({f0:.4g} Hz, period "
                            f"{1 / f0:.4g} s); expected at least {2 / f0:.4g} s")
    U = np.fft.rfft(u_w - u_w.mean())
    E = np.fft.rfft(e_w - e_w.mean())
    omega = 2 * np.pi * np.fft.rfftfreq(length, dt)
    all_lines = np.union1d(d_lines, r_lines)
    source, owner = (d_lines, D) if d_lines.size else (r_lines, R)
    if not d_lines.size:
        notes.append("the disturbance has no lines: the feedback response is taken at the "
                     "reference's lines")
    fb = _response(U, E, owner, source, all_lines, omega)
    ref = _response(U, E, R, r_lines, all_lines, omega) if (d_lines.size and r_lines.size) else None
    pu = np.abs(U) ** 2
    quiet = np.ones(pu.size, dtype=bool)
    quiet[0] = False
    quiet[all_lines] = False
    total = pu[1:].sum()
    share = float(pu[quiet].sum() / total) if total > 0 else float("nan")
    cross = (nonparametric_crossover(fb, yc, seed=seed) if yc is not None else
             FrfCrossover(*(float("nan"),) * 4, "no plants given"))
    leaky = period_note([d, r], purity, dt)
    found = int(np.union1d(d_lines, r_lines).size)
    if start:
        # "Whole periods" only where the lines say so: a record cut to 30 % of a period read it.
        whole = leaky is None and found >= MIN_LINES
        notes.append(f"first {start} sample(s) left out" + (" so that the window holds whole periods" if whole
                                                            else ": the lines leak least over the rest"))
    if start + length < d.size:
        notes.append(f"last {d.size - start - length} sample(s) left out: the forcing stops repeating there")
    if drift is not None:
        notes.append("a slow drift in the forcing hid lines: they were found on it less its "
                     "straight-line trend")
    if leaky is not None:
        notes.append(leaky)
    if found < MIN_LINES:
        notes.append(f"only {found} forcing line(s) found in {length * dt:.4g} s: the crossover rests on "
                     f"them; a multisine record shorter than one period of its forcing (a run cut short) "
                     f"leaves few of its lines on bins, and the motion test needs {MIN_LINES}")
    return Frf("multisine", fb, ref, share, cross, (start, length), dt,
               getattr(run, "id", ""), bool(getattr(run, "synthetic", False)), tuple(notes))
