"""Numbers taken from the source paper (SPEC.md), written once.

Modules and tests import these instead of copying them. Plain tuples of floats
(no numpy) so that importing this module stays light; build a transfer function
with ``control.tf(*EQ16)``.
"""

from __future__ import annotations

#: The paper's Eq. 16: lateral wind (ft/s) -> roll rate (rad/s) ARX model of its
#: Boeing 757, continuous, as printed: ``(num, den)``, coefficients in descending
#: powers of s (4 poles, 3 zeros).
EQ16 = ((-0.2554, 14.4, -272.6, 25.72), (1.0, 84.37, 452.2, 1510.0, 628.8))

#: The rolling approximation of Table 4's aircraft (Eq. 14): aileron (rad) -> roll
#: rate (rad/s), ``p / delta_a = 2.436 / (s + 1.0496)`` (``Lda = 2.436`` 1/s^2,
#: ``Lp = -1.0496`` 1/s), as ``(num, den)``.
EQ14 = ((2.436,), (1.0, 1.0496))

#: The band of the paper's fitness (Eq. 10) and of every analysis that follows it, Hz: the
#: control spectra are compared, and the describing function's lines taken, from 0 to 5 Hz.
FITNESS_BAND_HZ = (0.0, 5.0)

#: Welch segment length of the paper's PSD estimate (Eqs. 5-9), samples; also the
#: fewest samples a record needs to give one spectral segment.
WELCH_SEGMENT = 1024

#: Overlap between consecutive Welch segments, samples.
WELCH_OVERLAP = 32

#: Energy-loss factor U of the Hamming window (Eq. 8), dimensionless.
WELCH_CORRECTION = 0.612
