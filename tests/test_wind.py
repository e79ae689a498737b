"""Wind profile, frames and excitation signals (hesspipe.flight.wind)."""

import numpy as np
import pytest

from hesspipe.core.config import Fields
from hesspipe.core.errors import HesspipeError
from hesspipe.flight.wind import (
    Excitation,
    SideWind,
    filtered_noise,
    heading_to_ned,
    multisine,
    ned_to_heading,
    prbs,
    relative_wind,
    taper,
)

DT = 1.0 / 120.0
T = np.arange(int(70 / DT)) * DT


def test_relative_wind_signs():
    along, lateral = relative_wind([10, 10, 10], [0, 90, 180])
    np.testing.assert_allclose(along, [-10, 0, 10], atol=1e-12)   # head-on, side, tail
    np.testing.assert_allclose(lateral, [0, -10, 0], atol=1e-12)  # from the right -> air moves left


def test_heading_frame_round_trip_and_heading_180():
    rng = np.random.default_rng(1)
    a, l, psi = rng.normal(size=(3, 50))
    n, e = heading_to_ned(a, l, psi)
    a2, l2 = ned_to_heading(n, e, psi)
    np.testing.assert_allclose([a2, l2], [a, l], atol=1e-12)
    # Heading south: a head wind moves the air north; air moving to the right moves west.
    n, e = heading_to_ned(-5.0, 0.0, np.pi)
    assert n == pytest.approx(5.0) and e == pytest.approx(0.0, abs=1e-12)
    n, e = heading_to_ned(0.0, 5.0, np.pi)
    assert n == pytest.approx(0.0, abs=1e-12) and e == pytest.approx(-5.0)


def test_side_wind_turns_clockwise_and_lateral_grows_to_paper_level():
    along, lateral = SideWind()(T, 70.0)
    assert along[0] == 0 and lateral[0] == 0
    # head-on early (air moving backwards), a side wind later, heading for a tail wind
    assert along[len(T) // 4] < 0
    assert np.all(lateral <= 0)  # clockwise: wind from the right
    mag = -lateral
    assert 16.0 <= mag.max() <= 18.0  # paper Fig. 7: grows to about 16-18 ft/s
    assert mag[-1] >= 0.98 * mag.max()
    assert np.all(np.diff(mag[: int(0.9 * len(T))]) >= 0)  # grows monotonically for 90 % of the record
    theta_end = np.degrees(np.arctan2(-lateral[-1], -along[-1]))
    assert theta_end == pytest.approx(120.0, abs=0.1)
    # anticlockwise variant mirrors the lateral component
    _, lat_acw = SideWind(theta_end_deg=-120.0)(T, 70.0)
    np.testing.assert_allclose(lat_acw, -lateral)


def test_multisine_rms_band_and_seed():
    x = multisine(T, f_min_hz=0.1, f_max_hz=1.0, rms=3.0, seed=7)
    assert np.sqrt(np.mean(x ** 2)) == pytest.approx(3.0, rel=1e-12)
    np.testing.assert_array_equal(x, multisine(T, f_min_hz=0.1, f_max_hz=1.0, rms=3.0, seed=7))
    assert not np.allclose(x, multisine(T, f_min_hz=0.1, f_max_hz=1.0, rms=3.0, seed=8))
    power = np.abs(np.fft.rfft(x)) ** 2
    f = np.fft.rfftfreq(len(T), DT)
    inside = (f >= 0.1 - 1e-9) & (f <= 1.0 + 1e-9)
    assert power[~inside].sum() < 1e-12 * power[inside].sum()  # periodic: no leakage
    assert np.count_nonzero(power[inside] > 1e-6 * power.max()) == inside.sum()  # flat: every line


def test_prbs_is_binary_held_balanced_and_seeded():
    x = prbs(len(T), dt=DT, clock_s=0.5, amplitude=0.2, seed=3)
    assert set(np.unique(x)) == {-0.2, 0.2}
    changes = np.flatnonzero(np.diff(x)) + 1
    assert np.all(changes % 60 == 0)  # switches only on the 0.5 s clock
    assert abs(x.mean()) < 0.2 * 0.1
    np.testing.assert_array_equal(x, prbs(len(T), dt=DT, clock_s=0.5, amplitude=0.2, seed=3))
    assert not np.array_equal(x, prbs(len(T), dt=DT, clock_s=0.5, amplitude=0.2, seed=4))


def test_filtered_noise_rms_and_corner():
    x = filtered_noise(len(T), dt=DT, corner_hz=0.5, rms=2.0, seed=0)
    assert np.sqrt(np.mean(x ** 2)) == pytest.approx(2.0, rel=1e-9)
    p = np.abs(np.fft.rfft(x)) ** 2
    f = np.fft.rfftfreq(len(T), DT)
    low, high = p[(f > 0.05) & (f < 0.2)].mean(), p[(f > 10) & (f < 20)].mean()
    assert low > 100 * high  # about (15/0.5)^2 = 900 for a first-order roll-off


def test_taper_and_excitation_none():
    w = taper(T, 1.0)
    assert w[0] == 0 and w[-1] == 0 and w[len(T) // 2] == 1
    assert np.all(Excitation(kind="none").signal(T, 0) == 0)
    x = Excitation(kind="multisine", rms=1.0).signal(T, 0)
    assert x[0] == 0 and np.sqrt(np.mean(x ** 2)) == pytest.approx(1.0, rel=0.05)


@pytest.mark.parametrize("table, field", [
    ({"kind": "chirp"}, "x.kind"),
    ({"rms": -1}, "x.rms"),
    ({"f_min_hz": 1.0, "f_max_hz": 0.5}, "x.f_max_hz"),
    ({"ampl": 1}, "x.ampl"),
])
def test_excitation_rejects_bad_tables(table, field):
    with pytest.raises(HesspipeError, match=f"cfg.toml: field '{field}'"):
        Excitation.from_fields(Fields(table, "cfg.toml", "x"), Excitation())


def test_side_wind_rejects_unknown_and_bad_values():
    with pytest.raises(HesspipeError, match="field 'w.speed_end_fps'"):
        SideWind.from_fields(Fields({"speed_end_fps": "fast"}, "c.toml", "w"))
    with pytest.raises(HesspipeError, match="field 'w.direction'"):
        SideWind.from_fields(Fields({"direction": 3}, "c.toml", "w"))
