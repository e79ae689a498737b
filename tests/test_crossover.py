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
