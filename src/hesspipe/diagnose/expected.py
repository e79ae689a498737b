"""The expected control spectrum of a pilot model on a run's Welch bins (diagnose).

Deterministic part simulated by the pilot package's simulator, remnant part in
expectation through the window's kernel; see :class:`ExpectedSpectrum`.
"""

from __future__ import annotations

import numpy as np

from ..core.formats import Plants, Run
from ..core.paper import WELCH_SEGMENT
from ..core.seeds import derive_seed
from ..pilot.blocks import ZERO, from_tf
from ..pilot.simulation import Simulator
from .settings import DiagnoseConfig
from .spectra import _psd, _window_gain, welch_kernel

#: Welch bins of the density beyond the highest reported frequency folded into the
#: expected remnant PSD (Hamming sidelobes 32 bins out are below -60 dB).
_KERNEL_MARGIN = 32
#: Frequency (Hz) below which the expected remnant PSD samples the density on the
#: simulator's fine grid (:meth:`_Problem.remnant_psd`).
_FINE_HZ = 1.0


class ExpectedSpectrum:
    """A model's expected paper-Welch control PSD on the run's Welch bins.

    The deterministic part is the PSD of the model's response to the measured
    disturbance (and reference), simulated by :class:`hesspipe.pilot.simulation.Simulator`;
    the remnant's part is its expectation, the density through the closed loop folded
    through the window's kernel (:func:`hesspipe.diagnose.spectra.welch_kernel`), never a
    random draw, so fits and scores do not depend on a noise realization.

    Parameters
    ----------
    run : hesspipe.core.formats.Run
        The measured run (its disturbance and reference drive the model).
    plants : hesspipe.core.formats.Plants
        Yc and Yd (and the optional motion path) the model is closed around.
    cfg : DiagnoseConfig
        Band (Hz) and band edges: how far the kernel must reach.
    seed : int
        Base seed (the simulator's noise seed is derived from it, never used).
    freq : ndarray
        The Welch bins, Hz.
    """

    def __init__(self, run: Run, plants: Plants, cfg: DiagnoseConfig, seed: int, freq: np.ndarray):
        self.run, self.freq = run, freq
        self.window_gain = _window_gain(len(run))
        # The remnant is evaluated in expectation, so the simulator's noise is never used;
        # its seed is derived all the same for reproducibility.
        self.sim = Simulator(plants, run.disturbance, run.dt, reference=run.reference_forcing,
                             noise_seed=derive_seed(seed, "diagnose"))
        f = self.freq.copy()
        f[0] = f[1] * 1e-6
        self.s = 2j * np.pi * f
        # Expected remnant PSD (see :meth:`remnant_psd`): the density up to `_KERNEL_MARGIN`
        # bins past the highest reported frequency, folded through the window kernel. It
        # is sampled every 1/16 Welch bin below `_FINE_HZ`, where the narrow features are
        # (lightly damped aircraft pairs, slow remnant that the loop barely opposes), every
        # quarter bin above (closed-loop features there are broad), and geometrically
        # from 1e-6 Hz up to the first fine point: a plant with a near-zero static gain
        # leaves a spike at DC narrower than any affordable uniform grid.
        top = max(float(cfg.band_hz[1]), float(cfg.band_edges_hz[-1]))
        self.n_kernel = int(np.searchsorted(self.freq, top, side="right"))
        bin_hz = run.fs / WELCH_SEGMENT
        end = min(top + _KERNEL_MARGIN * bin_hz, run.fs / 2)
        fine = np.arange(bin_hz / 16, min(_FINE_HZ, end), bin_hz / 16)
        grid = np.concatenate([[0.0], np.geomspace(1e-6, fine[0], 41)[:-1], fine,
                               np.arange(fine[-1] + bin_hz / 4, end + bin_hz / 8, bin_hz / 4)])
        self.kernel = welch_kernel(len(run), run.fs, self.freq[:self.n_kernel], grid)
        g = grid.copy()
        g[0] = 1e-9   # finite value just above DC (integrating plants)
        # One evaluation per block serves both: the fine grid, then the bins above it.
        self.n_fine = g.size
        self.s_all = np.concatenate([2j * np.pi * g, self.s[self.n_kernel:]])
        self.yc_all = from_tf(plants.control_to_output).response(self.s_all)

    # model pieces -----------------------------------------------------------------------

    def loop(self, model, params):
        """The model's loop for `params`, prepared for the simulator (motion path applied).

        Parameters
        ----------
        model : hesspipe.pilot.hess.PilotModel
            The model, with its effects.
        params : mapping
            Its parameters (missing: defaults).
        """
        # Through the plants' motion path, as the Simulator sees it (remnant_density too).
        return self.sim.prepare(model.loop(model.complete(params)))

    def stochastic(self, model, params) -> bool:
        """Whether the model's loop has a remnant.

        Parameters
        ----------
        model : hesspipe.pilot.hess.PilotModel
            The model, with its effects.
        params : mapping
            Its parameters (missing: defaults).
        """
        return not self.loop(model, params).noise.is_zero

    def control(self, model, params, loop=None) -> np.ndarray | None:
        """Deterministic control (remnant off) driven by the measured disturbance; None if
        the loop is unstable (a remnant filter has no poles in the right half plane).

        Parameters
        ----------
        model : hesspipe.pilot.hess.PilotModel
            The model, with its effects.
        params : mapping
            Its parameters (missing: defaults).
        loop : hesspipe.pilot.blocks.Loop, optional
            The prepared loop, when the caller has it already.
        """

        loop = self.loop(model, params) if loop is None else loop
        u = self.sim.control(loop.replace(noise=ZERO))
        return None if u is None or not np.all(np.isfinite(u)) else u

    def remnant_density(self, loop, s: np.ndarray, yc: np.ndarray) -> np.ndarray:
        """Two-sided PSD (control units^2/Hz) of the remnant's share of the control at `s`.

        The unit-variance white sequence of :class:`hesspipe.pilot.simulation.Simulator` has a
        two-sided density ``dt``; the closed loop passes it to the control through
        ``noise / (1 + NM PF + NM (visual + vestibular) Yc plant)`` (the loop of
        :class:`hesspipe.pilot.blocks.Loop`); `yc` is Yc's response at `s`.

        Parameters
        ----------
        loop : hesspipe.pilot.blocks.Loop
            The prepared loop (with its remnant filter).
        s : array of complex
            Laplace variable, 1/s.
        yc : array of complex
            Yc's response at `s`, output units per control unit.
        """
        den = loop.return_difference(s, yc)
        return np.abs(loop.noise.response(s) / den) ** 2 * self.run.dt

    def remnant_psd(self, loop) -> np.ndarray:
        """Expected paper-Welch PSD of the remnant's share of the control.

        Up to the highest reported frequency the density is folded through the window
        kernel (:func:`welch_kernel`), which is what the estimator's expectation is; above
        it (outside every fit, score and report) the density at the bin times the
        window's gain (:func:`_window_gain`) stands in.

        Parameters
        ----------
        loop : hesspipe.pilot.blocks.Loop
            The prepared loop; zeros when it has no remnant.
        """
        if loop.noise.is_zero:
            return np.zeros_like(self.freq)
        dens = self.remnant_density(loop, self.s_all, self.yc_all)
        return np.concatenate([self.kernel @ dens[:self.n_fine], dens[self.n_fine:] * self.window_gain])

    def model_psd(self, model, params) -> tuple[np.ndarray, np.ndarray] | None:
        """(total, remnant) expected PSDs (control units^2/Hz) on all bins; None if unstable.

        Parameters
        ----------
        model : hesspipe.pilot.hess.PilotModel
            The model, with its effects.
        params : mapping
            Its parameters (missing: defaults).
        """
        loop = self.loop(model, params)
        u = self.control(model, params, loop)
        if u is None:
            return None
        _, det = _psd(u, self.run.fs)
        rem = self.remnant_psd(loop)
        return det + rem, rem
