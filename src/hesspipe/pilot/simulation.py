"""Closed-loop simulation of a pilot model around the plants.

Simulation is done in the frequency domain on a zero-padded FFT grid: every
block, the delays included, is evaluated exactly on the shifted contour
``s = sigma0 + j w``; the input samples are taken as band-limited (no hold).
The inputs are weighted by ``exp(-sigma0 t)`` and the result un-weighted by
``exp(+sigma0 t)``: that is exact for a causal linear loop, and every mode
slower than ``sigma0`` (slow decaying modes, and the slow growing modes a
record cannot see) decays on the weighted grid, so a padding of a few
record lengths makes the circular convolution a linear one and the result
is the causal zero-initial-state response, the one a time-domain simulator
gives. (On ``s = j w`` a loop with a right-half-plane mode gives a
non-causal answer, and a mode slower than the padding wraps around.)

Stability is relative to the record (:func:`growth_limit`): a closed loop
is *stable on the record* when its fastest-growing mode grows by less than
a factor two over the record, ``rate < ln 2 / duration`` (0.0099 1/s for
70 s: a time to double longer than the record, where MIL-F-8785C accepts a
spiral mode that doubles in 20 s). A fitted plant holds roots a 70 s record
cannot place to within 1e-2 1/s (see :mod:`hesspipe.plants.fit`), and a loop
whose slowest mode grows at 1e-4 1/s is, for that record and for the pilot,
as good as stable; its simulation above is exact all the same. The rate is
decided from the roots of the closed loop's characteristic polynomial
(delays as Padé approximants of an order chosen for the delay).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Mapping

import numpy as np
import scipy.fft as sfft

from ..core.errors import HesspipeError
from ..core.formats import Run, as_plants
from .blocks import ONE, Block, Loop, from_tf, max_delay, max_real_root, pade_order_for
from .crossover import gain_scale
from .hess import model_from_name
from .motion import motion_block, with_motion_path

UNSTABLE_FITNESS = 1.0e12
"""Least fitness given to a parameter set whose closed loop is unstable: finite (optimisers
and JSON cope) and worse than any stable fit (those are capped at a tenth of it).
Identification grades it, ``UNSTABLE_FITNESS * (1 + min(growth rate - growth_limit, 1000))``
(:func:`growth_limit`: stability is relative to the record), so that
an optimiser standing on the unstable side still sees the way back."""


def unstable_fitness(rate: float, limit: float = 0.0) -> float:
    """Finite worst fitness of a loop whose slowest-decaying mode grows at `rate` (1/s).

    ``UNSTABLE_FITNESS * (1 + min(rate - limit, 1000))`` with `limit` the record's
    growth limit (:func:`growth_limit`); an undecidable (NaN) rate scores the worst.
    Never NaN, always >= UNSTABLE_FITNESS.

    Parameters
    ----------
    rate : float
        Growth rate of the loop's fastest mode, 1/s (> limit: unstable; NaN allowed).
    limit : float
        The record's growth limit, 1/s.

    Returns
    -------
    float
        In the units of the fitness (control^2/Hz for Eq. 10).
    """
    excess = float(rate) - float(limit) if np.isfinite(rate) else 1000.0
    return UNSTABLE_FITNESS * (1.0 + min(max(excess, 0.0), 1000.0))


@dataclass(frozen=True)
class Simulation:
    """Closed-loop time histories at the input's sample times.

    Attributes
    ----------
    time : ndarray
        s, from 0.
    control : ndarray
        Pilot control delta (input of Yc).
    output : ndarray
        Controlled output y (roll rate, rad/s).
    error : ndarray
        Displayed error e = r - y.
    stable : bool
        False if the closed loop is not stable on the record (:func:`growth_limit`);
        the arrays are then NaN.
    """

    time: np.ndarray
    control: np.ndarray
    output: np.ndarray
    error: np.ndarray
    stable: bool = True


#: Growth over one record (a factor 2) below which a closed loop counts as stable.
RECORD_GROWTH = math.log(2.0)


def growth_limit(duration_s: float) -> float:
    """Largest closed-loop growth rate (1/s) that counts as stable on a record of `duration_s`.

    ``ln 2 / duration``: the loop's fastest-growing mode at most doubles over
    the record (0.0099 1/s for 70 s; time to double >= the record). Neither a
    record nor a pilot flying it can tell such a mode from a slow decaying
    one, and a plant fitted to that record cannot place its own roots more
    finely (:mod:`hesspipe.plants.fit` resolves slower roots), so the cohort does
    not redraw such pilots and identification does not punish them.

    Parameters
    ----------
    duration_s : float
        Record length, s (> 0).

    Returns
    -------
    float
        1/s.
    """
    if not (duration_s > 0 and math.isfinite(duration_s)):
        raise HesspipeError(f"duration: expected a positive finite record length (s), got {duration_s!r}")
    return RECORD_GROWTH / float(duration_s)


@dataclass(frozen=True, eq=False)
class Contour:
    """The FFT grid of a record on the shifted contour ``s = sigma0 + j w``.

    Signals are weighted by ``exp(-sigma0 t)`` before the transform and the
    result un-weighted after it: exact for a causal linear system, and every
    mode slower than ``sigma0`` (slow decaying modes, and slowly growing ones
    the record cannot tell from stable) has decayed on the weighted grid
    before it could wrap around. The one convention of :class:`Simulator` and
    :func:`hesspipe.diagnose.checks.forced_response`.

    Attributes
    ----------
    n, nfft : int
        Record and FFT length (samples).
    dt : float
        Sample interval, s.
    growth_limit : float
        :func:`growth_limit` of the record (1/s).
    sigma0 : float
        ``growth_limit + decays / (nfft dt)`` (1/s).
    s : ndarray
        The contour's points (rad/s, complex), one per rfft bin.
    """

    n: int
    dt: float
    nfft: int
    growth_limit: float
    sigma0: float
    s: np.ndarray
    weight: np.ndarray
    unweight: np.ndarray

    @classmethod
    def for_record(cls, n: int, dt: float, *, pad_factor: int = 4, decays: float = 10.0) -> "Contour":
        """The contour of `n` samples at `dt` s, zero-padded to `pad_factor` records.

        Parameters
        ----------
        n : int
            Samples of the record.
        dt : float
            Sample interval, s.
        pad_factor : int
            FFT length in records (at least 2): room for the loop's response to decay.
        decays : float
            How many e-folds the weight ``exp(-sigma0 t)`` falls over the padded FFT.
        """
        limit = growth_limit(n * dt)
        nfft = sfft.next_fast_len(max(int(pad_factor), 2) * n, real=True)
        sigma0 = limit + float(decays) / (nfft * dt)
        # sigma0 > 0 also keeps s off the origin, where integrating plants (1/s) are infinite.
        s = sigma0 + 2j * np.pi * np.fft.rfftfreq(nfft, dt)
        t = dt * np.arange(n)
        return cls(n, float(dt), nfft, limit, sigma0, s, np.exp(-sigma0 * t), np.exp(sigma0 * t))

    def spectrum(self, x: np.ndarray) -> np.ndarray:
        """Transform of the weighted samples `x` (length n).

        Parameters
        ----------
        x : array
            n samples of a signal, its own units.

        Returns
        -------
        ndarray of complex
            On :attr:`s` (length ``nfft // 2 + 1``).
        """
        return sfft.rfft(np.asarray(x, dtype=float) * self.weight, self.nfft)

    def waveform(self, spectrum: np.ndarray) -> np.ndarray:
        """Samples on the record of a spectrum on this contour (un-weighted).

        Parameters
        ----------
        spectrum : array of complex
            A spectrum on :attr:`s` (what :meth:`spectrum` gives, times responses).

        Returns
        -------
        ndarray
            n samples.
        """
        return sfft.irfft(spectrum, self.nfft)[: self.n] * self.unweight


class Simulator:
    """Closed-loop simulation prepared for one record: call it with many loops.

    Everything that does not depend on the pilot (frequency grid, plant
    responses, input spectra, remnant noise) is computed once, and block
    shapes are cached, so one call costs a few vector operations and an
    inverse FFT.

    Parameters
    ----------
    plants : hesspipe.core.formats.Plants
        Yc (control → output) and Yd (disturbance → output).
    disturbance : array
        w at the sample times.
    dt : float
        Sample interval, s.
    reference : array, optional
        r (default 0).
    noise_seed : int
        Seed of the unit-variance white sequence that remnant shapes.
    pad_factor : int
        The record is zero-padded to this many times its length (default 4).
    decays : float
        The contour shift ``sigma0`` is chosen so that a mode growing at
        :attr:`growth_limit` has decayed ``exp(-decays)`` on the weighted
        grid by the time it would wrap around: ``sigma0 = growth_limit +
        decays / (nfft dt)``. Its output is un-weighted by at most
        ``exp(sigma0 duration)`` (about 24 for the defaults).

    Attributes
    ----------
    growth_limit : float
        :func:`growth_limit` of the record (1/s): loops growing slower are stable.
    sigma0 : float
        Real part of the evaluation contour (1/s).
    """

    def __init__(self, plants, disturbance, dt: float, *, reference=None, noise_seed: int = 0,
                 pad_factor: int = 4, decays: float = 10.0):
        plants = as_plants(plants)
        w = np.asarray(disturbance, dtype=float)
        if w.ndim != 1 or w.size < 2:
            raise HesspipeError("disturbance: expected a 1-D signal of at least 2 samples")
        if not np.all(np.isfinite(w)):
            raise HesspipeError(f"disturbance: a non-finite value at sample {int(np.argmax(~np.isfinite(w)))}; "
                                "expected a continuous record")
        if isinstance(dt, (bool, str)) or not isinstance(dt, (int, float, np.number)) \
                or not (dt > 0 and np.isfinite(dt)):
            raise HesspipeError(f"dt: expected a positive sample interval, got {dt!r}")
        self.contour = c = Contour.for_record(w.size, float(dt), pad_factor=pad_factor, decays=decays)
        self.n, self.dt, self.nfft = c.n, c.dt, c.nfft
        self.growth_limit, self.sigma0, self.s = c.growth_limit, c.sigma0, c.s
        self._cache: dict = {}
        self._seen: set = set()
        self.yc_block = from_tf(plants.control_to_output)
        self.yd_block = from_tf(plants.disturbance_to_output)
        yd_den = np.asarray(self.yd_block.terms[0].den)
        if not max_real_root(yd_den) < self.growth_limit:
            raise HesspipeError("plants: disturbance_to_output has unstable poles "
                                f"{np.round(np.roots(yd_den), 4).tolist()}; expected a Yd stable on a "
                                f"{self.n * self.dt:g} s record (growth rate < {self.growth_limit:.3g} 1/s)")
        self.yc = self.yc_block.response(self.s)
        self.ydw = self.yd_block.response(self.s) * c.spectrum(w)
        r = None if reference is None else np.asarray(reference, dtype=float)
        if r is not None and r.shape != w.shape:
            raise HesspipeError("reference: expected the same length as the disturbance")
        if r is not None and not np.all(np.isfinite(r)):
            raise HesspipeError(f"reference: a non-finite value at sample {int(np.argmax(~np.isfinite(r)))}; "
                                "expected a continuous record")
        self.r = r if r is not None and np.any(r) else None
        self.rf = None if self.r is None else c.spectrum(self.r)
        self.noise_seed = int(noise_seed)
        self._noise = None
        self.cab = motion_block(plants)   # None: the paper's platform x washout

    def prepare(self, loop: Loop) -> Loop:
        """`loop` with its vestibular feedback through the plants' ``motion_path``.

        Parameters
        ----------
        loop : Loop
            The pilot's loop (its vestibular block is the default motion path's).
        """
        return with_motion_path(loop, self.cab)

    def _trim_cache(self):
        if len(self._cache) > 96:  # each entry is one complex spectrum (~100 kB)
            self._cache.clear()
        if len(self._seen) > 4096:
            self._seen.clear()

    @property
    def noise(self) -> np.ndarray:
        """Spectrum of the seeded unit-variance white sequence used by remnant."""
        if self._noise is None:
            white = np.random.default_rng(self.noise_seed).standard_normal(self.n)
            self._noise = self.contour.spectrum(white)
        return self._noise

    def growth_rate(self, loop: Loop) -> float:
        """Largest real part (1/s) of the closed loop's modes; below :attr:`growth_limit`: stable.

        The remnant shaping filter's poles count too (it feeds the loop).

        Parameters
        ----------
        loop : Loop
            The pilot's loop.
        """
        loop = self.prepare(loop)
        order = pade_order_for(max_delay((loop.visual, loop.vestibular, loop.neuromuscular,
                                          loop.proprioceptive, loop.plant)))
        rate = max_real_root(loop.characteristic(self.yc_block, order))
        for t in loop.noise.terms:
            if t.gain != 0:
                rate = max(rate, max_real_root(t.den))
        return rate

    def stable(self, loop: Loop) -> bool:
        """True if the closed loop is stable on the record: growth rate below :attr:`growth_limit`.

        Parameters
        ----------
        loop : Loop
            The pilot's loop.
        """
        return self.growth_rate(loop) < self.growth_limit

    def waveform(self, spectrum: np.ndarray) -> np.ndarray:
        """Time history on the record's samples of a spectrum from :meth:`spectra`.

        Parameters
        ----------
        spectrum : array of complex
            A spectrum on the simulator's contour.

        Returns
        -------
        ndarray
            Samples on the record (its length), the spectrum's units.
        """
        return self.contour.waveform(spectrum)

    def spectra(self, loop: Loop, output: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
        """Spectra (control, output) of the closed loop on the shifted contour; no stability check.

        They are spectra of the *weighted* signals (``exp(-sigma0 t)``);
        :meth:`waveform` turns them into time histories. Valid for loops
        growing slower than :attr:`sigma0` (every loop :meth:`stable` accepts).

        ``delta = (NM vis R - NM (vis + ves) Yd W + N n) / (1 + NM PF + NM (vis + ves) Yc')``

        Parameters
        ----------
        loop : Loop
            The pilot's loop.
        output : bool
            Also return the output's spectrum.

        Returns
        -------
        control : ndarray of complex
            Spectrum of the control deviation delta (control units).
        output : ndarray of complex or None
            Spectrum of the plant output y (output units); None if not asked for.
        """
        self._trim_cache()
        loop = self.prepare(loop)
        yc = self.yc_block if loop.plant.terms == ONE.terms else self.yc_block * loop.plant
        nm, vis, ves = loop.neuromuscular, loop.visual, loop.vestibular
        paths = [vis] if ves.is_zero else [vis, ves]
        local: dict = {}
        den = self._sum(loop.return_difference_products(yc), local)
        den += 1.0
        num = self._sum([(nm, p, "ydw") for p in paths], local)
        np.negative(num, out=num)
        if self.rf is not None:
            num += self._sum([(nm, vis, "rf")], local)
        if not loop.noise.is_zero:
            num += self._sum([(loop.noise, "noise")], local)
        num /= den
        if not output:
            return num, None
        return num, yc.response(self.s, self._cache) * num + self._fixed("ydw")

    def _fixed(self, name: str) -> np.ndarray:
        return {"ydw": self.ydw, "rf": self.rf}.get(name) if name != "noise" else self.noise

    def _sum(self, products, local: dict) -> np.ndarray:
        """Sum of products of blocks / fixed spectra, with each product's shape cached.

        Gains are scalars outside the cached shapes, so when only gains change
        (Ke, K1, K2, Km ...) a product costs one scalar multiplication.
        """
        total = None
        for factors in products:
            blocks = [f for f in factors if not isinstance(f, str)]
            if all(len(b.terms) == 1 for b in blocks):
                gain = 1.0
                for b in blocks:
                    gain *= b.terms[0].gain
                key = ("prod",) + tuple(f if isinstance(f, str) else
                                        (f.terms[0].num, f.terms[0].den, f.terms[0].delay)
                                        for f in factors)
                shape = self._cache.get(key)
                if shape is None:
                    # Cache a shape only once it is asked for twice: shapes that
                    # change at every call (a fit of time constants) would just
                    # churn the cache.
                    keep = key in self._seen
                    self._seen.add(key)
                    cache = self._cache if keep else local  # local: this call only
                    shape = None
                    for f in factors:
                        part = (self._fixed(f) if isinstance(f, str) else
                                Block((replace(f.terms[0], gain=1.0),)).response(self.s, cache))
                        shape = part if shape is None else shape * part
                    if keep:
                        self._cache[key] = shape
                term = gain * shape
            else:
                term = np.ones(self.s.shape, dtype=complex)
                for f in factors:
                    term = term * (self._fixed(f) if isinstance(f, str) else f.response(self.s, self._cache))
            if total is None:
                total = term
            else:
                total += term
        return total

    def control(self, loop: Loop) -> np.ndarray | None:
        """Simulated control delta, or None if the loop is not stable on the record.

        Parameters
        ----------
        loop : Loop
            The pilot's loop.

        Returns
        -------
        ndarray or None
            Control deviation from trim on the record's samples, control units.
        """
        if not self.stable(loop):
            return None
        control, _ = self.spectra(loop, output=False)
        return self.waveform(control)

    def run(self, loop: Loop) -> Simulation:
        """The closed loop's time histories (NaN if it is not stable on the record).

        Parameters
        ----------
        loop : Loop
            The pilot's loop.

        Returns
        -------
        Simulation
            Time (s), control, output and error ``e = r - y`` (output units).
        """
        t = self.dt * np.arange(self.n)
        if not self.stable(loop):
            nan = np.full(self.n, np.nan)
            return Simulation(t, nan, nan.copy(), nan.copy(), stable=False)
        cf, yf = self.spectra(loop)
        delta = self.waveform(cf)
        y = self.waveform(yf)
        r = self.r if self.r is not None else np.zeros(self.n)
        return Simulation(t, delta, y, r - y, stable=True)


def simulate(model, params: Mapping[str, float] | None, plants, disturbance, dt: float, *,
             reference=None, seed: int | None = None, k: int | None = None) -> Simulation:
    """Simulate the closed loop of `model` with `params` around `plants`.

    Parameters
    ----------
    model : PilotModel or str
        "original", "expanded", ... (see :func:`model_from_name`).
    params : mapping
        Parameter values; missing ones take the model's defaults (Table 1, its loop gains
        scaled to the plants by :func:`hesspipe.pilot.crossover.gain_scale`, as
        identification's defaults are).
    plants : hesspipe.core.formats.Plants
    disturbance : array
        Disturbance w (input of Yd) sampled at `dt`, from t = 0.
    dt : float
        Sample interval, s.
    reference : array, optional
        Reference r (default 0).
    seed : int, optional
        Seed of the remnant noise (default 0); ignored without remnant.

    Returns
    -------
    Simulation
        ``stable=False`` (NaN arrays) for a loop that is not stable on the
        record (:func:`growth_limit`); never raises for it.
    """
    model = model_from_name(model)
    plants = as_plants(plants)
    order = k if k is not None else int((params or {}).get("k", 1))
    p = model.complete(params, k, gain=gain_scale(plants, order) if order in (1, 2) else 1.0)
    loop = model.loop(p)
    sim = Simulator(plants, disturbance, dt, reference=reference,
                    noise_seed=0 if seed is None else int(seed))
    return sim.run(loop)


def synthetic_run(model, params: Mapping[str, float] | None, plants, disturbance, dt: float, *,
                  seed: int = 0, run_id: str = "synthetic", reference=None, k: int | None = None):
    """A :class:`hesspipe.core.formats.Run` generated by `model`, labelled synthetic.

    Parameters
    ----------
    model : PilotModel or str
        The generating model.
    params : mapping, optional
        Parameter values (missing ones: Table 1 defaults, loop gains scaled as in :func:`simulate`).
    plants : hesspipe.core.formats.Plants
    disturbance : array
        Disturbance w sampled at `dt`, the plants' disturbance units.
    dt : float
        Sample interval, s.
    seed : int
        Remnant noise seed.
    run_id : str
        Id of the run.
    reference : array, optional
        Reference r (default 0), output units.
    k : {1, 2}, optional
        Table 1 column.

    Raises
    ------
    HesspipeError
        If the closed loop is unstable (there is nothing to record).
    """

    model = model_from_name(model)
    p = model.complete(params, k)
    sim = simulate(model, p, plants, disturbance, dt, reference=reference, seed=seed)
    if not sim.stable:
        raise HesspipeError(f"synthetic run {run_id}: the closed loop of model {model.name} is "
                            "unstable with these parameters")
    text = ", ".join(f"{n}={p[n]:g}" for n in model.parameter_names())
    comments = ("synthetic data: generated by the hesspipe pilot model, not measured",
                f"model: {model.name}", f"parameters: {text}", f"seed: {seed}")
    ref = np.zeros(len(sim.time)) if reference is None else np.asarray(reference, dtype=float)
    return Run(time=sim.time, disturbance=np.asarray(disturbance, dtype=float), output=sim.output,
               control=sim.control, reference=ref, id=run_id, synthetic=True, comments=comments)
