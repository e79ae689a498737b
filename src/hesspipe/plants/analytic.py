"""The paper's analytic aircraft: Table 4 → Table 3 → Eqs. 11–14, with a side-wind input.

Roskam's (1979) wide-body transport in the landing approach (AIAA 2009-6032,
Table 4, in ``aircraft/roskam.toml``) is dimensionalised with Table 3
(``q = rho U^2 / 2``, ``Lp = q S b^2 Clp / (2 Ixx U)``, ...) and assembled
into Roskam's small-perturbation lateral-directional equations in stability
axes, which are Eqs. 11–13 of the paper in state-space form::

    U (beta_dot + r)     = g cos(theta) phi + Yb beta_a + Yp p + Yr r + Yda da
    p_dot - A1 r_dot     = Lb beta_a + Lp p + Lr r + Lda da
    r_dot - B1 p_dot     = (Nb + NTb) beta_a + Np p + Nr r + Nda da
    phi_dot              = p
    A1 = Ixz / Ixx,  B1 = Ixz / Izz,  beta_a = beta - v_w / U

``beta`` is the inertial sideslip (lateral velocity / U), ``beta_a`` the
aerodynamic one: a lateral wind ``v_w`` changes only the latter, the
paper's "side wind → sideslip → dihedral roll" path. The rolling
approximation (Eq. 14) keeps only the roll equation: ``p/da = Lda / (s - Lp)``,
and with the wind ``p/v_w = -(Lb / U) / (s - Lp)``.

Units and signs: aileron ``da`` in rad, positive gives positive roll rate
(right wing down); lateral wind ``v_w`` in ft/s, positive when the air moves
towards the right wing (body +y); roll rate ``p`` in rad/s; sideslip in rad,
positive with the relative wind from the right.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import control as ct
import numpy as np

from ..core.config import Fields, aircraft_file, data_dir, load_toml
from ..core.errors import HesspipeError
from ..core.formats import siso_coefficients

_DERIVATIVES = ("Cy_beta", "Cy_p", "Cy_r", "Cy_da", "Cl_beta", "Cl_p", "Cl_r", "Cl_da",
                "Cn_beta", "Cn_p", "Cn_r", "Cn_Tbeta", "Cn_da")


@dataclass(frozen=True)
class AnalyticAircraft:
    """Table 4: geometry, mass, flight condition and dimensionless derivatives.

    Units: ft, ft/s, slug/ft^3, lb (weight), slug ft^2, deg; derivatives per rad.

    Attributes
    ----------
    name : str
    U_fps : float
        True airspeed, ft/s.
    rho_slug_ft3 : float
        Air density, slug/ft^3.
    theta_deg : float
        Pitch attitude (flight-path angle) of the trim, deg.
    g_fps2 : float
        Gravity, ft/s^2.
    S_ft2, b_ft : float
        Wing area (ft^2) and span (ft).
    weight_lb : float
        Weight, lb (:attr:`mass_slug` is the mass).
    Ixx, Iyy, Izz, Ixz : float
        Inertias, slug ft^2.
    derivatives : dict
        Dimensionless stability and control derivatives (``Cl_p`` ...), per rad.
    paper_eq15 : ((float, ...), (float, ...)) or None
        The paper's printed Eq. 15 transfer function, if any.
    path : str
        The file it was read from.
    """

    name: str
    U_fps: float
    rho_slug_ft3: float
    theta_deg: float
    g_fps2: float
    S_ft2: float
    b_ft: float
    weight_lb: float
    Ixx: float
    Iyy: float
    Izz: float
    Ixz: float
    derivatives: dict
    paper_eq15: tuple[tuple[float, ...], tuple[float, ...]] | None = None
    path: str = ""

    @property
    def mass_slug(self) -> float:
        """Mass, slug (``weight_lb / g_fps2``)."""
        return self.weight_lb / self.g_fps2

    @property
    def dynamic_pressure(self) -> float:
        """q = rho U^2 / 2, lb/ft^2."""
        return 0.5 * self.rho_slug_ft3 * self.U_fps ** 2


def load_analytic(name_or_path: str | Path) -> AnalyticAircraft:
    """Read an analytic aircraft file (``kind = "analytic"``, e.g. ``roskam``).

    Parameters
    ----------
    name_or_path : str or Path
        A bare name in ``aircraft/`` or a path to the TOML file.
    """
    path = aircraft_file(name_or_path)
    if not path.exists():
        known = sorted(p.stem for p in data_dir("aircraft").glob("*.toml")
                       if load_toml(p).get("kind") == "analytic")
        raise HesspipeError(f"{path}: file not found; expected an analytic aircraft "
                            f"(known: {', '.join(known) or 'none'})")
    f = Fields(load_toml(path), path)
    if f.string("kind", "jsbsim") != "analytic":
        raise HesspipeError(f"{path}: field 'kind': expected 'analytic' (a Table-4 style aircraft), "
                            f"got {f.table.get('kind', 'jsbsim')!r}")
    c, g, m, d, paper = (f.table_(k) for k in ("condition", "geometry", "mass", "derivatives", "paper"))
    pos = dict(min=0, strict_min=True)
    out = dict(U_fps=c.number("U_fps", **pos), rho_slug_ft3=c.number("rho_slug_ft3", **pos),
               theta_deg=c.number("theta_deg", 0.0, min=-90, max=90), g_fps2=c.number("g_fps2", 32.174, **pos),
               S_ft2=g.number("S_ft2", **pos), b_ft=g.number("b_ft", **pos),
               weight_lb=m.number("weight_lb", **pos), Ixx=m.number("Ixx_slug_ft2", **pos),
               Iyy=m.number("Iyy_slug_ft2", 0.0, min=0), Izz=m.number("Izz_slug_ft2", **pos),
               Ixz=m.number("Ixz_slug_ft2", 0.0))
    derivs = {k: d.number(k, 0.0) for k in _DERIVATIVES}
    eq15 = None
    if paper.table:
        eq15 = (paper.numbers("eq15_num"), paper.numbers("eq15_den"))
    for t in (c, g, m, d, paper, f):
        t.reject_unknown()
    return AnalyticAircraft(name=path.stem, derivatives=derivs, paper_eq15=eq15, path=str(path), **out)


def dimensional_derivatives(ac: AnalyticAircraft) -> dict[str, float]:
    """Table 3: dimensional derivatives.

    Y* in ft/s^2 (Yb, Yda) or ft/s (Yp, Yr); L*, N* in 1/s^2 (beta, da) or
    1/s (p, r). Keys: Yb Yp Yr Yda Lb Lp Lr Lda Nb NTb Np Nr Nda q.

    Parameters
    ----------
    ac : AnalyticAircraft
    """
    q, S, b, U, m = ac.dynamic_pressure, ac.S_ft2, ac.b_ft, ac.U_fps, ac.mass_slug
    c = ac.derivatives
    return {
        "q": q,
        "Yb": q * S * c["Cy_beta"] / m, "Yp": q * S * b * c["Cy_p"] / (2 * m * U),
        "Yr": q * S * b * c["Cy_r"] / (2 * m * U), "Yda": q * S * c["Cy_da"] / m,
        "Lb": q * S * b * c["Cl_beta"] / ac.Ixx, "Lp": q * S * b ** 2 * c["Cl_p"] / (2 * ac.Ixx * U),
        "Lr": q * S * b ** 2 * c["Cl_r"] / (2 * ac.Ixx * U), "Lda": q * S * b * c["Cl_da"] / ac.Ixx,
        "Nb": q * S * b * c["Cn_beta"] / ac.Izz, "NTb": q * S * b * c["Cn_Tbeta"] / ac.Izz,
        "Np": q * S * b ** 2 * c["Cn_p"] / (2 * ac.Izz * U),
        "Nr": q * S * b ** 2 * c["Cn_r"] / (2 * ac.Izz * U), "Nda": q * S * b * c["Cn_da"] / ac.Izz,
    }


def lateral_model(ac: AnalyticAircraft) -> ct.StateSpace:
    """Full lateral-directional model (Eqs. 11–13) with aileron and side-wind inputs.

    States ``beta`` (rad), ``p`` (rad/s), ``r`` (rad/s), ``phi`` (rad); inputs
    ``aileron_rad``, ``wind_lateral_fps``; outputs ``roll_rate_rps``, ``bank_rad``,
    ``sideslip_rad`` (aerodynamic, beta_a), ``yaw_rate_rps``.

    Parameters
    ----------
    ac : AnalyticAircraft
    """
    d = dimensional_derivatives(ac)
    U, g = ac.U_fps, ac.g_fps2 * math.cos(math.radians(ac.theta_deg))
    A1, B1 = ac.Ixz / ac.Ixx, ac.Ixz / ac.Izz
    Nb = d["Nb"] + d["NTb"]
    mass = np.array([[U, 0, 0, 0], [0, 1, -A1, 0], [0, -B1, 1, 0], [0, 0, 0, 1]], dtype=float)
    force = np.array([[d["Yb"], d["Yp"], d["Yr"] - U, g],
                      [d["Lb"], d["Lp"], d["Lr"], 0],
                      [Nb, d["Np"], d["Nr"], 0],
                      [0, 1, 0, 0]], dtype=float)
    # Inputs: aileron, and wind through beta_a = beta - v_w / U (the aerodynamic terms only).
    inputs = np.array([[d["Yda"], -d["Yb"] / U],
                       [d["Lda"], -d["Lb"] / U],
                       [d["Nda"], -Nb / U],
                       [0, 0]], dtype=float)
    A = np.linalg.solve(mass, force)
    B = np.linalg.solve(mass, inputs)
    C = np.array([[0, 1, 0, 0], [0, 0, 0, 1], [1, 0, 0, 0], [0, 0, 1, 0]], dtype=float)
    D = np.array([[0, 0], [0, 0], [0, -1 / U], [0, 0]], dtype=float)
    return ct.ss(A, B, C, D, states=["beta", "p", "r", "phi"],
                 inputs=["aileron_rad", "wind_lateral_fps"],
                 outputs=["roll_rate_rps", "bank_rad", "sideslip_rad", "yaw_rate_rps"],
                 name=f"{ac.name}_lateral")


def characteristic_polynomial(ac: AnalyticAircraft) -> np.ndarray:
    """Roskam's lateral-directional characteristic polynomial (Eq. 12), monic.

    Written from the closed-form coefficients A..E, independently of
    :func:`lateral_model`, so the two can check each other.

    Parameters
    ----------
    ac : AnalyticAircraft

    Returns
    -------
    ndarray
        Coefficients, descending powers of s (roots in 1/s).
    """
    d = dimensional_derivatives(ac)
    U, gc = ac.U_fps, ac.g_fps2 * math.cos(math.radians(ac.theta_deg))
    A1, B1 = ac.Ixz / ac.Ixx, ac.Ixz / ac.Izz
    Yb, Yp, Yr = d["Yb"], d["Yp"], d["Yr"]
    Lb, Lp, Lr = d["Lb"], d["Lp"], d["Lr"]
    Nb, NTb, Np, Nr = d["Nb"], d["NTb"], d["Np"], d["Nr"]
    A = U * (1 - A1 * B1)
    B = -Yb * (1 - A1 * B1) - U * (Lp + Nr + A1 * Np + B1 * Lr)
    C = (U * (Lp * Nr - Np * Lr) + Yb * (Nr + Lp + A1 * Np + B1 * Lr)
         - Yp * (Lb + Nb * A1 + NTb * A1) + U * (Lb * B1 + Nb + NTb)
         - Yr * (Lb * B1 + Nb + NTb))
    D = (-Yb * (Lp * Nr - Np * Lr) + Yp * (Lb * Nr - Nb * Lr - NTb * Lr)
         - gc * (Lb + Nb * A1 + NTb * A1) + U * (Lb * Np - Nb * Lp - NTb * Lp)
         - Yr * (Lb * Np - Nb * Lp - NTb * Lp))
    E = gc * (Lb * Nr - Nb * Lr - NTb * Lr)
    return np.array([A, B, C, D, E]) / A


def modes(ac: AnalyticAircraft) -> dict[str, complex]:
    """Roll, Dutch roll (upper-half-plane pole) and spiral eigenvalues, 1/s.

    Parameters
    ----------
    ac : AnalyticAircraft
    """
    poles = np.linalg.eigvals(lateral_model(ac).A)
    cplx = poles[np.abs(poles.imag) > 1e-9]
    real = np.sort(poles[np.abs(poles.imag) <= 1e-9].real)
    if cplx.size != 2 or real.size != 2:
        raise HesspipeError(f"{ac.path}: lateral modes are not one oscillatory pair and two real roots "
                            f"(poles {np.round(poles, 4).tolist()}); cannot name roll/Dutch roll/spiral")
    return {"roll": complex(real[0]), "dutch_roll": complex(cplx[np.argmax(cplx.imag)]),
            "spiral": complex(real[1])}


def _siso(sys: ct.StateSpace, inp: int, out: int) -> ct.TransferFunction:
    tf = ct.ss2tf(sys[out, inp])
    num, den = siso_coefficients(tf)
    # ss2tf leaves round-off (~1e-16) where the structure has exact zeros, e.g. the zero at
    # s = 0 of p/da (p = s phi) and the double zero of the wind path (a steady wind only
    # drifts the aircraft): make them exact so the file shows the structure.
    num = np.where(np.abs(num) <= 1e-12 * np.max(np.abs(num)), 0.0, num)
    return ct.tf(np.trim_zeros(num, "f") if np.any(num) else [0.0], den)


@dataclass(frozen=True)
class AnalyticPlants:
    """Transfer functions of the analytic aircraft.

    Attributes
    ----------
    full_control, full_disturbance : control.TransferFunction
        Full model: aileron (rad) → roll rate (rad/s); lateral wind (ft/s) → roll rate.
    rolling_control, rolling_disturbance : control.TransferFunction
        Rolling approximation (Eq. 14) and its wind counterpart.
    """

    aircraft: AnalyticAircraft
    full_control: ct.TransferFunction
    full_disturbance: ct.TransferFunction
    rolling_control: ct.TransferFunction
    rolling_disturbance: ct.TransferFunction


def analytic_transfer_functions(ac: AnalyticAircraft) -> AnalyticPlants:
    """Build all four transfer functions of :class:`AnalyticPlants`.

    Parameters
    ----------
    ac : AnalyticAircraft
    """
    sys = lateral_model(ac)
    d = dimensional_derivatives(ac)
    return AnalyticPlants(
        aircraft=ac,
        full_control=_siso(sys, 0, 0), full_disturbance=_siso(sys, 1, 0),
        rolling_control=ct.tf([d["Lda"]], [1.0, -d["Lp"]]),
        rolling_disturbance=ct.tf([-d["Lb"] / ac.U_fps], [1.0, -d["Lp"]]))
