"""ARX identification and discrete → continuous conversion on systems with a known answer."""

import control as ct
import numpy as np
import pytest
from scipy import signal

from hesspipe.core.errors import HesspipeError
from hesspipe.plants import arx, d2c, order, validation

# A known discrete system: A = 1 - 1.5 q^-1 + 0.7 q^-2, B = 0.5 + 0.3 q^-1, nk = 1
# (poles 0.75 ± 0.37j, |z| = 0.84).
A_TRUE = np.array([1.0, -1.5, 0.7])
B_TRUE = np.array([0.5, 0.3])


def _arx_data(n=3000, noise=0.1, seed=1):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n)
    e = noise * rng.standard_normal(n)
    y = signal.lfilter(np.r_[0.0, B_TRUE], A_TRUE, u) + signal.lfilter([1.0], A_TRUE, e)
    return u, y


def test_recovers_known_arx_system_orders_and_coefficients():
    u, y = _arx_data()
    sel = order.select_order(u, y, na_max=6, nb_max=6, nk_min=1, nk_max=3, criterion="bic")
    m = sel.model
    assert m.orders == (2, 2, 1)
    # Tolerance: about 5 standard errors of the LS estimate at this noise level and length.
    np.testing.assert_allclose(m.a, A_TRUE, atol=0.01)
    np.testing.assert_allclose(m.b, B_TRUE, atol=0.02)
    assert m.noise_variance == pytest.approx(0.01, rel=0.1)
    assert len(sel.candidates) == 6 * 6 * 3


@pytest.mark.parametrize("criterion", ["aic", "fpe"])
def test_other_criteria_find_the_true_delay(criterion):
    u, y = _arx_data(seed=2)
    m = order.select_order(u, y, criterion=criterion).model
    assert m.nk == 1 and m.na >= 2 and m.nb >= 2


def test_simulation_focus_removes_output_error_bias():
    # White noise added to the *output* (output-error data): plain least squares is biased,
    # the 1/A-prefiltered (simulation-focus) fit is not.
    rng = np.random.default_rng(3)
    u = rng.standard_normal(4000)
    y = signal.lfilter(np.r_[0.0, B_TRUE], A_TRUE, u) + 0.5 * rng.standard_normal(4000)
    plain = arx.arx_fit(u, y, 2, 2, 1)
    focused = arx.arx_fit(u, y, 2, 2, 1, focus="simulation")
    err_plain = np.max(np.abs(plain.a - A_TRUE))
    err_focus = np.max(np.abs(focused.a - A_TRUE))
    assert err_focus < 0.02
    assert err_plain > 3 * err_focus


def test_simulate_and_predict_match_the_definition():
    u, y = _arx_data(n=500, noise=0.0)
    m = arx.arx_fit(u, y, 2, 2, 1)
    assert validation.fit_percent(y, m.simulate(u)) > 99.99
    np.testing.assert_allclose(m.predict(u, y)[5:], y[5:], atol=1e-9)
    num, den = m.polynomials()
    assert m.tf().dt == 1.0 and len(num) == len(den) == 3


def test_fit_percent():
    y = np.sin(np.linspace(0, 10, 200))
    assert validation.fit_percent(y, y) == pytest.approx(100.0)
    assert validation.fit_percent(y, np.full_like(y, y.mean())) == pytest.approx(0.0)
    assert validation.fit_percent(y, y + 0.1 * (y - y.mean())) == pytest.approx(90.0)


def test_excitation_order():
    t = np.arange(2000)
    assert arx.excitation_order(np.zeros(2000), 6) == 0
    assert arx.excitation_order(np.ones(2000), 6) == 1
    assert arx.excitation_order(np.sin(0.3 * t), 6) == 2
    assert arx.excitation_order(np.sin(0.3 * t) + np.sin(1.1 * t), 6) == 4
    assert arx.excitation_order(np.random.default_rng(0).standard_normal(2000), 6) == 6


def test_single_sine_is_not_persistently_exciting():
    t = np.arange(2000)
    u = np.sin(0.3 * t)
    y = signal.lfilter(np.r_[0.0, B_TRUE], A_TRUE, u)
    with pytest.raises(HesspipeError, match="not persistently exciting"):
        order.select_order(u, y, label="x.csv: column 'u'")


def test_record_too_short():
    u, y = _arx_data(n=60)
    with pytest.raises(HesspipeError, match="record too short"):
        order.select_order(u, y, label="x.csv: column 'u'")
    with pytest.raises(HesspipeError, match="record too short"):
        arx.arx_fit(u[:20], y[:20], 2, 2, 1)


def test_nan_input_is_refused():
    u, y = _arx_data(n=500)
    u[10] = np.nan
    with pytest.raises(HesspipeError, match="NaN"):
        arx.arx_fit(u, y, 2, 2, 1, label="x.csv: column 'u'")


def test_residual_tests_pass_white_and_fail_coloured():
    rng = np.random.default_rng(4)
    u = rng.standard_normal(3000)
    white = rng.standard_normal(3000)
    ok = validation.residual_tests(white, u)
    assert ok.white and ok.independent
    coloured = signal.lfilter([1.0], [1.0, -0.8], white)
    assert not validation.residual_tests(coloured, u).white
    leaking = white + 0.3 * np.r_[0.0, u[:-1]]  # residual still contains the input
    assert not validation.residual_tests(leaking, u).independent
    d = ok.to_dict()
    assert d["whiteness"]["bound"] == pytest.approx(2.5758 / np.sqrt(3000), rel=1e-3)


# -- discrete -> continuous ---------------------------------------------------------------

def test_tustin_round_trip_is_exact():
    sysc = ct.tf([2.0, 3.0], [1.0, 1.4, 4.0])
    sysd = ct.sample_system(sysc, 0.05, method="tustin")
    back, notes = d2c.tustin_d2c(sysd)
    num = np.trim_zeros(np.squeeze(back.num[0][0]), "f")
    den = np.squeeze(back.den[0][0])
    np.testing.assert_allclose(den, [1.0, 1.4, 4.0], rtol=1e-9)
    np.testing.assert_allclose(num[-2:], [2.0, 3.0], rtol=1e-9)
    assert np.all(np.abs(num[:-2]) < 1e-9)
    assert notes == []


def test_delay_poles_at_z_zero_become_pade_all_pass():
    dt = 0.05
    sysd = ct.tf([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], dt)  # z^-2
    sysc, notes = d2c.tustin_d2c(sysd)
    # (double roots: numerically split by about sqrt(eps) * 40)
    np.testing.assert_allclose(np.roots(np.squeeze(sysc.den[0][0])), [-2 / dt, -2 / dt], atol=1e-5)
    np.testing.assert_allclose(np.roots(np.squeeze(sysc.num[0][0])), [2 / dt, 2 / dt], atol=1e-5)
    assert any("Padé" in n for n in notes)
    check = d2c.compare_frequency_response(sysd, sysc, band_hz=(0.01, 2.0))
    assert check.max_gain_error_db < 1e-9      # all-pass: exact gain
    # Each Padé factor lags the true delay by 2 (x - atan x), x = w dt / 2: 1.1 deg at 2 Hz, 20 Hz.
    x = 2 * np.pi * 2.0 * dt / 2
    assert check.max_phase_error_deg == pytest.approx(np.degrees(2 * 2 * (x - np.arctan(x))), rel=1e-3)


def test_negative_real_pole_is_kept_and_reported():
    sysd = ct.tf([0.0, 0.2], [1.0, 0.5], 0.05)  # pole at z = -0.5
    sysc, notes = d2c.tustin_d2c(sysd)
    assert np.roots(np.squeeze(sysc.den[0][0]))[0] == pytest.approx(2 / 0.05 * (-1.5 / 0.5))
    assert any("negative real pole" in n for n in notes)


def test_pole_at_nyquist_is_refused():
    with pytest.raises(HesspipeError, match="z = -1"):
        d2c.tustin_d2c(ct.tf([0.0, 1.0], [1.0, 1.0], 0.1))


def test_frequency_check_detects_a_wrong_model():
    sysd = ct.sample_system(ct.tf([1.0], [1.0, 1.0]), 0.05, method="tustin")
    good, _ = d2c.tustin_d2c(sysd)
    assert d2c.compare_frequency_response(sysd, good).passed
    wrong = ct.tf([1.2], [1.0, 1.0])
    check = d2c.compare_frequency_response(sysd, wrong)
    # 1.58 dB from the gain, plus the (small) warping of the discrete model near 2 Hz
    assert not check.passed and 1.58 < check.max_gain_error_db < 2.0
    with pytest.raises(HesspipeError, match="Nyquist"):
        d2c.compare_frequency_response(sysd, good, band_hz=(0.1, 20.0))


def test_rank_deficient_regressors_are_refused():
    u, y = _arx_data(n=500)
    with pytest.raises(HesspipeError, match="rank deficient"):
        arx.arx_fit(np.zeros(500), y, 2, 2, 1, label="x.csv: column 'u'")
    # u(t-1) and u(t-2) identical columns: a constant input
    with pytest.raises(HesspipeError, match="rank deficient"):
        arx.arx_fit(np.ones(500), y, 1, 2, 1)


def test_ill_conditioned_solver_agrees_with_svd_least_squares():
    # A slowly varying input makes the regressors nearly collinear (condition number ~4e11):
    # the Cholesky-QR path, which must agree with LAPACK's SVD solver.
    rng = np.random.default_rng(5)
    u = signal.lfilter([1.0], np.poly([0.99, 0.99, 0.99]), rng.standard_normal(3000))
    y = signal.lfilter(np.r_[0.0, B_TRUE], A_TRUE, u) + 1e-6 * rng.standard_normal(3000)
    phi, target = arx._regression(u, y, 4, 4, 1, 6)
    scaled = phi / np.linalg.norm(phi, axis=0)
    assert arx._NORMAL_EQUATIONS_COND < np.linalg.cond(scaled) < arx._RANK_COND
    ref = np.linalg.lstsq(phi, target, rcond=None)[0]
    m = arx.arx_fit(u, y, 4, 4, 1, start=6)
    np.testing.assert_allclose(np.r_[m.a[1:], m.b], ref, atol=1e-5)
