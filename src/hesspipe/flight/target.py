"""Two-input forcing for closed-loop flights: a target multisine interleaved with the wind's.

The paper's task is disturbance-only: the pilot sees e = -y at every excited
frequency, so the visual and the vestibular channel act on the same signal and
the identification cannot tell Km from the proprioceptive loop. The field's
remedy (Stapleford, McRuer & Magdaleno's two-input method; van der Vaart; Pool
et al.) adds a target (reference) multisine on lines interleaved with the
disturbance's: at the target lines the motion path still senses only y, so the
describing function there differs from the one at the disturbance lines by the
vestibular channel (:func:`hesspipe.identification.criteria.model_df_reference`).

:class:`TargetForcing` makes both signals: the lateral-wind excitation (ft/s) on
the disturbance lines and the roll-rate reference (rad/s) on the lines one bin
above them, both periodic over the record so that each line falls on one DFT
bin, with the bins between left free for the remnant.

Two design choices decide whether the lines can be read (measured on flown runs,
``benchmarks/bench_km_identifiability.py``): a run-in (``run_in_s``) before the analysed
period, so that the loop's start-up transient (its slow proprioceptive and washout modes
take 10-20 s to settle) does not leak into the lines, and no paper's turning side wind
(``paper_side_wind``), whose ~17 ft/s drift leaks over the low wind lines and hides them.
Both are off by default (the first two-input study's design); :data:`TWO_INPUT` has both on.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..core.errors import HesspipeError
from ..core.seeds import derive_seed

TARGET_KINDS = ("none", "multisine")
"""``[pilots] target``: the paper's disturbance-only task, or a target multisine added."""


def interleaved_lines(period_s: float, n_lines: int, f_min_hz: float, f_max_hz: float):
    """Disturbance and target line numbers (multiples of 1/period_s), disjoint and interleaved.

    Disturbance lines are log-spaced over the band, at least three bins apart and
    never below k = 2; the target takes k + 1 of each.

    Parameters
    ----------
    period_s : float
        The record's period, s.
    n_lines : int
        Lines per set.
    f_min_hz, f_max_hz : float
        Band, Hz.

    Returns
    -------
    k_disturbance, k_target : ndarray of int
    """
    k_lo = max(2, int(round(f_min_hz * period_s)))
    k_hi = int(np.floor(f_max_hz * period_s)) - 1
    if n_lines < 1 or k_hi < k_lo + 3 * (n_lines - 1):
        raise HesspipeError(f"target: {n_lines} lines three bins apart do not fit between "
                            f"{f_min_hz:g} and {f_max_hz:g} Hz in a {period_s:g} s record")
    k = np.round(np.geomspace(k_lo, k_hi, n_lines)).astype(int)
    for i in range(1, n_lines):
        k[i] = max(k[i], k[i - 1] + 3)
    for i in range(n_lines - 1, 0, -1):  # squeeze from the top if spacing pushed past k_hi
        k[i] = min(k[i], k_hi - 3 * (n_lines - 1 - i))
    return k, k + 1


def line_multisine(t, k, period_s: float, rms: float, seed: int, corner_hz: float = 0.0,
                   fall_hz: float = 0.0, amplitudes=None) -> np.ndarray:
    """Sum of sines on lines `k` (cycles per `period_s`), random phases, RMS `rms`.

    Amplitudes are flat, or with `corner_hz` > 0 proportional to ``f / (f + corner_hz)``:
    a rate whose integral (the bank angle of a roll-rate target) stays bounded at the
    low lines.

    Parameters
    ----------
    t : array_like
        Sample times, s (the phases are referred to ``t[0]``).
    k : sequence of int
        Line numbers: line ``k`` has frequency ``k / period_s`` Hz.
    period_s : float
        Period of the multisine, s.
    rms : float
        Standard deviation of the returned signal, in the signal's units (rad/s for a
        roll-rate target, ft/s for a wind).
    seed : int
        Seed of the random phases.
    corner_hz : float
        Amplitude corner, Hz (0: flat amplitudes).
    fall_hz : float
        With `fall_hz` > 0 the amplitudes are also multiplied by ``1 / (1 + f / fall_hz)``:
        more power on the low lines.
    amplitudes : array_like, optional
        Given, the lines' amplitudes themselves (signal units, one per line): `rms`,
        `corner_hz` and `fall_hz` are then not used.

    Returns
    -------
    ndarray
        The multisine at `t`.
    """
    t = np.asarray(t, dtype=float)
    f = np.asarray(k, dtype=float) / period_s
    phases = np.random.default_rng(seed).uniform(0.0, 2.0 * np.pi, len(k))
    sines = np.sin(2.0 * np.pi * np.outer(t - t[0], f) + phases)
    if amplitudes is not None:
        return sines @ np.asarray(amplitudes, dtype=float)
    x = sines @ _shape(f, corner_hz, fall_hz)
    sd = float(np.std(x))
    return x * (rms / sd) if sd > 0 else x


def _shape(f, corner_hz: float, fall_hz: float = 0.0) -> np.ndarray:
    """Relative line amplitudes at `f` (Hz): ``f / (f + corner_hz)`` (flat for 0), times
    ``1 / (1 + f / fall_hz)`` for `fall_hz` > 0."""
    a = f / (f + corner_hz) if corner_hz > 0 else np.ones_like(f)
    return a / (1.0 + f / fall_hz) if fall_hz > 0 else a


def line_amplitudes(k, period_s: float, rms: float, corner_hz: float = 0.0) -> np.ndarray:
    """Amplitudes of :func:`line_multisine`'s lines for RMS `rms` (lines on distinct bins).

    Parameters
    ----------
    k : sequence of int
        Line numbers (frequency ``k / period_s`` Hz).
    period_s : float
        Period, s.
    rms : float
        RMS of the sum, the signal's units.
    corner_hz : float
        Amplitudes proportional to ``f / (f + corner_hz)`` (0: flat).

    Returns
    -------
    ndarray
        One amplitude per line, the signal's units (the RMS of the sum is ``sqrt(sum a^2 / 2)``).
    """
    a = _shape(np.asarray(k, dtype=float) / period_s, corner_hz)
    return a * rms / np.sqrt(np.sum(a ** 2) / 2.0)


@dataclass(frozen=True)
class TargetForcing:
    """A wind excitation and a roll-rate target on interleaved multisine lines.

    Attributes
    ----------
    target_rms : float
        RMS of the reference, rad/s (roll rate).
    wind_rms : float
        RMS of the lateral-wind excitation, ft/s (replaces the flight's own).
    n_lines : int
        Lines per set.
    f_min_hz, f_max_hz : float
        Band of both sets, Hz.
    corner_hz : float
        The target's amplitudes rise like ``f / (f + corner_hz)`` (Hz): a roll-rate
        target whose bank angle stays small at the low lines.
    wind_fall_hz : float
        The wind's amplitudes fall like ``1 / (1 + f / wind_fall_hz)`` (Hz; 0: flat): more
        wind on the low lines, where the pilot's high loop gain leaves little error.
    run_in_s : float
        Run-in, s: the signals are periodic with period = record length - `run_in_s`,
        so the record's last period is one whole period of both and the start-up
        transient falls in the run-in (the analysis window ends at the record's end).
    paper_side_wind : bool
        Keep the paper's turning side wind under the wind lines (False: the wind lines alone).
    wind_equivalent : float
        0: the wind's lines as set by `wind_rms` and `wind_fall_hz`. Above 0: an
        output-equivalent wind, as multisine experiments are designed: each wind line's
        amplitude is divided by the disturbance path's gain ``|Yd(j w)|`` (roll rate per
        ft/s of wind, given to :meth:`signals`), so that at the output it stands at
        `wind_equivalent` times the amplitude of the target line next to it (1: the wind
        moves the roll rate as much as the target at every line). `wind_rms` is then unused.
    """

    target_rms: float = 0.02
    wind_rms: float = 3.0
    n_lines: int = 12
    f_min_hz: float = 0.03
    f_max_hz: float = 2.0
    corner_hz: float = 0.3
    wind_fall_hz: float = 0.0
    run_in_s: float = 0.0
    paper_side_wind: bool = True
    wind_equivalent: float = 0.0

    def __post_init__(self):
        if not isinstance(self.paper_side_wind, bool):
            raise HesspipeError(f"target: paper_side_wind: expected true or false, got {self.paper_side_wind!r}")
        for name in ("target_rms", "wind_rms", "f_min_hz", "f_max_hz", "corner_hz", "wind_fall_hz",
                     "run_in_s", "wind_equivalent"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and np.isfinite(v) and v >= 0):
                raise HesspipeError(f"target: {name}: expected a finite number >= 0, got {v!r}")
        if not self.f_max_hz > self.f_min_hz:
            raise HesspipeError(f"target: f_max_hz: expected above f_min_hz ({self.f_min_hz:g}), "
                                f"got {self.f_max_hz!r}")

    def signals(self, t, seed: int, disturbance_path=None):
        """(wind excitation ft/s, reference rad/s) on `t` (uniform, s), periodic over the record.

        Parameters
        ----------
        t : array
            Sample times, s.
        seed : int
            Seed of both sets' phases (derived per set).
        disturbance_path : callable, optional
            ``disturbance_path(s)``: the complex response of Yd (rad/s of roll rate per
            ft/s of wind) at complex frequencies `s` (rad/s); needed when
            `wind_equivalent` > 0.

        Raises
        ------
        HesspipeError
            A run-in as long as the record, or an output-equivalent wind without its
            disturbance path (or one with no gain at a wind line).
        """
        t = np.asarray(t, dtype=float)
        period = (t[-1] - t[0]) + (t[1] - t[0]) - self.run_in_s
        if not period > 0:
            raise HesspipeError(f"target: run_in_s: expected shorter than the record "
                                f"({(t[-1] - t[0]) + (t[1] - t[0]):g} s), got {self.run_in_s:g}")
        kd, kt = interleaved_lines(period, self.n_lines, self.f_min_hz, self.f_max_hz)
        amplitudes = None
        if self.wind_equivalent > 0:
            if disturbance_path is None:
                raise HesspipeError("target: wind_equivalent: an output-equivalent wind needs the "
                                    "disturbance path Yd (disturbance_path)")
            gain = np.abs(np.asarray(disturbance_path(2j * np.pi * kd / period), dtype=complex))
            if not np.all(np.isfinite(gain) & (gain > 0)):
                raise HesspipeError("target: wind_equivalent: the disturbance path Yd has no finite, "
                                    "non-zero gain at every wind line")
            target_amplitude = line_amplitudes(kt, period, self.target_rms, self.corner_hz)
            amplitudes = self.wind_equivalent * target_amplitude / gain
        wind = line_multisine(t, kd, period, self.wind_rms, derive_seed(seed, "target-wind"),
                              fall_hz=self.wind_fall_hz, amplitudes=amplitudes)
        ref = line_multisine(t, kt, period, self.target_rms, derive_seed(seed, "target"), self.corner_hz)
        return wind, ref

    def describe(self) -> dict:
        """The forcing's settings (JSON-ready, units in the names)."""
        return {"kind": "multisine", "target_rms_rad_s": self.target_rms,
                "wind_rms_ft_s": self.wind_rms, "lines_per_set": self.n_lines,
                "band_hz": [self.f_min_hz, self.f_max_hz], "target_corner_hz": self.corner_hz,
                "wind_fall_hz": self.wind_fall_hz,
                "run_in_s": self.run_in_s, "paper_side_wind": self.paper_side_wind,
                "wind_output_equivalent": self.wind_equivalent,
                "note": "disturbance and target on interleaved lines (target = disturbance line + 1); "
                        "periodic over the record less the run-in"}


TWO_INPUT = TargetForcing(run_in_s=15.0, paper_side_wind=False)
"""The two-input design that identification can read on flown runs: a 15 s run-in and the
wind lines alone (fly 85 s for a 70 s analysed period)."""

FORCINGS = {"paper": None, "two_input": TWO_INPUT}
"""Named forcings of a closed-loop flight: ``paper`` (the paper's turning side wind with its
gusts, no forcing lines: None) or ``two_input`` (:data:`TWO_INPUT`)."""


def named_forcing(name: str) -> TargetForcing | None:
    """The forcing called `name` in :data:`FORCINGS` (None for the paper's).

    Parameters
    ----------
    name : str
        "paper" or "two_input".

    Raises
    ------
    HesspipeError
        For another name.
    """
    if name not in FORCINGS:
        raise HesspipeError(f"forcing: expected one of {', '.join(FORCINGS)}, got {name!r}")
    return FORCINGS[name]


def record_flight(config, target: TargetForcing | None):
    """The flight settings whose record, after `target`'s run-in, lasts ``config.duration_s``.

    Parameters
    ----------
    config : hesspipe.flight.approach.FlightConfig
        Settings whose ``duration_s`` (s) is the wanted record length.
    target : TargetForcing or None
        The forcing (None: no run-in, `config` unchanged).

    Returns
    -------
    FlightConfig
        With ``duration_s`` lengthened by the run-in (s).
    """
    if target is None or target.run_in_s == 0:
        return config
    return replace(config, duration_s=config.duration_s + target.run_in_s)
