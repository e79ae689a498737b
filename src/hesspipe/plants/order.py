"""ARX order selection: the candidates, the information criterion, the data checks that come
first (persistent excitation, enough samples)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.errors import HesspipeError
from .arx import CRITERIA, ArxModel, _check_signals, _first_sample, arx_fit, excitation_order, information_criterion


@dataclass(frozen=True)
class Candidate:
    """One grid point of an order selection.

    Attributes
    ----------
    na, nb, nk : int
        Orders and input delay (samples).
    criterion : float
        Value of the information criterion (lower is better).
    noise_variance : float
        Mean squared one-step residual, output units^2.
    stable : bool
        Whether the fit may be chosen (stable, or stable on the record).
    """

    na: int
    nb: int
    nk: int
    criterion: float
    noise_variance: float
    stable: bool = True

    def to_dict(self) -> dict:
        """The candidate as JSON-ready values."""
        return {"na": self.na, "nb": self.nb, "nk": self.nk, "criterion": self.criterion,
                "noise_variance": self.noise_variance, "stable": self.stable}


@dataclass(frozen=True)
class OrderSelection:
    """Result of :func:`select_order`: the best model and the whole grid.

    Attributes
    ----------
    model : ArxModel
        The chosen model, fitted.
    criterion : str
        ``"aic"``, ``"bic"`` or ``"fpe"``.
    candidates : tuple of Candidate
        Every grid point.
    excitation_order : int
        Order of persistent excitation of the input.
    n_samples : int
        Equations every candidate was fitted on.
    """

    model: ArxModel
    criterion: str
    candidates: tuple[Candidate, ...]
    excitation_order: int
    n_samples: int

    @property
    def best(self) -> Candidate:
        """The chosen candidate (same orders as :attr:`model`)."""
        m = self.model
        return next(c for c in self.candidates if (c.na, c.nb, c.nk) == m.orders)

    def ranked(self, n: int = 10) -> list[Candidate]:
        """The `n` best candidates, best first.

        Parameters
        ----------
        n : int
            How many.
        """
        return sorted(self.candidates, key=lambda c: c.criterion)[:n]


def check_data(u, y, *, na_max: int = 6, nb_max: int = 6, nk_max: int = 3, min_excitation: int = 4,
               rcond: float = 1e-4, label: str = "data") -> int:
    """Check that `u`, `y` can support an order selection; return the excitation order.

    Parameters
    ----------
    u, y : array
        Input and output deviations from trim (same length).
    na_max, nb_max, nk_max : int
        Largest orders and input delay (samples) of the grid.
    min_excitation : int
        Least excitation order accepted.
    rcond : float
        Relative singular-value threshold of :func:`excitation_order`.
    label : str
        What the data is called in messages (e.g. the file).

    Raises
    ------
    HesspipeError
        Non-finite values; ``"... input not persistently exciting ..."`` if
        the excitation order of `u` is below `min_excitation`; ``"... record
        too short ..."`` if the record cannot support the largest candidate.
    """
    u, y = _check_signals(u, y, label)
    order = excitation_order(u, max(nb_max, min_excitation), rcond=rcond)
    if order < min_excitation:
        raise HesspipeError(f"{label}: input not persistently exciting (excitation order {order}, "
                            f"expected at least {min_excitation}); use a broadband excitation "
                            "(multisine, PRBS or turbulence)")
    nb_top = min(nb_max, order)
    need = _first_sample(na_max, nb_top, nk_max) + 10 * (na_max + nb_top)
    if len(y) < need:
        raise HesspipeError(f"{label}: record too short for ARX orders up to ({na_max},{nb_top},{nk_max}): "
                            f"{len(y)} samples, expected at least {need}")
    return order


def select_order(u, y, *, na_max: int = 6, nb_max: int = 6, nk_min: int = 1, nk_max: int = 3,
                 criterion: str = "bic", dt: float = 1.0, min_excitation: int = 4,
                 rcond: float = 1e-4, stable_only: bool = True, focus: str = "prediction",
                 iterations: int = 10, max_growth: float = 0.0, label: str = "data") -> OrderSelection:
    """Choose ARX orders and delay by an information criterion, and fit.

    The grid is ``na in 1..na_max``, ``nb in 1..nb_max`` (capped at the input's
    excitation order), ``nk in nk_min..nk_max``. All candidates are fitted on
    the same samples (those after the longest lag of the grid). With
    `stable_only`, candidates with a pole on or outside the unit circle are
    listed but cannot be chosen: the plants are stable aircraft, and an
    equation-error fit can place a slow pole just outside the circle, which
    the one-step criterion cannot see but the simulated output does.
    `max_growth` (1/s, default 0) relaxes "stable" to "stable on the record":
    poles growing slower than it are accepted (a record of duration T
    cannot tell a pole at ``ln|z|/dt = +1e-4`` from one at ``-1e-4``; see
    :func:`hesspipe.pilot.simulation.growth_limit`). Refusing them can leave only
    candidates that fit badly (the MD11's slightly divergent spiral mode).

    Parameters
    ----------
    u, y : array
        Input and output deviations from trim, same length, sampled at `dt`.
    na_max, nb_max : int
        Largest orders of A(q) and B(q).
    nk_min, nk_max : int
        Range of the input delay, samples.
    criterion : {"aic", "bic", "fpe"}
        Information criterion (lower is better).
    dt : float
        Sample interval, s.
    min_excitation : int
        Least excitation order of `u` accepted.
    rcond : float
        Relative singular-value threshold of :func:`excitation_order`.
    stable_only : bool
        Only stable candidates (see above) may be chosen.
    focus : {"prediction", "simulation"}
        Fit criterion of each candidate (see :func:`fit_arx`).
    iterations : int
        Most prefiltering iterations for ``focus="simulation"``.
    max_growth : float
        Largest pole growth rate counted as stable, 1/s.
    label : str
        What the data is called in messages.

    Raises
    ------
    HesspipeError
        ``"... not persistently exciting ..."`` if the input's excitation
        order is below `min_excitation`; ``"... record too short ..."`` if
        the record cannot support the largest candidate.
    """
    if criterion not in CRITERIA:
        raise HesspipeError(f"criterion: expected one of {', '.join(CRITERIA)}, got {criterion!r}")
    order = check_data(u, y, na_max=na_max, nb_max=nb_max, nk_max=nk_max,
                       min_excitation=min_excitation, rcond=rcond, label=label)
    u, y = np.asarray(u, dtype=float), np.asarray(y, dtype=float)
    nb_top = min(nb_max, order)
    start = _first_sample(na_max, nb_top, nk_max)
    n = len(y) - start
    cands = []
    for nk in range(nk_min, nk_max + 1):
        for na in range(1, na_max + 1):
            for nb in range(1, nb_top + 1):
                try:
                    m = arx_fit(u, y, na, nb, nk, dt=dt, start=start, focus=focus,
                                iterations=iterations, label=label)
                except HesspipeError:
                    continue  # rank deficient at this order: not a candidate
                cands.append(Candidate(na, nb, nk, information_criterion(
                    criterion, m.noise_variance, n, na + nb), m.noise_variance,
                    m.is_stable(max_growth)))
    if not cands:
        raise HesspipeError(f"{label}: regressors rank deficient at every order; input not "
                            "persistently exciting")
    pool = [c for c in cands if c.stable] if stable_only else cands
    if not pool:
        raise HesspipeError(f"{label}: every ARX candidate up to ({na_max},{nb_top},{nk_max}) is unstable; "
                            "expected a stable plant (check the record, or set stable_only = false)")
    best = min(pool, key=lambda c: c.criterion)
    model = arx_fit(u, y, best.na, best.nb, best.nk, dt=dt, start=start, focus=focus,
                    iterations=iterations, label=label)
    return OrderSelection(model=model, criterion=criterion, candidates=tuple(cands),
                          excitation_order=order, n_samples=n)
