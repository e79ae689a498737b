"""lab12_yaw_mat.py -- SYNTHETIC laboratory data generator (independent reviewer).

EVERYTHING THIS SCRIPT WRITES IS SYNTHETIC.  No human took part; every "person"
is a simulated quasi-linear operator model whose parameters are drawn from the
ranges reported in the manual-control literature (Zaal, Pool, Mulder,
van Paassen, Hosman, Nieuwenhuizen et al.).

Usage:  python benchmarks/labs/lab12_yaw_mat.py SEED OUTDIR

The simulated laboratory
------------------------
* Yaw tracking task, compensatory display (the display shows the yaw error
  psi_tgt - psi), target and disturbance multisines on interleaved lines of
  the 81.92 s measurement window, disturbance added at the plant input.
* Controlled elements: SI  psi = Kc/s  * stick  (+ 1/s  * fd),  Kc = 5  (deg/s)/V
                       DI  psi = Kc/s^2* stick  (+ 1/s^2* fd),  Kc = 16 (deg/s^2)/V
  The stick is a side-stick potentiometer, +-5 V = full deflection.
* Motion condition: the cab yaws with gain 0.6 through a 2nd-order high-pass
  washout (0.5 rad/s, zeta 0.7), a 2nd-order platform lag (25 rad/s, zeta 0.7)
  and a 30 ms transport delay.  Static condition: cab fixed.
* Person: Hpe = Kv (TL s + 1) e^{-tau_v s} on the perceived error, semicircular
  canals (Hosman/Zaal) on the cab yaw rate with gain Km and delay tau_m
  (subtracted), neural command -> arm + stick mass-spring-damper (recorded
  stick = manipulator position).  Remnant = filtered observation noise on the
  perceived error, scaled to a target share of the stick power.  Slow visual
  gain drift; a short control lapse in a few runs.
* Time-domain simulation at 1 kHz with exact ZOH discretisation of every linear
  block and exact integer-sample delay buffers; logged at 100 Hz to MATLAB
  v5 .mat files (one struct `run` per file), byte-reproducible per SEED.
"""
import io
import json
import os
import sys
import time

import numpy as np
from scipy import io as sio
from scipy import linalg, signal
from scipy.optimize import brentq

LABEL = "SYNTHETIC data - simulated operators, lab12_yaw_mat (not human data)"

# ----------------------------------------------------------------- lab design
FS = 100.0                     # logging rate (Hz)
H = 1e-3                       # simulation step (s)
DEC = int(round(1.0 / (FS * H)))
N_WIN = 8192
T_WIN = N_WIN / FS             # 81.92 s
RUNIN = 8.08                   # s before the measurement window
I_WIN0 = int(round(RUNIN * FS))  # 808 (0-based)
T_TOT = 90.0
N_LOG = int(round(T_TOT * FS))   # 9000
N_SIM = int(round(T_TOT / H))    # 90000
FADE = 3.0                     # s raised-cosine fade-in of both forcings
W0 = 2 * np.pi / T_WIN
KD = np.array([5, 11, 23, 37, 51, 71, 101, 137, 171, 226])   # disturbance lines
KT = np.array([6, 13, 27, 41, 53, 73, 103, 139, 174, 229])   # target lines
SIG_T = 1.2                    # deg rms target
SIG_YD = 2.0                   # deg rms of the open-loop yaw the disturbance would cause
N_PHASESETS = 4                # one phase realisation per run number

KC = {"SI": 5.0, "DI": 16.0}   # (deg/s)/V , (deg/s^2)/V
NINT = {"SI": 1, "DI": 2}
V_FULL = 5.0                   # V at full deflection
STICK_DEG_FULL = 18.0          # stick angle at full deflection (deg)
STICK_I = 0.010                # stick inertia kg m^2 (about pivot)
STICK_K = 1.5                  # stick spring Nm/rad
STICK_B = 0.05                 # stick damper Nm s/rad

KMOT = 0.6                     # motion gain (cab yaw / simulated yaw, in washout passband)
WW, ZW = 0.5, 0.7              # washout 2nd-order high pass
WP, ZP = 25.0, 0.7             # platform 2nd-order lag
TAU_P = 0.030                  # platform transport delay (s)
SCC = dict(tau1=5.97, tauL=0.11, tau2=0.005)   # Hosman / Zaal semicircular canals

ELEMENTS = ["SI", "DI"]
CONDS = ["motion", "static"]
N_PERS = 10
N_RUNS = 4
N_LAPSE_RUNS = 8


def hs_shape(w):
    s = 1j * w
    return np.abs((1 + 0.1 * s) ** 2 / (1 + 0.8 * s) ** 2)


def crest_search(rng, k, amp, ntry=300):
    """pick phases with low crest factor for a multisine on bins k (8192 grid)."""
    best, bphi = np.inf, None
    for _ in range(ntry):
        phi = rng.uniform(0, 2 * np.pi, len(k))
        X = np.zeros(N_WIN // 2 + 1, complex)
        X[k] = amp * np.exp(1j * (phi - np.pi / 2)) * N_WIN / 2
        x = np.fft.irfft(X, N_WIN)
        cf = np.max(np.abs(x)) / np.sqrt(np.mean(x ** 2))
        if cf < best:
            best, bphi = cf, phi
    return bphi, best


def fade(t):
    f = np.where(t >= FADE, 1.0, 0.5 - 0.5 * np.cos(np.pi * np.clip(t, 0, FADE) / FADE))
    fd = np.where((t > 0) & (t < FADE), 0.5 * np.pi / FADE * np.sin(np.pi * np.clip(t, 0, FADE) / FADE), 0.0)
    return f, fd


def multisine(t, w, amp, phi):
    """value and time derivative, with fade-in; t 1-D."""
    arg = np.outer(t, w) + phi
    s = np.sin(arg) @ amp
    sd = np.cos(arg) @ (amp * w)
    f, fd = fade(t)
    return f * s, f * sd + fd * s


# ------------------------------------------------------------ analytic loop
def scc_tf(s):
    return SCC["tau1"] * s * (SCC["tauL"] * s + 1) / ((SCC["tau1"] * s + 1) * (SCC["tau2"] * s + 1))


def motion_tf(s, delay=True):
    M = KMOT * s * s ** 2 / (s ** 2 + 2 * ZW * WW * s + WW ** 2) * WP ** 2 / (s ** 2 + 2 * ZP * WP * s + WP ** 2)
    return M * np.exp(-s * TAU_P) if delay else M


def loop_L(w, el, p, motion):
    s = 1j * w
    Yc = KC[el] / s ** NINT[el]
    Hnm = p["wnm"] ** 2 / (s ** 2 + 2 * p["znm"] * p["wnm"] * s + p["wnm"] ** 2)
    Hpe = p["Kv"] * (p["TL"] * s + 1) * np.exp(-s * p["tv"])
    L = Hpe
    if motion:
        L = L + p["Km"] * scc_tf(s) * np.exp(-s * p["tm"]) * motion_tf(s)
    return Yc * Hnm * L


WGRID = np.logspace(-1, 2, 6000)


def margins(w, L, nint):
    """crossover(s), phase margin (deg), gain margin (abs) from a frequency response."""
    mag = np.abs(L)
    ph = np.unwrap(np.angle(L))
    ph -= 2 * np.pi * np.round((ph[0] + nint * np.pi / 2) / (2 * np.pi))
    ph = np.degrees(ph)
    lm = np.log(mag)
    idx = np.where((lm[:-1] > 0) & (lm[1:] <= 0))[0]
    idx_up = np.where((lm[:-1] <= 0) & (lm[1:] > 0))[0]
    if len(idx) == 0:
        return np.nan, np.nan, np.nan, 0
    i = idx[0]
    fr = lm[i] / (lm[i] - lm[i + 1])
    lw = np.log(w)
    wc = np.exp(lw[i] + fr * (lw[i + 1] - lw[i]))
    pm = 180 + ph[i] + fr * (ph[i + 1] - ph[i])
    jj = np.where((ph[:-1] > -180) & (ph[1:] <= -180))[0]
    jj = jj[w[jj] > wc]
    gm = 1 / mag[jj[0]] if len(jj) else np.inf
    return wc, pm, gm, len(idx) + len(idx_up)


def char_poly_stable(el, p, motion, order=6):
    """closed-loop poles with Pade(order) delays; True if all in LHP."""
    P = np.polynomial.polynomial  # ascending coefficients

    def asc(c):
        return np.asarray(c, float)[::-1]

    def pade(tau):
        from math import factorial as fa
        c = np.array([fa(2 * order - k) * fa(order) / (fa(2 * order) * fa(k) * fa(order - k)) * tau ** k
                      for k in range(order + 1)])
        sg = (-1.0) ** np.arange(order + 1)
        return c * sg, c                      # ascending powers of s

    Nv, Dv = pade(p["tv"])
    Pn = asc([1, 2 * p["znm"] * p["wnm"], p["wnm"] ** 2])
    sn = np.zeros(NINT[el] + 1)
    sn[-1] = 1
    vis = P.polymul(p["Kv"] * asc([p["TL"], 1]), Nv)
    if motion:
        Nm, Dm = pade(p["tm"])
        Np, Dp = pade(TAU_P)
        Nsc = asc([SCC["tau1"] * SCC["tauL"], SCC["tau1"], 0])
        Dsc = asc([SCC["tau1"] * SCC["tau2"], SCC["tau1"] + SCC["tau2"], 1])
        Pw = asc([1, 2 * ZW * WW, WW ** 2])
        Pp = asc([1, 2 * ZP * WP, WP ** 2])
        mot_num = P.polymul(P.polymul(P.polymul(Nsc, Nm), Np), asc([KMOT * WP ** 2 * p["Km"], 0, 0, 0]))
        mot_den = P.polymul(P.polymul(P.polymul(P.polymul(Dsc, Dm), Dp), Pw), Pp)
        num = P.polyadd(P.polymul(vis, mot_den), P.polymul(mot_num, Dv))
        den = P.polymul(Dv, mot_den)
    else:
        num, den = vis, Dv
    num = KC[el] * p["wnm"] ** 2 * num
    den = P.polymul(P.polymul(den, Pn), sn)
    ch = P.polyadd(den, num)
    r = P.polyroots(ch)
    return bool(np.max(r.real) < -1e-6), float(np.max(r.real))


# ---------------------------------------------------------- discretisation
def zoh(A, B, h=H):
    n, m = B.shape
    Mx = np.zeros((n + m, n + m))
    Mx[:n, :n] = A
    Mx[:n, n:] = B
    E = linalg.expm(Mx * h)
    return E[:n, :n], E[:n, n:]


def second_order(A, i, wn, zn):
    """states i, i+1 of A as a second-order mode (position, rate) of frequency wn, damping zn."""
    A[i, i + 1] = 1
    A[i + 1, i] = -wn ** 2
    A[i + 1, i + 1] = -2 * zn * wn


def block1(el, p, kmot):
    """states [x, xd, y, yd, w1, w2]; inputs [c, d]."""
    wn, zn, kc = p["wnm"], p["znm"], KC[el]
    A = np.zeros((6, 6))
    B = np.zeros((6, 2))
    second_order(A, 0, wn, zn)
    B[1, 0] = wn ** 2
    if el == "SI":
        A[2, 0] = kc
        B[2, 1] = 1
    else:
        A[2, 3] = 1
        A[3, 0] = kc
        B[3, 1] = 1
    second_order(A, 4, WW, ZW)
    A[5, 2] = kmot
    return zoh(A, B)


def block2():
    """states [psi_cab, r_cab, h1, h2]; input delayed washout output."""
    Ah, Bh, Ch, Dh = signal.tf2ss([SCC["tau1"] * SCC["tauL"], SCC["tau1"], 0],
                                  [SCC["tau1"] * SCC["tau2"], SCC["tau1"] + SCC["tau2"], 1])
    A = np.zeros((4, 4))
    B = np.zeros((4, 1))
    second_order(A, 0, WP, ZP)
    B[1, 0] = WP ** 2
    A[2:, 2:] = Ah
    A[2:, 1] = Bh[:, 0]
    Ad, Bd = zoh(A, B)
    Cp = np.array([0.0, Dh[0, 0], Ch[0, 0], Ch[0, 1]])  # perceived yaw rate
    return Ad, Bd, Cp


# ------------------------------------------------------------- persons
def draw_persons(rng):
    base = []
    for i in range(N_PERS):
        base.append(dict(tv=rng.uniform(0.19, 0.27), wnm=rng.uniform(8.5, 13.0),
                         znm=rng.uniform(0.15, 0.40), I_arm=rng.uniform(0.06, 0.11),
                         rem=rng.uniform(0.14, 0.32), dtm=rng.uniform(0.06, 0.13)))
    cohorts = {}
    for el in ELEMENTS:
        nonusers = sorted(rng.choice(N_PERS, 2, replace=False).tolist())
        strengths = np.linspace(0.25, 1.0, N_PERS - 2) + rng.uniform(-0.04, 0.04, N_PERS - 2)
        rng.shuffle(strengths)
        persons = []
        si = 0
        for i in range(N_PERS):
            user = i not in nonusers
            if user:
                st = float(np.clip(strengths[si], 0.2, 1.0))
                si += 1
            else:
                st = float(rng.uniform(0.0, 0.04))
            b = base[i]
            for attempt in range(1000):
                if attempt and attempt % 100 == 0:      # this person's base does not fit: redraw it
                    b = dict(b, wnm=rng.uniform(8.5, 13.0), znm=rng.uniform(0.15, 0.40),
                             tv=rng.uniform(0.19, 0.27))
                ps = dict(wnm=b["wnm"] * rng.uniform(0.95, 1.05), znm=b["znm"] * rng.uniform(0.95, 1.05))
                if el == "SI":
                    ps["tv"] = float(np.clip(b["tv"] + rng.normal(0, 0.01), 0.15, 0.35))
                    ps["TL"] = rng.uniform(0.0, 0.06)
                    wc_t = rng.uniform(2.3, 3.1)
                    cK, kap, lam = 0.07, 0.15, 0.5
                else:
                    ps["tv"] = float(np.clip(b["tv"] + 0.04 + rng.normal(0, 0.01), 0.15, 0.35))
                    ps["TL"] = rng.uniform(0.8, 1.5)
                    wc_t = rng.uniform(1.6, 2.4)
                    cK, kap, lam = 0.50, 0.32, 0.40
                ps["Kv"] = 1.0
                ps["Km"] = 0.0
                ps["tm"] = 0.15
                ps["Kv"] = float(1.0 / np.abs(loop_L(np.array([wc_t]), el, ps, False))[0])
                tm = float(np.clip(ps["tv"] - b["dtm"], 0.10, 0.18))
                pm_ = dict(ps)
                pm_["tm"] = tm
                ps["tm"] = tm
                if user:
                    pm_["Kv"] = ps["Kv"] * (1 + kap * st * rng.uniform(0.7, 1.3))
                    pm_["TL"] = ps["TL"] * (1 - lam * st * rng.uniform(0.7, 1.3))
                else:
                    pm_["Kv"] = ps["Kv"] * rng.uniform(0.98, 1.02)
                    pm_["TL"] = ps["TL"] * rng.uniform(0.98, 1.02)
                pm_["Km"] = cK * st * ps["Kv"] / KMOT
                ok = True
                for pp, mot in ((ps, False), (pm_, True)):
                    wc, pm, gm, nx = margins(WGRID, loop_L(WGRID, el, pp, mot), NINT[el])
                    if not (1.7 <= wc <= 3.6 and 27 <= pm <= (50 if el == "SI" else 52) and gm > 1.3 and nx == 1):
                        ok = False
                if ok:
                    break
            else:
                raise RuntimeError("could not draw person")
            persons.append(dict(id="P%02d" % (i + 1), user=user, strength=st,
                                static=ps, motion=pm_, I_arm=b["I_arm"], rem=b["rem"]))
        cohorts[el] = persons
    return cohorts


def draw_runs(rng, cohorts):
    runs = []
    for el in ELEMENTS:
        for per in cohorts[el]:
            for cond in CONDS:
                for rn in range(1, N_RUNS + 1):
                    base = per[cond]
                    mot = cond == "motion"
                    for attempt in range(200):
                        p = dict(base)
                        p["Kv"] = base["Kv"] * rng.normal(1, 0.03)
                        p["TL"] = base["TL"] * rng.normal(1, 0.05)
                        p["tv"] = float(np.clip(base["tv"] + rng.normal(0, 0.008), 0.15, 0.35))
                        p["tm"] = float(np.clip(base["tm"] + rng.normal(0, 0.005), 0.09, 0.20))
                        p["Km"] = base["Km"] * rng.normal(1, 0.05)
                        wc, pm, gm, nx = margins(WGRID, loop_L(WGRID, el, p, mot), NINT[el])
                        if 1.7 <= wc <= 3.5 and 26 <= pm <= 52 and gm > 1.25 and nx == 1:
                            break
                    p["tv"] = round(p["tv"], 3)
                    p["tm"] = round(p["tm"], 3)
                    drift = dict(lin=rng.uniform(-0.06, 0.04), amp=rng.uniform(0.01, 0.03),
                                 period=rng.uniform(30, 90), phase=rng.uniform(0, 2 * np.pi))
                    rem = float(np.clip(per["rem"] + rng.normal(0, 0.025), 0.11, 0.38))
                    runs.append(dict(element=el, person=per["id"], condition=cond, run=rn, p=p,
                                     user=per["user"], strength=per["strength"], I_arm=per["I_arm"],
                                     drift=drift, rem_target=rem, Tn=rng.uniform(0.10, 0.25),
                                     lapse=None, analytic=dict(wc=wc, pm=pm, gm=gm)))
    idx = rng.choice(len(runs), N_LAPSE_RUNS, replace=False)
    for i in sorted(idx.tolist()):
        t0 = rng.uniform(RUNIN + 8.0, T_TOT - 6.0)
        runs[i]["lapse"] = dict(t_start=round(t0, 3), duration=round(rng.uniform(0.5, 1.0), 3))
    return runs


# ------------------------------------------------------------- simulation
def simulate(runs, forcing, seed, alpha=None):
    """pass 1 (alpha None): linear, columns = forcing part (0..N-1) and unit-noise part
    (N..2N-1), no stick stops.  pass 2: one column per run, forcing + alpha*noise, with the
    stick's mechanical stops at +-V_FULL."""
    N = len(runs)
    M = 2 * N if alpha is None else N
    A1 = np.zeros((M, 6, 8))
    A2, B2, Cp = block2()
    Kv = np.zeros(M)
    TL = np.zeros(M)
    Km = np.zeros(M)
    Dv = np.zeros(M, int)
    Dm = np.zeros(M, int)
    isDI = np.zeros(M, bool)
    kc = np.zeros(M)
    kmot = np.zeros(M)
    an = np.zeros(M)
    Tn = np.zeros(M)
    lap0 = np.full(M, -1)
    lap1 = np.full(M, -1)
    rset = np.zeros(M, int)
    dset = np.zeros(M, int)
    dr = np.zeros((M, 4))
    for j in range(M):
        r = runs[j % N]
        p = r["p"]
        km = KMOT if r["condition"] == "motion" else 0.0
        Ad, Bd = block1(r["element"], p, km)
        A1[j, :, :6] = Ad
        A1[j, :, 6:] = Bd
        Kv[j], TL[j] = p["Kv"], p["TL"]
        Km[j] = p["Km"] if r["condition"] == "motion" else 0.0
        Dv[j] = int(round(p["tv"] / H))
        Dm[j] = int(round(p["tm"] / H))
        isDI[j] = r["element"] == "DI"
        kc[j] = KC[r["element"]]
        kmot[j] = km
        Tn[j] = r["Tn"]
        an[j] = np.exp(-H / r["Tn"])
        if r["lapse"]:
            lap0[j] = int(round(r["lapse"]["t_start"] / H))
            lap1[j] = lap0[j] + int(round(r["lapse"]["duration"] / H))
        rset[j] = r["run"] - 1
        dset[j] = (r["run"] - 1) + (N_PHASESETS if r["element"] == "DI" else 0)
        d = r["drift"]
        dr[j] = [d["lin"], d["amp"], 2 * np.pi / d["period"], d["phase"]]
    if alpha is None:
        isF = (np.arange(M) < N).astype(float)
        isN = 1.0 - isF
    else:
        isF = np.ones(M)
        isN = np.asarray(alpha, float)
    A1T = np.ascontiguousarray(A1.transpose(1, 2, 0))   # (6, 8, M)
    A2T = np.ascontiguousarray(np.concatenate([A2, B2], 1)[None].repeat(M, 0).transpose(1, 2, 0))
    Dp = int(round(TAU_P / H))
    LB = 512
    cols = np.arange(M)
    bufE = np.zeros((LB, M))
    bufED = np.zeros((LB, M))
    bufP = np.zeros((LB, M))
    bufM = np.zeros((LB, M))
    Z1 = np.zeros((8, M))
    Z2 = np.zeros((5, M))
    n = np.zeros(M)
    chold = np.zeros(M)
    logs = {k: np.zeros((N_LOG, M)) for k in ("psi", "stick", "psi_cab", "r_cab")}
    rng_w = np.random.default_rng([seed, 424242])
    CH = 1000
    for k0 in range(0, N_SIM, CH):
        tt = (k0 + np.arange(CH)) * H
        R = np.zeros((CH, N_PHASESETS))
        RD = np.zeros((CH, N_PHASESETS))
        Dd = np.zeros((CH, 2 * N_PHASESETS))
        for q in range(N_PHASESETS):
            R[:, q], RD[:, q] = multisine(tt, forcing["wt"], forcing["At"], forcing["phit"][q])
            Dd[:, q], _ = multisine(tt, forcing["wd"], forcing["Ad"]["SI"], forcing["phid"][q])
            Dd[:, N_PHASESETS + q], _ = multisine(tt, forcing["wd"], forcing["Ad"]["DI"], forcing["phid"][q])
        Rc = R[:, rset] * isF
        RDc = RD[:, rset] * isF
        Dc = Dd[:, dset] * isF
        Wc = np.zeros((CH, M))
        Wc[:, M - N:] = rng_w.standard_normal((CH, N))
        G = 1 + dr[:, 0] * (tt[:, None] / T_TOT - 0.5) + dr[:, 1] * np.sin(dr[:, 2] * tt[:, None] + dr[:, 3])
        KvG = Kv * G
        for jj in range(CH):
            k = k0 + jj
            x = Z1[0]
            y = Z1[2]
            dk = Dc[jj]
            ydot = np.where(isDI, Z1[3], kc * x + dk)
            psi_ref = kmot * y - (WW ** 2 * Z1[4] + 2 * ZW * WW * Z1[5])
            w = Wc[jj] * isN
            ndot = (w - n) / Tn
            ib = k % LB
            bufE[ib] = Rc[jj] - y + n
            bufED[ib] = RDc[jj] - ydot + ndot
            bufP[ib] = psi_ref
            bufM[ib] = Cp @ Z2[:4]
            v = KvG[jj] * (bufE[(k - Dv) % LB, cols] + TL * bufED[(k - Dv) % LB, cols])
            c = v - Km * bufM[(k - Dm) % LB, cols]
            inl = (k >= lap0) & (k < lap1)
            c = np.where(inl, chold, c)
            chold = c
            if k % DEC == 0:
                i = k // DEC
                logs["psi"][i] = y
                logs["stick"][i] = x
                logs["psi_cab"][i] = Z2[0]
                logs["r_cab"][i] = Z2[1]
            Z1[6] = c
            Z1[7] = dk
            Z1[:6] = (A1T * Z1[None]).sum(1)
            if alpha is not None:                      # mechanical stops of the stick
                hit = np.abs(Z1[0]) > V_FULL
                if hit.any():
                    Z1[0] = np.clip(Z1[0], -V_FULL, V_FULL)
                    Z1[1] = np.where(hit, 0.0, Z1[1])
            Z2[4] = bufP[(k - Dp) % LB]
            Z2[:4] = (A2T * Z2[None]).sum(1)
            n = an * n + (1 - an) * w
    return logs


# ------------------------------------------------------------- analysis
def df_check(stick, err, el):
    sl = slice(I_WIN0, I_WIN0 + N_WIN)
    U = np.fft.rfft(stick[sl])
    E = np.fft.rfft(err[sl])
    Hd = U[KD] / E[KD]
    Ht = U[KT] / E[KT]
    w = KD * W0
    L = KC[el] / (1j * w) ** NINT[el] * Hd
    wc, pm, gm, nx = margins(w, L, NINT[el])
    P = np.abs(U[1:]) ** 2
    forced = np.zeros(len(U), bool)
    forced[KD] = True
    forced[KT] = True
    share = 1 - np.sum(np.abs(U[forced]) ** 2) / np.sum(P)
    return wc, pm, share, Hd, Ht


def remnant_share(Uf, Un, a, forced):
    U = Uf + a * Un
    P = np.abs(U[1:]) ** 2
    return 1 - np.sum(np.abs(U[forced]) ** 2) / np.sum(P)


def write_mat(path, struct):
    bio = io.BytesIO()
    sio.savemat(bio, {"run": struct}, format="5", do_compression=False, oned_as="column")
    b = bytearray(bio.getvalue())
    hdr = ("MATLAB 5.0 MAT-file, Platform: lab12 yaw rig logger, " + LABEL).encode("ascii")[:116]
    b[:116] = hdr.ljust(116, b" ")
    with open(path, "wb") as f:
        f.write(bytes(b))


def main():
    if len(sys.argv) != 3:
        print(__doc__.splitlines()[0])
        print("usage: python lab12_yaw_mat.py SEED OUTDIR")
        sys.exit(2)
    t_start = time.time()
    seed = int(sys.argv[1])
    out = sys.argv[2]
    rng = np.random.default_rng([seed, 12])

    # forcing design
    wt, wd = KT * W0, KD * W0
    At = hs_shape(wt)
    At *= SIG_T / np.sqrt(np.sum(At ** 2) / 2)
    Ay = hs_shape(wd)
    Ay *= SIG_YD / np.sqrt(np.sum(Ay ** 2) / 2)
    Ad = {"SI": Ay * wd, "DI": Ay * wd ** 2}
    phit, phid, cft, cfd = [], [], [], []
    for q in range(N_PHASESETS):
        ph, cf = crest_search(rng, KT, At)
        phit.append(ph)
        cft.append(cf)
        ph, cf = crest_search(rng, KD, Ay)
        phid.append(ph)
        cfd.append(cf)
    forcing = dict(wt=wt, wd=wd, At=At, Ad=Ad, phit=phit, phid=phid)

    cohorts = draw_persons(rng)
    runs = draw_runs(rng, cohorts)
    N = len(runs)
    logs1 = simulate(runs, forcing, seed)

    tlog = np.arange(N_LOG) / FS
    sl = slice(I_WIN0, I_WIN0 + N_WIN)
    forced = np.zeros(N_WIN // 2 + 1, bool)
    forced[KD] = True
    forced[KT] = True
    rng_s = np.random.default_rng([seed, 99])
    truth_runs = []
    summary = {}
    alphas = np.zeros(N)
    for i, r in enumerate(runs):
        Uf = np.fft.rfft(logs1["stick"][sl, i])
        Un = np.fft.rfft(logs1["stick"][sl, N + i])
        tgt = r["rem_target"]
        if remnant_share(Uf, Un, 0.0, forced) < tgt:
            alphas[i] = brentq(lambda a: remnant_share(Uf, Un, a, forced) - tgt, 0.0, 1e4, xtol=1e-12)
    del logs1
    logs = simulate(runs, forcing, seed, alpha=alphas)
    for i, r in enumerate(runs):
        el, cond = r["element"], r["condition"]
        tgt = r["rem_target"]
        a = alphas[i]
        comb = {k: logs[k][:, i] for k in logs}
        stop_s = float(np.sum(np.abs(comb["stick"]) >= V_FULL - 1e-9) / FS)
        q = r["run"] - 1
        psi_t, _ = multisine(tlog, wt, At, phit[q])
        dist, _ = multisine(tlog, wd, Ad[el], phid[q])
        stick = comb["stick"] + rng_s.normal(0, 0.002, N_LOG)
        stick = np.round(stick / (20.0 / 65536)) * (20.0 / 65536)      # 16-bit ADC, +-10 V
        r_cab = comb["r_cab"] + 0.02 + rng_s.normal(0, 0.05, N_LOG)      # gyro bias + noise
        psi_cab = comb["psi_cab"] + rng_s.normal(0, 0.005, N_LOG)
        psi = comb["psi"]
        err = psi_t - psi
        sync = np.zeros(N_LOG)
        sync[I_WIN0:I_WIN0 + N_WIN] = 5.0
        f32 = lambda z: np.asarray(z, np.float32).reshape(-1, 1)
        struct = {
            "t": np.asarray(tlog, float).reshape(-1, 1),
            "psi_tgt": f32(psi_t),
            "fd": f32(dist),
            "psi": f32(psi),
            "stick": f32(stick),
            "err_disp": f32(err),
            "r_cab": f32(r_cab),
            "psi_cab": f32(psi_cab),
            "sync": f32(sync),
            "subject": r["person"],
            "element": el,
            "condition": cond,
            "run_no": float(r["run"]),
            "units": "t s; psi_tgt deg; fd %s; psi deg; stick V (+-5 V full); err_disp deg; "
                     "r_cab deg/s; psi_cab deg; sync V" % ("deg/s" if el == "SI" else "deg/s^2"),
            "label": LABEL,
        }
        d = os.path.join(out, "data", el, cond)
        os.makedirs(d, exist_ok=True)
        fn = "%s_%s_%s_run%d.mat" % (r["person"], el, cond, r["run"])
        write_mat(os.path.join(d, fn), struct)

        # self-check on the logged (float32) data
        st32 = struct["stick"][:, 0].astype(float)
        er32 = struct["err_disp"][:, 0].astype(float)
        wc, pm, share, Hd, Ht = df_check(st32, er32, el)
        p = r["p"]
        mot = cond == "motion"
        stab, maxre = char_poly_stable(el, p, mot)
        bounded = bool(np.max(np.abs(psi[sl])) < 30 and np.max(np.abs(comb["stick"])) <= V_FULL + 1e-9)
        # remnant noise level (deg rms of the observation noise on the perceived error)
        Itot = STICK_I + r["I_arm"]
        rem_rms = a * np.sqrt((1 - np.exp(-H / r["Tn"])) / (1 + np.exp(-H / r["Tn"])))
        uses = bool(mot and r["user"])
        truth_runs.append(dict(
            file="data/%s/%s/%s" % (el, cond, fn), person=r["person"], element=el, condition=cond,
            run=r["run"], uses_motion=uses, person_is_motion_user=r["user"],
            motion_use_strength=round(r["strength"], 3),
            params=dict(Kv_V_per_deg=round(p["Kv"], 5), TL_s=round(p["TL"], 4), tau_v_s=p["tv"],
                        Km_V_per_degps=round(p["Km"], 5) if mot else 0.0,
                        Km_person_when_motion=round(p["Km"], 5), tau_m_s=p["tm"],
                        w_nm_rad_s=round(p["wnm"], 3), zeta_nm=round(p["znm"], 3),
                        manipulator=dict(stick_inertia_kgm2=STICK_I, stick_spring_Nm_rad=STICK_K,
                                         stick_damper_Nms_rad=STICK_B, arm_inertia_kgm2=round(r["I_arm"], 4),
                                         arm_stiffness_Nm_rad=round(p["wnm"] ** 2 * Itot - STICK_K, 4),
                                         arm_damping_Nms_rad=round(2 * p["znm"] * p["wnm"] * Itot - STICK_B, 4)),
                        remnant_filter_T_s=round(r["Tn"], 4),
                        remnant_obs_noise_rms_deg=round(float(rem_rms), 5),
                        visual_gain_drift=dict(linear_total=round(r["drift"]["lin"], 4),
                                               sine_amp=round(r["drift"]["amp"], 4),
                                               sine_period_s=round(r["drift"]["period"], 2)),
                        lapse=r["lapse"]),
            remnant_share_target=round(tgt, 4), remnant_share_achieved=round(float(share), 4),
            analytic=dict(crossover_rad_s=round(r["analytic"]["wc"], 3), phase_margin_deg=round(r["analytic"]["pm"], 2),
                          gain_margin=round(float(r["analytic"]["gm"]), 3), closed_loop_stable=stab,
                          max_real_pole=round(maxre, 4)),
            measured=dict(crossover_rad_s=round(float(wc), 3), phase_margin_deg=round(float(pm), 2)),
            stick_at_stop_s=stop_s, bounded=bounded))
        key = (el, cond)
        summary.setdefault(key, []).append((wc, pm, share, stab and bounded, uses,
                                            np.sqrt(np.mean(stick[sl] ** 2))))

    # plants files
    for el in ELEMENTS:
        sdelay = "first-order Pade of the %.3f s platform transport delay included" % TAU_P
        num_m = np.polymul([KMOT * WP ** 2, 0, 0, 0], [-TAU_P / 2, 1])
        den_m = np.polymul(np.polymul([1, 2 * ZW * WW, WW ** 2], [1, 2 * ZP * WP, WP ** 2]), [TAU_P / 2, 1])
        plants = {
            "label": LABEL,
            "control_to_output": {"num": [KC[el]], "den": [1.0] + [0.0] * NINT[el]},
            "disturbance_to_output": {"num": [1.0], "den": [1.0] + [0.0] * NINT[el]},
            "motion_path": {"num": [float(v) for v in num_m], "den": [float(v) for v in den_m]},
            "units": {"control": "stick, V (+-5 V = full deflection)", "output": "yaw psi, deg",
                      "disturbance": "fd, %s, added at the plant input" % ("deg/s" if el == "SI" else "deg/s^2"),
                      "motion_path": "deg of simulated yaw -> deg/s of cab yaw rate"},
            "motion_path_note": "motion gain %.2f * s * washout s^2/(s^2+2*%.2f*%.2f s+%.2f^2) * platform "
                                "%.0f^2/(s^2+2*%.2f*%.0f s+%.0f^2) * delay; %s. Only in motion runs; in "
                                "static runs the cab is fixed." % (KMOT, ZW, WW, WW, WP, ZP, WP, WP, sdelay),
        }
        with open(os.path.join(out, "plants_%s.json" % el), "w") as f:
            json.dump(plants, f, indent=1)

    cohort_truth = {}
    for el in ELEMENTS:
        for cond in CONDS:
            us = [t["uses_motion"] for t in truth_runs if t["element"] == el and t["condition"] == cond]
            cohort_truth["%s_%s" % (el, cond)] = dict(
                cohort_uses_motion=bool(np.mean(us) > 0.5), runs_using_motion=int(np.sum(us)), runs=len(us))
    design = dict(
        label=LABEL, seed=seed, fs_log_Hz=FS, sim_step_s=H, integration="exact ZOH per block, integer-sample delays",
        run_length_s=T_TOT, window_start_s=RUNIN, window_start_index_0based=I_WIN0, window_samples=N_WIN,
        window_s=T_WIN, fade_in_s=FADE, base_freq_rad_s=W0,
        display="compensatory: error psi_tgt - psi shown; no target feedforward possible",
        Kc=KC, element_tf={"SI": "Kc/s", "DI": "Kc/s^2"}, stick_full_scale_V=V_FULL,
        stick_angle_full_deg=STICK_DEG_FULL,
        disturbance="fd added at plant input in output-derivative units; y = Kc/s^n stick + 1/s^n fd",
        target_lines_k=KT.tolist(), disturbance_lines_k=KD.tolist(),
        target_amp_deg=At.round(6).tolist(),
        disturbance_amp={el: Ad[el].round(6).tolist() for el in ELEMENTS},
        disturbance_openloop_yaw_amp_deg=Ay.round(6).tolist(),
        target_phases_by_run=[p.round(6).tolist() for p in phit],
        disturbance_phases_by_run=[p.round(6).tolist() for p in phid],
        crest_factors=dict(target=np.round(cft, 3).tolist(), disturbance=np.round(cfd, 3).tolist()),
        motion=dict(gain=KMOT, washout_w=WW, washout_zeta=ZW, platform_w=WP, platform_zeta=ZP,
                    platform_delay_s=TAU_P),
        semicircular_canals=dict(model="tau1 s (tauL s+1)/((tau1 s+1)(tau2 s+1)) on cab yaw rate", **SCC),
        person_model="c = Kv(t)(TL s+1)e^{-tau_v s}[e+n] - Km Hscc e^{-tau_m s} r_cab ; stick = Hnm c (arm+stick MSD)",
        remnant="n = first-order low-pass (T = remnant_filter_T_s) white noise on the perceived error; "
                "share = 1 - power at all forcing lines / total stick power in window (bins 1..N/2)",
    )
    truth = dict(label=LABEL, design=design, cohorts=cohort_truth,
                 persons={el: [dict(person=p["id"], motion_user=p["user"], strength=round(p["strength"], 3))
                               for p in cohorts[el]] for el in ELEMENTS},
                 runs=truth_runs)
    with open(os.path.join(out, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1, default=float)

    write_readme(out, At, Ad, Ay)

    print("lab12_yaw_mat (SYNTHETIC): %d runs written to %s in %.1f s" % (N, out, time.time() - t_start))
    print("%-3s %-7s %5s %14s %14s %14s %7s %6s %10s" % ("el", "cond", "runs", "crossover", "PM deg",
                                                          "remnant", "stable", "users", "stick rms V"))
    allok = True
    for key in [(e, c) for e in ELEMENTS for c in CONDS]:
        a = np.array([s[:6] for s in summary[key]], float)
        ok = (np.all(a[:, 3] > 0) and np.nanmin(a[:, 0]) >= 1.5 and np.nanmax(a[:, 0]) <= 4
              and np.nanmin(a[:, 1]) >= 20 and np.nanmax(a[:, 1]) <= 60 and a[:, 2].min() >= 0.1
              and a[:, 2].max() <= 0.4)
        allok &= bool(ok)
        print("%-3s %-7s %5d %6.2f-%-6.2f  %6.1f-%-6.1f  %6.3f-%-6.3f %5d/%d %6d  %4.2f-%4.2f %s" % (
            key[0], key[1], len(a), np.nanmin(a[:, 0]), np.nanmax(a[:, 0]), np.nanmin(a[:, 1]),
            np.nanmax(a[:, 1]), a[:, 2].min(), a[:, 2].max(), int(a[:, 3].sum()), len(a), int(a[:, 4].sum()),
            a[:, 5].min(), a[:, 5].max(), "OK" if ok else "OUT OF RANGE"))
    print("lapse runs: %d; all runs in literature ranges and stable: %s" % (N_LAPSE_RUNS, allok))


def write_readme(out, At, Ad, Ay):
    L = []
    L.append("LAB 12 - YAW TRACKING WITH / WITHOUT CAB MOTION  --  *** SYNTHETIC DATA ***")
    L.append("=" * 76)
    L.append("These files were produced by a simulation (lab12_yaw_mat.py). They contain no")
    L.append("human data. They are meant to stand in for real yaw-tracking trials.")
    L.append("")
    L.append("LAYOUT")
    L.append("  data/<SI|DI>/<motion|static>/Pnn_<EL>_<cond>_run<k>.mat   one run per file")
    L.append("  plants_SI.json, plants_DI.json   controlled element, disturbance path, motion path")
    L.append("  10 persons (P01..P10) per element, 2 conditions, 4 runs per condition.")
    L.append("  The same person ids appear in SI and DI.")
    L.append("")
    L.append("FILE CONTENT (MATLAB v5 .mat, one struct variable named `run`)")
    L.append("  Numeric channels are column vectors, 9000 samples, 100 Hz (single precision")
    L.append("  except t, which is double).")
    L.append("    t         s        time since start of the run (0 .. 89.99)")
    L.append("    psi_tgt   deg      target yaw angle (forcing function ft)")
    L.append("    fd        deg/s (SI) or deg/s^2 (DI)   disturbance, added at the plant input")
    L.append("    psi       deg      simulated yaw angle (controlled output)")
    L.append("    stick     V        side-stick position, +-5 V = full deflection (16-bit ADC)")
    L.append("    err_disp  deg      error shown on the display, psi_tgt - psi")
    L.append("    r_cab     deg/s    cab yaw rate, rate gyro (has a small bias + noise; static: ~0)")
    L.append("    psi_cab   deg      cab yaw angle, platform encoder")
    L.append("    sync      V        trigger: 5 V inside the measurement window, 0 V outside")
    L.append("  Strings/scalars: subject ('P03'), element ('SI'|'DI'), condition")
    L.append("  ('motion'|'static'), run_no, units, label (contains the word SYNTHETIC).")
    L.append("")
    L.append("CONTROLLED ELEMENT (stick V -> yaw deg)")
    L.append("  SI:  psi = 5/s   * (stick)  + 1/s   * fd      [Kc = 5 (deg/s)/V]")
    L.append("  DI:  psi = 16/s^2* (stick)  + 1/s^2 * fd      [Kc = 16 (deg/s^2)/V]")
    L.append("  i.e. the disturbance fd is injected at the plant input, expressed as a yaw")
    L.append("  rate (SI) or yaw acceleration (DI) command that adds to Kc*stick.")
    L.append("  The side-stick is a spring-centred stick (inertia 0.010 kg m^2, spring")
    L.append("  1.5 Nm/rad, damper 0.05 Nms/rad, +-18 deg = +-5 V).")
    L.append("")
    L.append("DISPLAY")
    L.append("  Compensatory. 'The display shows yaw angle' is implemented as a yaw-error")
    L.append("  display: a heading marker is drawn at psi - psi_tgt relative to a fixed")
    L.append("  reference line, i.e. the person sees only the error (err_disp), not the")
    L.append("  target and yaw separately. No target preview, no pursuit information.")
    L.append("")
    L.append("RUN TIMING AND MEASUREMENT WINDOW")
    L.append("  Each run lasts 90.00 s and is recorded in full (run-in included).")
    L.append("  Both forcing functions start at t = 0 with a 3 s raised-cosine fade-in.")
    L.append("  Measurement window: t = 8.08 s .. 89.99 s, samples 809..9000 (MATLAB,")
    L.append("  1-based) = 808..8999 (0-based), 8192 samples = 81.92 s, exactly one period")
    L.append("  of both forcing functions; sync = 5 V marks it.")
    L.append("")
    L.append("FORCING FUNCTIONS (sum of sines, base frequency w0 = 2*pi/81.92 = %.5f rad/s)" % W0)
    L.append("  Lines k (w = k*w0); amplitude of psi_tgt in deg; of fd in deg/s (SI),")
    L.append("  deg/s^2 (DI). Phases differ between run numbers 1..4 (same for all persons).")
    L.append("    target                          disturbance")
    L.append("    k    w rad/s  amp deg           k    w rad/s  SI deg/s  DI deg/s^2")
    for i in range(len(KT)):
        L.append("    %-4d %7.3f  %8.4f          %-4d %7.3f  %8.4f  %9.4f" % (
            KT[i], KT[i] * W0, At[i], KD[i], KD[i] * W0, Ad["SI"][i], Ad["DI"][i]))
    L.append("  Amplitudes follow |(1+0.1jw)^2/(1+0.8jw)^2|; target rms %.1f deg; the" % SIG_T)
    L.append("  disturbance is sized so that its open-loop yaw effect (fd/(jw)^n) has")
    L.append("  rms %.1f deg with the same spectral shape." % SIG_YD)
    L.append("")
    L.append("MOTION SYSTEM (motion condition only; static: cab held still)")
    L.append("  cab yaw = 0.6 * s^2/(s^2 + 2*0.7*0.5 s + 0.5^2) * psi    (washout, 2nd order)")
    L.append("  then platform lag 25^2/(s^2 + 2*0.7*25 s + 25^2) and 30 ms transport delay.")
    L.append("  r_cab is the cab's yaw rate, which the occupant feels. plants_*.json holds")
    L.append("  motion_path = psi (deg) -> cab yaw rate (deg/s), with the 30 ms delay as a")
    L.append("  first-order Pade approximant.")
    L.append("")
    L.append("SIMULATION NOTES")
    L.append("  Closed loop simulated in the time domain at 1 kHz; logged every 10th step.")
    L.append("  Participants' parameters are kept in truth.json (not in this README).")
    with open(os.path.join(out, "README.txt"), "w") as f:
        f.write("\n".join(L) + "\n")


if __name__ == "__main__":
    main()
