"""Crossover frequency and phase margin (SPEC.md checks)."""

import control as ct
import numpy as np
import pytest

from hesspipe.pilot.crossover import CrossoverLimits, crossover
from hesspipe.pilot.hess import table1
from pilot_data import plants


def test_spec_checks_for_rate_and_acceleration_plants():
    c1 = crossover("original", table1(1), ct.tf([1], [1, 0]))
    assert c1.frequency_rad_s == pytest.approx(2.9, abs=0.05)
    assert c1.phase_margin_deg == pytest.approx(70.0, abs=1.0)
    c2 = crossover("original", table1(2), ct.tf([1], [1, 0, 0]))
    assert c2.frequency_rad_s == pytest.approx(3.8, abs=0.05)
    assert c2.phase_margin_deg == pytest.approx(27.0, abs=1.0)
    assert c2.within_limits and not c1.within_limits  # default limits 1-5 rad/s, 20-60 deg


def test_crossover_is_where_open_loop_gain_is_one():
    # Independent check with python-control's margin on the same loop (rate plant,
    # pilot with Padé delay): crossover and phase margin agree.
    p = table1(1)
    nm = ct.tf([100], [1, 2 * 0.707 * 10, 100])
    pf = ct.tf([6, 0], [1, 0.01])
    delay = ct.tf(*ct.pade(0.1, 10))
    yc = ct.tf([1], [1, 0])
    loop = ct.feedback(nm, pf) * p["Ke"] * delay * yc
    gm, pm, wcg, wcp = ct.margin(loop)
    c = crossover("original", p, yc)
    assert c.frequency_rad_s == pytest.approx(wcp, rel=1e-4)
    assert c.phase_margin_deg == pytest.approx(pm, abs=0.05)


def test_motion_path_included_and_limits_configurable():
    pl = plants()
    orig = crossover("original", {}, pl)
    zero = crossover("expanded", {"Km": 0.0}, pl)
    assert zero.frequency_rad_s == pytest.approx(orig.frequency_rad_s)
    more = crossover("expanded", {"Km": 10.0}, pl)
    assert abs(more.frequency_rad_s - orig.frequency_rad_s) > 0.1
    wide = crossover("original", {}, pl, limits=CrossoverLimits((0.5, 10.0), (10.0, 80.0)))
    assert wide.within_limits
    d = wide.to_dict()
    assert set(d) >= {"frequency_rad_s", "phase_margin_deg", "within_limits", "limits", "limits_note"}
    assert "assumption" in d["limits_note"]
    none = crossover("original", {"Ke": 0.0}, pl)
    assert np.isnan(none.frequency_rad_s) and not none.within_limits


def test_tracking_crossover_ignores_crossings_the_record_cannot_resolve():
    # A plant like the fitted 737 aileron channel: a slow right-half-plane zero and a slow pole
    # below the roll mode. Table 1's pilot (Ke 50) then has |L| > 1 at 0.001 rad/s, falls
    # through 1 near 0.004 rad/s, rises again and crosses over near 3.5 rad/s: the first
    # crossing is an artefact of the slow roots (a 70 s record resolves nothing below 0.09
    # rad/s); the tracking crossover is the one near 3 rad/s.
    from hesspipe.pilot.crossover import loop_crossover, record_band_floor, tracking_crossover
    from hesspipe.pilot.hess import PilotModel

    yc = ct.tf([0.5, -0.5 * 0.0064], [1.0, 1.07, 0.07])
    p = dict(table1(1), Ke=50.0)
    loop = PilotModel().loop(p)
    from hesspipe.pilot.blocks import from_tf

    block = from_tf(yc)
    first = loop_crossover(loop, block, first=True)
    highest = loop_crossover(loop, block)
    tracking = tracking_crossover(loop, block, 70.0)
    assert first.frequency_rad_s < 0.01
    assert 1.0 < tracking.frequency_rad_s < 5.0
    assert tracking.frequency_rad_s == pytest.approx(highest.frequency_rad_s, rel=1e-6)
    assert record_band_floor(70.0) == pytest.approx(2 * np.pi / 70.0)
    # the same through crossover(..., duration_s=)
    c = crossover("original", p, yc, duration_s=70.0)
    assert c.frequency_rad_s == pytest.approx(tracking.frequency_rad_s, rel=1e-9)


def test_tracking_crossover_is_the_first_fall_not_a_neuromuscular_peak():
    # A lightly damped neuromuscular mode puts |L| back above 1 near wn, far above the
    # tracking loop's crossover; SPEC's highest crossing moves there, the tracking one does not.
    from hesspipe.pilot.blocks import from_tf
    from hesspipe.pilot.crossover import loop_crossover, tracking_crossover
    from hesspipe.pilot.hess import PilotModel

    p = dict(table1(1), zn=0.03, wn=20.0)
    loop = PilotModel().loop(p)
    block = from_tf(ct.tf([1], [1, 0]))
    assert loop_crossover(loop, block).frequency_rad_s > 15.0
    assert 2.0 < tracking_crossover(loop, block, 70.0).frequency_rad_s < 4.0


def test_band_floor_is_checked():
    from hesspipe.core.errors import HesspipeError
    from hesspipe.pilot.crossover import loop_crossover, record_band_floor
    from hesspipe.pilot.hess import PilotModel

    with pytest.raises(HesspipeError, match="duration_s"):
        record_band_floor(0.0)
    with pytest.raises(HesspipeError, match="w_min"):
        loop_crossover(PilotModel().loop(table1(1)), None, w_min=float("nan"))


def test_flat_band_of_a_crossover_model_loop_and_of_a_flat_one():
    from hesspipe.pilot.crossover import FLAT_FACTOR, flat_band

    w = np.geomspace(0.1, 30, 3000)
    cm = flat_band(w, 3.0 / (1j * w) * np.exp(-0.2j * w), 3.0)
    assert cm.low_rad_s == pytest.approx(3.0 / FLAT_FACTOR, rel=0.01)
    assert cm.high_rad_s == pytest.approx(3.0 * FLAT_FACTOR, rel=0.01) and not cm.wide
    assert cm.phase_margin_range_deg[0] == pytest.approx(90 - np.degrees(0.2 * 3.75), abs=0.5)
    # |L| of -6 dB/decade: within 1.25 of 1 over a factor 1.25**(20/6) each side
    flat = flat_band(w, (3.0 / w) ** 0.3 + 0j, 3.0)
    assert flat.wide and flat.high_rad_s / flat.low_rad_s == pytest.approx(FLAT_FACTOR ** (2 / 0.3), rel=0.02)
    assert "within a factor 1.25 of 1" in flat.describe()
    # a loop without phase lag has 180 deg of margin, as phase_margin_deg says (not -180)
    assert flat.phase_margin_range_deg == (180.0, 180.0)
    assert flat_band(w, 3.0 / (1j * w), float("nan")) is None


def test_the_model_crossover_reports_its_flat_band():
    c = crossover("original", table1(1), ct.tf([1], [1, 0]))
    band = c.to_dict()["flat_band"]
    assert band["low_rad_s"] < c.frequency_rad_s < band["high_rad_s"] and band["wide"] is False
