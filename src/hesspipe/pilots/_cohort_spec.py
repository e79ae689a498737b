"""How a synthetic cohort is drawn and recorded: :class:`CohortSpec` and the named draws.

Implementation module of :mod:`hesspipe.pilots.cohort`, which re-exports its names (the
distributions themselves are described there).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..core.errors import HesspipeError
from ..flight.target import TargetForcing
from ..flight.wind import Excitation, SideWind
from ..pilot.crossover import CrossoverLimits
from .settings import COHORT_DRAWS

#: Bounds of a pilot's remnant share of control variance.
SHARE_RANGE = (0.01, 0.5)


@dataclass(frozen=True)
class CohortSpec:
    """How synthetic pilots are drawn and recorded.

    Attributes
    ----------
    duration_s, dt_s : float
        Record length and sample interval (s). The paper's runs are 70 s.
    gain_spread : float
        Log-normal spread of Ke, K1, K2 around Table 1.
    tau0_spread, wn_spread : float
        Log-normal spreads of the delay and the neuromuscular frequency.
        Zero by default: the paper identifies only Ke, K1, K2 (and Km), and
        pilots differing in parameters that are held at Table 1 give any
        extra free parameter something to absorb. With spreads of 0.15 and
        0.1, Km "improves" a cohort without motion feedback by about a fifth
        (benchmarks/bench_compare.py measures it).
    km_range : (float, float)
        Range of the log-uniform Km of pilots with motion feedback, for
        ``Yc = 1/s`` (multiplied by the plants' gain scale).
    remnant_share, remnant_spread : float
        Share of the pilot's control variance that is remnant noise:
        log-normal around `remnant_share` (truncated to 0.01-0.5); Kn follows
        from it (see the module docstring).
    side_wind : SideWind
        Slow turning wind (lateral component used).
    gust : Excitation
        Seeded excitation added to the lateral wind (ft/s).
    k : int
        Hess model order (1 for the roll-rate task).
    crossover_rad_s : (float, float) or None
        None (default): the Table 1 draw (:mod:`hesspipe.pilots.cohort`). A range: the *crossover-model
        cohort* (:func:`hesspipe.pilots.cohort.draw_crossover_parameters`): each pilot gets a target
        crossover log-uniform on this range, the proprioceptive corner 1/T1 by
        Hess's rule on the plants, and the Ke that puts the tracking loop's
        crossover at the target; pilots whose crossover or phase margin then
        falls outside `limits` are redrawn.
    tau0_s : float
        Centre of the delay's log-normal (Table 1: 0.1 s).
    limits : CrossoverLimits
        What the crossover-model cohort keeps (default 1-5 rad/s, 20-60 deg).
    target : hesspipe.flight.target.TargetForcing or None
        None (default): the paper's task, the side wind and gusts above. A two-input
        forcing: its wind lines (ft/s; with the side wind only if its ``paper_side_wind``)
        and its roll-rate target (the run's ``reference``), periodic over the record. The
        frequency-domain model is the loop's periodic steady state, so the forcing's
        run-in is not simulated (a flight needs it, :mod:`hesspipe.flight.target`).
    """

    duration_s: float = 70.0
    dt_s: float = 0.02
    gain_spread: float = 0.25
    tau0_spread: float = 0.0
    wn_spread: float = 0.0
    km_range: tuple[float, float] = (2.0, 8.0)
    remnant_share: float = 0.1
    remnant_spread: float = 0.3
    side_wind: SideWind = field(default_factory=SideWind)
    gust: Excitation = field(default_factory=lambda: Excitation(kind="noise", rms=3.0, f_max_hz=1.0,
                                                                taper_s=1.0))
    k: int = 1
    crossover_rad_s: tuple[float, float] | None = None
    tau0_s: float = 0.1
    limits: CrossoverLimits = field(default_factory=CrossoverLimits)
    target: TargetForcing | None = None

    @classmethod
    def crossover_model(cls, **kw) -> "CohortSpec":
        """The pipeline's default cohort: pilots a human-factors researcher accepts.

        Target crossover log-uniform on 1.5-4 rad/s and a delay around 0.2 s
        (spread 0.2, within 0.05-0.5 s): SPEC.md's typical identified values
        (crossover 1.5-4 rad/s, visual delay 0.2-0.3 s); kept only within the
        crossover-model limits (1-5 rad/s, 20-60 deg).

        Parameters
        ----------
        **kw
            Fields overriding these defaults.
        """
        return cls(**{"crossover_rad_s": (1.5, 4.0), "tau0_s": 0.2, "tau0_spread": 0.2, **kw})

    def describe(self) -> dict:
        """The distributions in words (written into every truth file)."""
        if self.crossover_rad_s is not None:
            lo, hi = self.crossover_rad_s
            return {
                "wc": f"target crossover log-uniform on [{lo:g}, {hi:g}] rad/s (tracking loop's "
                      "primary crossover in the record's band, hesspipe.pilot.crossover.tracking_crossover)",
                "Ke": "set so that the crossover is at the target (|L(j wc)| = 1)",
                "K1, K2": f"Table 1 x exp(N(0, {self.gain_spread:g}))",
                "1/T1": "Hess's rule on the plants: K1 s/(s + 1/T1) shaped like s Yc over 1-5 rad/s "
                        "(hesspipe.pilots.cohort.hess_corner; 0.01 for 1/s, about 1 for the JSBSim 737)",
                "tau0": f"{self.tau0_s:g} s x exp(N(0, {self.tau0_spread:g})), within 0.05-0.5 s",
                "wn": f"Table 1 x exp(N(0, {self.wn_spread:g}))",
                "zn, 1/T2": "Table 1",
                "Km": f"g x log-uniform on [{self.km_range[0]:g}, {self.km_range[1]:g}] "
                      "(motion_feedback only)",
                "kept": f"crossover in {list(self.limits.frequency_rad_s)} rad/s and phase margin in "
                        f"{list(self.limits.phase_margin_deg)} deg (others redrawn), closed loop "
                        "stable on the record",
                "Kn": f"remnant share of control variance {self.remnant_share:g} x "
                      f"exp(N(0, {self.remnant_spread:g})), truncated to [{SHARE_RANGE[0]:g}, "
                      f"{SHARE_RANGE[1]:g}]; Tn default",
                "g": "hesspipe.hess.gain_scale(plants)",
                "other effect parameters": "the effect's defaults",
            }
        return {
            "Ke": f"g x Table 1 x exp(N(0, {self.gain_spread:g})), g = plant gain scale",
            "K1, K2": f"Table 1 x exp(N(0, {self.gain_spread:g}))",
            "tau0": f"Table 1 x exp(N(0, {self.tau0_spread:g}))",
            "wn": f"Table 1 x exp(N(0, {self.wn_spread:g}))",
            "zn, 1/T1, 1/T2": "Table 1",
            "Km": f"g x log-uniform on [{self.km_range[0]:g}, {self.km_range[1]:g}] "
                  "(motion_feedback only)",
            "Kn": f"remnant share of control variance {self.remnant_share:g} x "
                  f"exp(N(0, {self.remnant_spread:g})), truncated to [{SHARE_RANGE[0]:g}, "
                  f"{SHARE_RANGE[1]:g}]; Tn default",
            "g": "hesspipe.pilot.crossover.gain_scale(plants): Table 1's crossover at 2.9 rad/s around the plants",
            "other effect parameters": "the effect's defaults",
            "all": "log-normals truncated (redrawn) to the model's search box",
        }


def cohort_spec(draw: str = "crossover_model", **kw) -> CohortSpec:
    """:class:`CohortSpec` of the named draw (:data:`COHORT_DRAWS`), other fields from `kw`.

    Parameters
    ----------
    draw : str
        "crossover_model" (:meth:`CohortSpec.crossover_model`) or "table1" (the
        :class:`CohortSpec` defaults).
    **kw
        Further :class:`CohortSpec` fields.

    Raises
    ------
    HesspipeError
        For an unknown `draw`.
    """
    if draw == "crossover_model":
        return CohortSpec.crossover_model(**kw)
    if draw == "table1":
        return CohortSpec(**kw)
    raise HesspipeError(f"cohort: unknown draw {draw!r}; expected one of {', '.join(COHORT_DRAWS)}")
