"""Shared inputs of the stage-three tests: the paper's analytic plants and seeded disturbances.

Yc is the rolling approximation of SPEC.md (2.436 / (s + 1.0496)), Yd the
paper's Eq. 16; 70 s at 50 Hz. Built directly (no dependence on the other
stages), so these tests check stage three alone.
"""

from __future__ import annotations

import control as ct
import numpy as np

from hesspipe.core.formats import Plants
from hesspipe.core.paper import EQ14, EQ16

DT = 0.02
N = 3500
YC = ct.tf(*EQ14)
YD = ct.tf(*EQ16)


def plants() -> Plants:
    return Plants(YC, YD, {"source": "tests: SPEC.md Eq. 14 and Eq. 16"})


def multisine(t, *, seed=3, fmax=5.0, period=70.0, scale=0.5, offset=0.0):
    """Seeded multisine up to `fmax` Hz, faded in over 2 s (smooth at any time step)."""
    rng = np.random.default_rng(seed)
    freqs = np.arange(1, int(fmax * period) + 1) / period
    phase = rng.uniform(0, 2 * np.pi, freqs.size)
    amp = 1.0 / np.sqrt(1.0 + (freqs / 0.5) ** 2)
    x = (amp[:, None] * np.cos(2 * np.pi * freqs[:, None] * t[None, :] + phase[:, None])).sum(0)
    ramp = 0.5 - 0.5 * np.cos(np.pi * np.clip(t / 2.0, 0.0, 1.0))
    return (x * scale + offset) * ramp


def broadband(seed=1, n=N):
    """Seeded broadband disturbance (moving-average filtered white noise), ft/s."""
    rng = np.random.default_rng(seed)
    return np.convolve(rng.standard_normal(n), np.ones(10) / 10, "same") * 5.0


def reference_control(p, t, w, *, motion=None, pade_order=10, yc=YC, yd=YD):
    """Independent reference: python-control state-space interconnection of the original
    (optionally + motion path TF) Hess loop with a Padé delay, forced_response at the
    time step of `t`. Returns the control signal."""
    wn, zn = p["wn"], p["zn"]
    pf = ct.tf([p["K1"] * p["K2"], 0], [1, p["1/T1"]])
    if int(p["k"]) == 2:
        pf = pf * ct.tf([1], [1, p["1/T2"]])
    blocks = [
        ct.tf2ss(ct.tf([wn * wn], [1, 2 * zn * wn, wn * wn]), inputs="u", outputs="delta", name="nm"),
        ct.tf2ss(pf, inputs="delta", outputs="up", name="pf"),
        ct.tf2ss(ct.tf(*ct.pade(p["tau0"], pade_order)), inputs="e", outputs="ed", name="delay"),
        ct.tf2ss(yc, inputs="delta", outputs="yc", name="yc"),
        ct.tf2ss(yd, inputs="w", outputs="yd", name="yd"),
        ct.tf2ss(ct.tf([p["Ke"]], [1]), inputs="ed", outputs="edk", name="ke"),
        ct.summing_junction(["yc", "yd"], "y", name="ysum"),
        ct.summing_junction(["-y"], "e", name="esum"),
    ]
    terms = ["edk", "-up"]
    if motion is not None:
        blocks.append(ct.tf2ss(motion, inputs="y", outputs="uv", name="mv"))
        terms.append("-uv")
    blocks.append(ct.summing_junction(terms, "u", name="usum"))
    cl = ct.interconnect(blocks, inputs="w", outputs="delta")
    return ct.forced_response(cl, t, w).outputs
