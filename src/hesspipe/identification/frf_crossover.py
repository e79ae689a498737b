"""The nonparametric crossover of ``L = H Yc`` from a measured describing function.

Two estimates, both times the exact plant:

* the smoothed estimate (the headline when it holds): a global low-order
  describing function fitted to all lines at once, magnitude and phase
  jointly (:mod:`hesspipe.identification.frf_smooth`), crossed with 1; its
  uncertainty from the fit's linearised covariance. It is used when the
  fit's residuals are consistent with the lines' variances (chi-square
  p >= 1e-4);
* the local regression (the headline otherwise, and always kept beside it):
  started at the raw crossing (the highest pair of reliable lines where |L|
  falls through 1), the reliable lines around it, each weighted by its
  inverse variance and its distance in ln w (see :func:`_cross`); its
  uncertainty is the spread over seeded draws of H from its error model.

The raw crossing, interpolated between the two bracketing lines, is kept
too. Split from :mod:`hesspipe.identification.frf`, which re-exports
:class:`FrfCrossover` and :func:`nonparametric_crossover`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..core.seeds import derive_seed
from ..pilot.blocks import from_tf
from ..pilot.crossover import FlatBand, flat_band, phase_margin_deg
from .frf_smooth import consistent, fit_smooth, smooth_crossover

DRAWS = 400
"""Draws of the lines' H from their error model for the local crossover's spread (seeded by
the caller's seed). Not :data:`.frf_smooth.DRAWS`: those are loops drawn from a smooth fit's
covariance, the same on every call."""
RELIABLE = 0.5
"""Lines with a relative error sigma/|H| above this are left out of the crossover."""
KERNEL = 0.7
"""Width (in ln w) of the Gaussian kernel that weights the lines in the crossover's local fit."""
KERNELS = (KERNEL, 0.5, 0.35, 0.25)
MAX_MISFIT = 4.0
"""The kernel is narrowed (KERNELS) while the local fit's mean square residual exceeds this
many line variances (an RMS residual above two standard deviations)."""
SPAN = 2.0
"""The smooth loop's crossing is sought within this factor of the previous estimate."""
ILL_SPREAD = 0.25
"""A crossover in a wide flat band (:class:`~hesspipe.pilot.crossover.FlatBand`) is ill-defined
when its standard deviation exceeds this share of it: its 95 % interval then spans a factor of
about three, the flat band's own width, so noise, not the pilot, places the crossing."""


@dataclass(frozen=True)
class FrfCrossover:
    """Nonparametric crossover of ``L = H Yc`` (NaN if |L| does not fall through 1 between lines).

    Attributes
    ----------
    frequency_rad_s : float
        The headline crossover frequency (rad/s): the smoothed estimate when `estimate` is
        "smoothed", else the local regression's.
    phase_margin_deg : float
        ``180 + angle L(j wc)`` there (deg, wrapped into (-180, 180]).
    frequency_std : float
        Its standard deviation (rad/s; inf when most draws or a perturbed fit find no crossing).
    phase_margin_std_deg : float
        Standard deviation of the phase margin (deg).
    note : str
        Why the crossover is NaN or very uncertain; empty otherwise.
    raw_frequency_rad_s, raw_phase_margin_deg : float
        The raw crossing: |L| and its phase interpolated linearly in ln w between
        the two reliable lines where |L| last falls through 1 (rad/s, deg).
    estimate : {"smoothed", "local"}
        Which estimate the headline is.
    local : tuple
        The local regression's (frequency rad/s, phase margin deg, their stds).
    smooth : dict
        The smooth fit: ``parameters``, ``chi2``, ``dof``, ``p_value``, ``consistent`` and its
        crossover (``frequency_rad_s``, ``phase_margin_deg``, stds and ``flat_band``); empty
        without one.
    flat_band : hesspipe.pilot.crossover.FlatBand or None
        Where |L| stays near 1 around the headline crossover: of the smooth fit's loop, or of
        the reliable lines for the local regression.
    """

    frequency_rad_s: float
    phase_margin_deg: float
    frequency_std: float
    phase_margin_std_deg: float
    note: str = ""
    raw_frequency_rad_s: float = float("nan")
    raw_phase_margin_deg: float = float("nan")
    estimate: str = "local"
    local: tuple = (float("nan"),) * 4
    smooth: dict = field(default_factory=dict)
    flat_band: FlatBand | None = None

    @property
    def ill_defined(self) -> bool:
        """The flat band is wide and the crossover's standard deviation above :data:`ILL_SPREAD`
        of it: the crossover and phase margin are then no stable measure of the loop."""
        return (self.flat_band is not None and self.flat_band.wide
                and not self.frequency_std <= ILL_SPREAD * self.frequency_rad_s)

    def to_dict(self) -> dict:
        """JSON-ready fields, with the method of each estimate in words.

        Returns
        -------
        dict
        """
        if self.estimate == "smoothed":
            method = ("smoothed: K e^(-tau s) (1 + TL s)/(1 + TI s) wn^2/(s^2 + 2 zn wn s + wn^2) "
                      "fitted to all lines at once (weighted complex least squares, weights "
                      "1/sigma^2, Cauchy loss, literature bounds, weak priors on tau, wn, zn), its "
                      "first fall of |L| through 1 with the exact plant; std from the fit's "
                      "linearised covariance. Taken because the fit's residuals are consistent "
                      f"with the lines' variances (chi-square p = {self.smooth.get('p_value', 0):.3g})")
        else:
            why = ("no smooth fit" if not self.smooth else
                   "the smooth fit's residuals are not consistent with the lines' variances "
                   f"(chi-square p = {self.smooth['p_value']:.3g})" if not self.smooth["consistent"]
                   else "the smooth fit finds no crossing")
            method = (f"local regression ({why}): " + LOCAL_METHOD)
        lw, lp, lws, lps = self.local
        return {"frequency_rad_s": self.frequency_rad_s, "phase_margin_deg": self.phase_margin_deg,
                "frequency_std_rad_s": self.frequency_std,
                "phase_margin_std_deg": self.phase_margin_std_deg, "note": self.note,
                "estimate": self.estimate, "method": method, "ill_defined": self.ill_defined,
                "flat_band": None if self.flat_band is None else self.flat_band.to_dict(),
                "local_regression": {"frequency_rad_s": lw, "phase_margin_deg": lp,
                                     "frequency_std_rad_s": lws, "phase_margin_std_deg": lps,
                                     "method": LOCAL_METHOD},
                "smooth_fit": dict(self.smooth),
                "raw_interpolated_frequency_rad_s": self.raw_frequency_rad_s,
                "raw_interpolated_phase_margin_deg": self.raw_phase_margin_deg,
                "raw_method": "|L| and phase interpolated linearly in ln w between the two reliable "
                              "lines where |L| last falls through 1 (noisier; for reference)"}


LOCAL_METHOD = ("the reliable lines around the crossing (ln|H| quadratic in ln w, phase c0 + c1 w "
                "+ c2 ln w; weights: inverse variance times a Gaussian kernel of width "
                f"{KERNEL} in ln w) times the exact plant; std over {DRAWS} seeded draws of H from "
                "its error model")


def nonparametric_crossover(resp, yc, *, seed: int = 0) -> FrfCrossover:
    """Crossover of ``L = H Yc`` at the response's frequencies, with its uncertainty.

    The smoothed estimate (:mod:`.frf_smooth`) when its fit is consistent with the
    lines' variances and crosses; else the local regression (module doc). Both,
    and the raw crossing, are kept in the result.

    Parameters
    ----------
    resp : hesspipe.identification.frf.Response
    yc : control.TransferFunction or Block
        The control plant (input of Yc: the pilot's control).
    seed : int
        Seed of the local regression's draws behind its standard deviation (neither estimate,
        nor the smoothed one's spread, depends on it).

    Returns
    -------
    FrfCrossover
    """
    block = yc if hasattr(yc, "response") else from_tf(yc)
    local = _local_crossover(resp, block, seed)
    fit = fit_smooth(resp.freq_rad_s, resp.H, resp.sigma)
    if fit is None:
        return local
    wc, pm, wc_std, pm_std, band = smooth_crossover(fit, block, resp.freq_rad_s)
    ok = consistent(fit)
    smooth = {"parameters": fit.params, "chi2": fit.chi2, "dof": fit.dof,
              "p_value": fit.p_value, "consistent": ok, "frequency_rad_s": wc,
              "phase_margin_deg": pm, "frequency_std_rad_s": wc_std, "phase_margin_std_deg": pm_std,
              "flat_band": None if band is None else band.to_dict()}
    if ok and np.isfinite(wc):
        out = replace(local, frequency_rad_s=wc, phase_margin_deg=pm, frequency_std=wc_std,
                      phase_margin_std_deg=pm_std, estimate="smoothed", smooth=smooth, flat_band=band,
                      note="smoothed crossover very uncertain" if not np.isfinite(wc_std) else "")
        return _with_band_note(out)
    return replace(local, smooth=smooth)


def _local_crossover(resp, block, seed: int) -> FrfCrossover:
    """The local regression's crossover with its draw-based std (the module doc's second estimate)."""
    w = resp.freq_rad_s
    nan = float("nan")
    if w.size < 2:
        return FrfCrossover(nan, nan, nan, nan, "fewer than two lines")
    order = np.argsort(w)
    w = w[order]
    H0 = resp.H[order]
    sig = resp.sigma[order]
    rel = sig / np.maximum(np.abs(H0), 1e-300)
    grid = np.logspace(np.log10(w[0] / SPAN), np.log10(w[-1] * SPAN), 600)
    yc_grid = block.response(1j * grid)
    plant = (grid, np.log(np.abs(yc_grid)), np.unwrap(np.angle(yc_grid)), block.response(1j * w))
    # Precise lines (little remnant) can show curvature the local model cannot follow (a
    # neuromuscular peak within the kernel): narrow the kernel until it fits them.
    # A noisy high line can make |L| fall through 1 far above the loop's crossover, where the
    # smooth fit then finds none: try the raw falls from the highest down.
    wc = pm = nan
    for start in _starts(w, H0, rel, plant[3]):
        for kernel in KERNELS:
            wc, pm, misfit = (float(x[0]) for x in _cross(w, H0, rel, plant, kernel, start))
            if misfit <= MAX_MISFIT:
                break
        if np.isfinite(wc):
            break
    ok_lines = rel < RELIABLE
    raw = _raw_cross(w[ok_lines], H0[ok_lines], plant[3][ok_lines]) if ok_lines.sum() >= 2 \
        else (nan, nan)
    if not np.isfinite(wc):
        mag = np.abs(H0 * plant[3])
        note = ("|L| > 1 at every line: crossover above the highest line" if np.all(mag > 1) else
                "|L| < 1 at every line: crossover below the lowest line" if np.all(mag < 1) else
                "|L| does not fall through 1 between reliable lines")
        return FrfCrossover(nan, nan, nan, nan, note, *raw)
    rng = np.random.default_rng(derive_seed(seed, "frf-crossover"))
    noise = (rng.standard_normal((DRAWS, w.size)) + 1j * rng.standard_normal((DRAWS, w.size))) / np.sqrt(2)
    arr = np.column_stack(_cross(w, H0 + sig * noise, rel, plant, kernel, start)[:2])
    ok = np.isfinite(arr[:, 0])
    if ok.sum() < DRAWS // 2:
        return FrfCrossover(wc, pm, float("inf"), float("inf"),
                            "crossover not found in most draws: very uncertain", *raw,
                            local=(wc, pm, float("inf"), float("inf")))
    dpm = (arr[ok, 1] - pm + 180.0) % 360.0 - 180.0
    sd = (float(np.std(arr[ok, 0])), float(np.std(dpm)))
    band = flat_band(w[ok_lines], (H0 * plant[3])[ok_lines], wc)
    return _with_band_note(FrfCrossover(wc, pm, *sd, "", *raw, local=(wc, pm, *sd), flat_band=band))


def _with_band_note(c: FrfCrossover) -> FrfCrossover:
    if not c.ill_defined:
        return c
    note = (f"crossover ill-defined: {c.flat_band.describe()}; its spread over draws is "
            f"{c.frequency_std:.2g} rad/s")
    return replace(c, note="; ".join(n for n in (c.note, note) if n))


def _wls(X, y, wt):
    """Weighted least squares ``y ~ X c`` row by row (X: (D, n, p), y, wt: (D, n)); c: (D, p)."""
    Xw = X * wt[..., None]
    A = np.einsum("dnp,dnq->dpq", Xw, X)
    return np.linalg.solve(A + 1e-12 * np.eye(X.shape[-1]), np.einsum("dnp,dn->dp", Xw, y)[..., None])[..., 0]


def _mag_basis(w, w0):
    x = np.log(w / w0)
    return np.stack((np.ones_like(x), x, x * x), axis=-1)


def _phase_basis(w, w0):
    x = np.log(w / w0)
    return np.stack((np.ones_like(x), w - w0 + 0 * x, x), axis=-1)


def _down(x, f):
    """Highest x where f (sampled at x, ascending) falls through 0, linearly interpolated."""
    down = np.nonzero((f[:-1] > 0) & (f[1:] <= 0))[0]
    if down.size == 0:
        return float("nan"), -1
    i = down[-1]
    t = f[i] / (f[i] - f[i + 1])
    return float(x[i] + t * (x[i + 1] - x[i])), int(i)


def _starts(w, H, rel, yc_w) -> np.ndarray:
    """Where the local regression may start (rad/s), highest first: every fall of |L| through 1
    between reliable lines, or the highest reliable line if |L| is still above 1 there."""
    keep = rel < RELIABLE
    if keep.sum() < 3:
        keep = np.isin(np.arange(w.size), np.argsort(rel)[:3])
    lw, lm = np.log(w[keep]), np.log(np.abs(H[keep] * yc_w[keep]))
    i = np.nonzero((lm[:-1] > 0) & (lm[1:] <= 0))[0][::-1]
    if i.size == 0:
        return np.array([w[keep][-1]]) if lm[-1] > 0 else np.zeros(0)
    return np.exp(lw[i] + lm[i] / (lm[i] - lm[i + 1]) * (lw[i + 1] - lw[i]))


def _raw_cross(w, H, yc_w) -> tuple[float, float]:
    """Highest fall of |L| through 1 between two lines, ln|L| and phase interpolated in ln w."""
    L = H * yc_w
    x, i = _down(np.log(w), np.log(np.abs(L)))
    if not np.isfinite(x):
        return float("nan"), float("nan")
    t = (x - np.log(w[i])) / (np.log(w[i + 1]) - np.log(w[i]))
    ph = np.unwrap(np.angle(L[i:i + 2]))
    return float(np.exp(x)), phase_margin_deg(np.degrees(ph[0] + t * (ph[1] - ph[0])))


def _cross(w, H, rel, plant, kernel: float = None, start: float = None
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Crossover and phase margin of ``L = H Yc`` from measured points H(j w) (w ascending).

    H may hold one row of points per draw, shape (D, n); `rel` (n,) is the
    lines' relative error. Returns arrays (D,) of wc (rad/s), PM (deg), NaN
    where there is no crossing, and the local fit's misfit: the kernel-weighted
    mean square of the lines' residuals in standard deviations (about 1 when
    the local model holds within the lines' scatter).

    Lines whose relative error exceeds RELIABLE are left out (above the
    forcing's corner the remnant swamps them). The raw crossing of |L|
    through 1 between the remaining lines (the highest; or the highest line,
    if |L| is still above 1 there) starts a local regression of the pilot's
    points: ln|H| by a quadratic in ln w, the unwrapped phase by
    ``c0 + c1 w + c2 ln w`` (a delay plus a lead or lag), each line weighted by
    its inverse relative variance times a Gaussian kernel in ln(w / wc) of
    width `kernel` (default KERNEL). With `start` (rad/s), every row starts
    there instead of at its own raw crossing. The smooth H times the exact plant is crossed with 1 (the
    fall nearest the previous estimate, within a factor SPAN), the kernel
    re-centred there, and so on until it settles. The plant's curvature
    (1/(s(s+1)) near 1 rad/s) is thus not interpolated, and the remnant's
    scatter is averaged over all reliable lines, the nearest counting most,
    instead of trusting the two that bracket the crossing.
    """
    grid, lyc, yc_ph, yc_w = plant
    kernel = KERNEL if kernel is None else kernel
    H = np.atleast_2d(H)
    keep = rel < RELIABLE
    if keep.sum() < 3:
        keep = np.isin(np.arange(w.size), np.argsort(rel)[:3])
    w, H, rel, yc_w = w[keep], H[:, keep], rel[keep], yc_w[keep]
    D = H.shape[0]
    lw = np.log(w)
    lm = np.log(np.abs(H * yc_w))
    fall = (lm[:, :-1] > 0) & (lm[:, 1:] <= 0)
    has = fall.any(axis=1)
    i = np.where(has, fall.shape[1] - 1 - np.argmax(fall[:, ::-1], axis=1), 0)
    rows = np.arange(D)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # rows without a fall
        t = lm[rows, i] / (lm[rows, i] - lm[rows, i + 1])
        wc0 = np.where(has, np.exp(lw[i] + t * (lw[i + 1] - lw[i])),
                       np.where(lm[:, -1] > 0, w[-1], np.nan))  # above 1 at the last line: look beyond
    if start is not None:
        wc0 = np.full(D, float(start))
    ok = np.isfinite(wc0)
    wc0 = np.where(ok, wc0, 1.0)
    wv = 1.0 / np.maximum(rel, 0.02) ** 2
    lh = np.log(np.abs(H))
    ph = np.unwrap(np.angle(H), axis=1)
    lg = np.log(grid)
    wc = wc0.copy()
    for _ in range(8):
        g = np.exp(-0.5 * ((lw - np.log(wc0)[:, None]) / kernel) ** 2)
        k = wv * g
        cm = _wls(_mag_basis(w[None, :], wc0[:, None]), lh, k)
        x = lg[None, :] - np.log(wc0)[:, None]
        f = cm[:, :1] + cm[:, 1:2] * x + cm[:, 2:] * x * x + lyc
        down = (f[:, :-1] > 0) & (f[:, 1:] <= 0) & (np.abs(x[:, :-1]) <= np.log(SPAN))
        found = down.any(axis=1)
        # the smooth loop's fall through 1 nearest the previous estimate
        j = np.argmin(np.where(down, np.abs(x[:, :-1]), np.inf), axis=1)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            tt = f[rows, j] / (f[rows, j] - f[rows, j + 1])
            wc = np.exp(lg[j] + tt * (lg[j + 1] - lg[j]))
        ok &= found
        # A row with no fall keeps its previous estimate (it is dropped below), so no
        # log of 0 or nan warns on a user's screen.
        wc = np.where(ok & np.isfinite(wc) & (wc > 0), wc, wc0)
        done = np.abs(np.log(wc / wc0)) < 1e-3
        wc0 = np.where(ok, wc, wc0)
        if np.all(done | ~ok):
            break
    cp = _wls(_phase_basis(w[None, :], wc0[:, None]), ph, k)
    phase = np.einsum("dp,dp->d", _phase_basis(wc, wc0), cp) + yc_ph[j] + tt * (yc_ph[j + 1] - yc_ph[j])
    pm = phase_margin_deg(np.degrees(phase))
    # ln|H| and the phase each carry half the complex relative variance
    r2 = ((lh - np.einsum("dnp,dp->dn", _mag_basis(w[None, :], wc0[:, None]), cm)) ** 2
          + (ph - np.einsum("dnp,dp->dn", _phase_basis(w[None, :], wc0[:, None]), cp)) ** 2)
    misfit = np.sum(g * r2 * 2 * wv, axis=1) / (2 * np.sum(g, axis=1))
    return np.where(ok, wc, np.nan), np.where(ok, pm, np.nan), misfit
