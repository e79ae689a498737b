"""The describing-function fits' shared multistart (`hesspipe.identification._lsq`)."""

import numpy as np
import pytest

from hesspipe.core.errors import HesspipeError
from hesspipe.identification._lsq import SCREEN_NFEV, TOLERANCE, _ForwardDifference, _solve, best_least_squares


def _counted(resid):
    calls = []

    def f(x):
        calls.append(1)
        return resid(x)
    return f, calls


def _wavy(x):
    # Local minima about every 2 in each coordinate; the global one near (3, -1).
    return np.array([np.sin(3 * x[0]) + 0.3 * (x[0] - 3.0), np.sin(3 * x[1]) + 0.3 * (x[1] + 1.0),
                     0.1 * (x[0] - x[1] - 4.0)])


def test_screened_search_finds_what_every_start_finds_with_fewer_evaluations():
    lo, hi = np.array([-6.0, -6.0]), np.array([6.0, 6.0])
    starts = [[a, b] for a in np.linspace(-5, 5, 5) for b in np.linspace(-5, 5, 5)]
    full, n_full = _counted(_wavy)
    rss_f, sol_f = best_least_squares(full, starts, lo, hi, "no fit")
    screened, n_screened = _counted(_wavy)
    rss_s, sol_s = best_least_squares(screened, starts, lo, hi, "no fit", keep=3)
    assert rss_s == pytest.approx(rss_f, rel=1e-9, abs=1e-12)
    np.testing.assert_allclose(sol_s.x, sol_f.x, atol=1e-6)
    assert len(n_screened) < len(n_full)
    # Every start had its screen (at least its first Jacobian) before the three went on.
    assert len(n_screened) >= len(starts) * 3


def test_screen_keeps_every_start_when_it_has_few():
    starts = [[0.0, 0.0], [3.0, -1.0]]
    lo, hi = np.array([-6.0, -6.0]), np.array([6.0, 6.0])
    a = best_least_squares(_wavy, starts, lo, hi, "no fit", keep=3)
    b = best_least_squares(_wavy, starts, lo, hi, "no fit")
    assert a[0] == b[0] and np.array_equal(a[1].x, b[1].x)
    assert SCREEN_NFEV > 0


def test_no_start_converging_is_the_callers_error():
    def bad(x):
        raise FloatingPointError("overflow")
    with pytest.raises(HesspipeError, match="^motion test: nothing$"):
        best_least_squares(bad, [[0.0], [0.5]], np.array([-1.0]), np.array([1.0]), "motion test: nothing", keep=1)


def test_tolerance_stops_sooner_with_the_rss_as_scipys_default_finds_it():
    # Two decaying exponentials, an ill-conditioned valley like the Hess loop's gains: the
    # searches' TOLERANCE stops sooner than scipy's 1e-8 and leaves the RSS (in noise-variance
    # units, as the describing-function fits' are) within 1e-3 of where the default leaves it,
    # far below what an F test reads.
    from scipy import optimize

    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 5.0, 60)

    def model(x):
        return x[0] * np.exp(-x[1] * t) + x[2] * np.exp(-x[3] * t)

    data = model([1.0, 1.0, 0.8, 1.6]) + 0.01 * rng.standard_normal(t.size)
    resid = lambda x: (model(x) - data) / 0.01  # noqa: E731
    lo, hi, x0 = np.array([0.0, 0.01, 0.0, 0.01]), np.full(4, 10.0), [0.5, 0.5, 0.5, 3.0]
    counted, n_ours = _counted(resid)
    rss, _ = best_least_squares(counted, [x0], lo, hi, "no fit")
    default, n_default = _counted(resid)
    ref = optimize.least_squares(default, x0, bounds=(lo, hi), x_scale="jac", max_nfev=400)
    assert rss == pytest.approx(float(np.sum(ref.fun ** 2)), abs=1e-3)
    assert len(n_ours) < len(n_default)


def test_the_forward_difference_is_scipys_default_bit_for_bit():
    # The searches' own Jacobian (_ForwardDifference) must give the numbers of scipy's
    # jac="2-point", steps turned at the bounds included, so that a search ends where it did.
    from scipy import optimize
    from scipy.optimize._numdiff import approx_derivative

    lo, hi = np.array([-6.0, -6.0]), np.array([6.0, 6.0])
    for x in ([0.0, 0.0], [6.0 - 1e-9, -3.0], [-6.0 + 1e-12, 5.5], [-2.5, 6.0 - 1e-10], [1e-300, -1e-7]):
        x = np.array(x)
        fd = _ForwardDifference(_wavy, lo, hi)
        ours = fd.jac(x)
        ref = approx_derivative(_wavy, x, method="2-point", f0=_wavy(x), bounds=(lo, hi))
        assert np.array_equal(ours, ref)
        fd.fun(x)
        assert np.array_equal(fd.jac(x), ref)
    # A narrow box, where neither side fits the step: the distance to the farther bound.
    nlo, nhi = np.array([1.0, -1e-9]), np.array([1.0 + 1e-9, 1e-9])
    x = np.array([1.0 + 3e-10, 0.0])
    fd = _ForwardDifference(_wavy, nlo, nhi)
    ref = approx_derivative(_wavy, x, method="2-point", f0=_wavy(x), bounds=(nlo, nhi))
    assert np.array_equal(fd.jac(x), ref)
    # Whole searches, screened (30 evaluations) and to convergence, end at the same point.
    for x0 in ([-5.0, 5.0], [0.3, -4.0], [2.0, 2.0]):
        for nfev in (SCREEN_NFEV, 400):
            ours = _solve(_wavy, np.array(x0), lo, hi, nfev)[1]
            ref = optimize.least_squares(_wavy, x0, bounds=(lo, hi), x_scale="jac", max_nfev=nfev,
                                         ftol=TOLERANCE, xtol=TOLERANCE, gtol=TOLERANCE)
            assert np.array_equal(ours.x, ref.x) and ours.nfev == ref.nfev and ours.njev == ref.njev
