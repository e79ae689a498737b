#!/usr/bin/env python
"""Synthetic yaw-tracking laboratory ("lab7") generator.

Independent of any identification tool: numpy + scipy only.
Usage:  python lab7_awkward_yaw.py --seed 2026 --out DIR   (the files scored in docs/status.md: seed 2026)
The same seed gives byte-identical output files.
"""
import argparse
import json
import os
import time

import numpy as np
from scipy import signal

# ----------------------------------------------------------------------------
# Lab constants
# ----------------------------------------------------------------------------
DT = 1e-3                 # simulation step (s), 1000 Hz
LOG_DEC = 10              # log every 10th step -> 100 Hz
T_RUNIN = 8.0             # run-in (s), logged
T_MEAS = 81.92            # measurement window (s)
N_FINE = int(round((T_RUNIN + T_MEAS) / DT))      # 89920
N_LOG = N_FINE // LOG_DEC                          # 8992
I0_LOG = int(round(T_RUNIN / (DT * LOG_DEC)))      # 800
N_MEAS = int(round(T_MEAS / (DT * LOG_DEC)))       # 8192
W0 = 2 * np.pi / T_MEAS   # base frequency 0.0767 rad/s
T_FADE = 3.0              # raised-cosine fade-in of the forcing functions

# interleaved integer multiples of W0: target on the 1st, disturbance on the 2nd of each pair
LINES_ALL = [2, 3, 5, 7, 11, 13, 17, 19, 27, 29, 41, 43, 59, 61, 83, 89, 119, 127, 179, 187]
N_T = LINES_ALL[0::2]
N_D = LINES_ALL[1::2]

ELEMENTS = {
    # Kc, forcing RMS (rad for ft; rad stick for fd)
    "SI": dict(Kc=1.5, order=1, ft_rms=0.025, fd_rms=0.040),
    "DI": dict(Kc=4.0, order=2, ft_rms=0.025, fd_rms=0.015),
}

# simulator motion system (TRUE): 2nd-order high-pass washout on yaw, pure platform delay
WO_TRUE = dict(K=0.7, w=0.5, zeta=0.7, platform_delay=0.050)
# lab manual (NOMINAL): same washout, platform modelled as 1st-order lag of 40 ms
WO_NOM = dict(K=0.7, w=0.5, zeta=0.7, platform_lag=0.040)

# canals: afferent response to the cab's yaw ACCELERATION (Hosman; Zaal et al.), i.e. s*Hsc on rate
HSC_NUM = [0.11, 1.0, 0.0]
HSC_DEN = [5.9, 1.0]

N_PERSONS = 10
N_RUNS = 4
N_USERS = 7
LEARN = np.array([0.85, 0.91, 0.96, 1.00])        # gain factor run 1..4
REMN_LEARN = np.array([1.35, 1.20, 1.08, 1.00])   # remnant-share factor run 1..4
CONDS = ["motion", "static"]


# ----------------------------------------------------------------------------
# frequency-domain model of a person's loop
# ----------------------------------------------------------------------------
def motion_true_fr(w):
    s = 1j * w
    W = WO_TRUE["K"] * s**2 / (s**2 + 2 * WO_TRUE["zeta"] * WO_TRUE["w"] * s + WO_TRUE["w"] ** 2)
    return s * W * np.exp(-s * WO_TRUE["platform_delay"])


def hsc_fr(w):
    s = 1j * w
    return np.polyval(HSC_NUM, s) / np.polyval(HSC_DEN, s)


def loop_fr(w, el, p, ge=1.0, gm=1.0, motion=False):
    """Open loop broken at the plant input: L = Hc (Hpe + Hpm M)."""
    s = 1j * w
    Kc, order = ELEMENTS[el]["Kc"], ELEMENTS[el]["order"]
    Hc = Kc / s**order
    Hn = p["wn"] ** 2 / (s**2 + 2 * p["zeta"] * p["wn"] * s + p["wn"] ** 2)
    Hv = ge * p["Ke"] * (p["TL"] * s + 1) * np.exp(-s * p["tau_v"]) * Hn
    L = Hc * Hv
    if motion and p["Km"] > 0:
        Hm = gm * p["Km"] * hsc_fr(w) * np.exp(-s * p["tau_m"]) * Hn
        L = L + Hc * Hm * motion_true_fr(w)
    return L


WGRID = np.logspace(-2, 3, 20000)


def loop_metrics(L, order):
    """crossover(s), phase margin, gain margin, stability (no crossing of (-inf,-1])."""
    mag = np.abs(L)
    lm = np.log(mag)
    idx = np.where(np.sign(lm[:-1]) != np.sign(lm[1:]))[0]
    wcs = []
    for i in idx:
        f = lm[i] / (lm[i] - lm[i + 1])
        wcs.append(np.exp(np.log(WGRID[i]) + f * (np.log(WGRID[i + 1]) - np.log(WGRID[i]))))
    re, im = L.real, L.imag
    j = np.where(np.sign(im[:-1]) != np.sign(im[1:]))[0]
    neg = [(re[i] + re[i + 1]) / 2 for i in j if re[i] + re[i + 1] < 0]
    stable = all(r > -1.0 for r in neg)
    if order == 2 and im[0] > 0:       # low-frequency asymptote above the axis -> unstable
        stable = False
    gm = 1.0 / max([-r for r in neg if r > -1.0], default=1e-9)
    if not wcs:
        return dict(wc=np.nan, pm=np.nan, gm=gm, n_wc=0, stable=stable)
    wc = wcs[-1]
    Lc = np.interp(np.log(wc), np.log(WGRID), re) + 1j * np.interp(np.log(wc), np.log(WGRID), im)
    pm = np.degrees(np.angle(Lc)) + 180.0      # angle in (-180,180]
    if pm > 180:
        pm -= 360
    return dict(wc=float(wc), pm=float(pm), gm=float(gm), n_wc=len(wcs), stable=stable)


def rho_of(el, p):
    """vestibular/visual control-contribution ratio, mean over 1-5 rad/s."""
    w = np.logspace(0, np.log10(5), 50)
    num = np.abs(p["Km"] * hsc_fr(w) * motion_true_fr(w))
    den = np.abs(p["Ke"] * (p["TL"] * 1j * w + 1))
    return float(np.mean(num / den))


# ----------------------------------------------------------------------------
# persons
# ----------------------------------------------------------------------------
def draw_base(el, rng):
    if el == "SI":
        b = dict(Ke=rng.uniform(1.3, 2.6), TL=rng.uniform(0.0, 0.12), tau_v=rng.uniform(0.17, 0.27))
    else:
        b = dict(Ke=rng.uniform(0.35, 0.75), TL=rng.uniform(1.2, 2.5), tau_v=rng.uniform(0.20, 0.32))
    b["wn"] = rng.uniform(7.0, 15.0)
    b["zeta"] = rng.uniform(0.12, 0.40)
    b["tau_m"] = min(rng.uniform(0.07, 0.17), b["tau_v"] - 0.05)
    b["rho_target"] = float(np.exp(rng.uniform(np.log(0.05), np.log(0.6))))
    b["share"] = rng.uniform(0.12, 0.26)
    return b


def draw_runs(el, b, user, weaken_run, rng):
    runs = {}
    # motion users re-balance their visual gain: the canal path adds loop gain in the crossover region
    # canals on acceleration: the vestibular path is rate-like feedback (lead); motion users raise the
    # visual gain (SI) or use less visual lead (DI), as Zaal/Pool et al. report
    kmot = 1 + 1.5 * b["rho_target"] if el == "SI" else 1.0
    tlmot = 1.0 if el == "SI" else 1 / (1 + 0.5 * b["rho_target"])
    b["Ke_motion_factor"] = kmot
    b["TL_motion_factor"] = tlmot
    for cond in CONDS:
        rr = []
        for r in range(N_RUNS):
            use = user and cond == "motion"
            p = dict(
                Ke=b["Ke"] * LEARN[r] * (1 + 0.04 * rng.standard_normal()) * (kmot if use else 1.0),
                TL=b["TL"] * (1 + 0.05 * rng.standard_normal()) * (tlmot if use else 1.0),
                tau_v=round(b["tau_v"] + 0.008 * rng.standard_normal(), 3),
                wn=b["wn"] * (1 + 0.04 * rng.standard_normal()),
                zeta=float(np.clip(b["zeta"] + 0.02 * rng.standard_normal(), 0.1, 0.45)),
                tau_m=round(max(0.05, b["tau_m"] + 0.006 * rng.standard_normal()), 3),
            )
            p["Km"] = 0.0
            if use:
                pk = dict(p)
                pk["Km"] = 1.0
                Km_full = b["rho_target"] / rho_of(el, dict(pk, Ke=b["Ke"] * kmot, TL=b["TL"] * tlmot))
                p["Km"] = Km_full * LEARN[r] * (1 + 0.06 * rng.standard_normal())
                if weaken_run == r:
                    p["Km"] *= rng.uniform(0.25, 0.45)
            share = b["share"] * REMN_LEARN[r] * rng.uniform(0.92, 1.08)
            p["share_target"] = float(np.clip(share, 0.10, 0.40))
            rr.append(p)
        runs[cond] = rr
    return runs


def person_ok(el, runs):
    order = ELEMENTS[el]["order"]
    for cond in CONDS:
        for p in runs[cond]:
            mot = cond == "motion" and p["Km"] > 0
            m = loop_metrics(loop_fr(WGRID, el, p, motion=mot), order)
            if not (m["stable"] and m["n_wc"] == 1 and 1.0 <= m["wc"] <= 5.0
                    and 20.0 <= m["pm"] <= 60.0 and m["gm"] > 1.3):
                return False
            for ge, gm_ in [(1.16, 1.16), (1.16, 0.84), (0.84, 1.16), (0.84, 0.84)]:
                mm = loop_metrics(loop_fr(WGRID, el, p, ge, gm_, motion=mot), order)
                if not (mm["stable"] and mm["pm"] > 8.0):
                    return False
    return True


# ----------------------------------------------------------------------------
# signals
# ----------------------------------------------------------------------------
def multisine(lines, rms, phases, t):
    w = W0 * np.asarray(lines)
    s = 1j * w
    A = np.abs((1 + 0.1 * s) ** 2 / (1 + 0.8 * s) ** 2)
    A = A * rms / np.sqrt(np.sum(A**2) / 2)
    x = np.zeros_like(t)
    for a, wi, ph in zip(A, w, phases):
        x += a * np.sin(wi * t + ph)
    return x, A


def fade(t):
    f = np.ones_like(t)
    m = t < T_FADE
    f[m] = 0.5 * (1 - np.cos(np.pi * t[m] / T_FADE))
    return f


def lp1(x, tau):
    a = np.exp(-DT / tau)
    return signal.lfilter([1 - a], [1, -a], x)


def remnant_unit(rng, t):
    """coloured remnant (with bursts) + slow OU + stick-offset wander, unit-ish scale."""
    wn_r = rng.uniform(1.0, 2.0)
    w = rng.standard_normal(t.size)
    env = np.ones_like(t)
    bursts = []
    nb = int(rng.integers(2, 5))
    for _ in range(nb):
        t0 = rng.uniform(T_RUNIN + 2, t[-1] - 3)
        d = rng.uniform(0.5, 2.0)
        g = rng.uniform(3.0, 5.0)
        m = (t >= t0) & (t < t0 + d)
        # smooth edges (50 ms)
        e = np.clip(np.minimum(t - t0, t0 + d - t) / 0.05, 0, 1)
        env[m] = 1 + (g - 1) * e[m]
        bursts.append(dict(t0=round(float(t0), 3), dur=round(float(d), 3), amp_factor=round(float(g), 3)))
    col0 = lp1(w, 1 / wn_r)
    sd = col0.std()
    col = lp1(w * env, 1 / wn_r) / sd
    tau_ou = rng.uniform(4.0, 12.0)
    ou = lp1(rng.standard_normal(t.size), tau_ou)
    ou *= rng.uniform(0.15, 0.35) / ou.std()
    tau_off = rng.uniform(30.0, 60.0)
    off = lp1(rng.standard_normal(t.size), tau_off)
    off *= rng.uniform(0.08, 0.2) / off.std()
    info = dict(w_filter=round(float(wn_r), 4), tau_ou=round(float(tau_ou), 3),
                tau_offset_wander=round(float(tau_off), 3), bursts=bursts)
    return col + ou + off, info


def drift(rng, t):
    amp = rng.uniform(0.10, 0.15)
    d = np.zeros_like(t)
    for _ in range(3):
        d += rng.uniform(0.5, 1.0) * np.sin(2 * np.pi * t / rng.uniform(25, 120) + rng.uniform(0, 2 * np.pi))
    d *= amp / np.max(np.abs(d))
    return 1 + d, float(amp)


def lapse_mask(t, t0, dur, ramp=0.15):
    m = np.ones_like(t)
    a = np.clip((t - t0) / ramp, 0, 1)              # going out
    b = np.clip((t - (t0 + dur)) / ramp, 0, 1)      # coming back
    m = 1 - a + b
    return np.clip(m, 0, 1)


# ----------------------------------------------------------------------------
# batch time-domain simulation (rows = runs), exact ZOH blocks, integer delays
# ----------------------------------------------------------------------------
def zoh(num, den):
    A, B, C, D = signal.tf2ss(num, den)
    Ad, Bd, Cd, Dd, _ = signal.cont2discrete((A, B, C, D), DT, method="zoh")
    return Ad, Bd[:, 0], Cd[0], float(Dd[0, 0])


def simulate(el, rows, ft, fd, noise, ge_t, gm_t, mask, record_parts=False):
    """rows: list of param dicts (with 'motion' flag). signal arrays shape (N_FINE, R)."""
    R = len(rows)
    Kc, order = ELEMENTS[el]["Kc"], ELEMENTS[el]["order"]
    Av = np.zeros((R, 2, 2)); Bv = np.zeros((R, 2)); Cv = np.zeros((R, 2))
    Am = np.zeros((R, 3, 3)); Bm = np.zeros((R, 3)); Cm = np.zeros((R, 3))
    nv = np.zeros(R, int); nmp = np.zeros(R, int); mot = np.zeros(R)
    for i, p in enumerate(rows):
        wn, z = p["wn"], p["zeta"]
        a, b, c, d = zoh([wn**2 * p["TL"], wn**2], [1, 2 * z * wn, wn**2])
        Av[i], Bv[i], Cv[i] = a, b, c
        a, b, c, d = zoh(np.polymul(HSC_NUM, [wn**2]), np.polymul(HSC_DEN, [1, 2 * z * wn, wn**2]))
        Am[i], Bm[i], Cm[i] = a, b, c
        nv[i] = int(round(p["tau_v"] / DT))
        nmp[i] = int(round((p["tau_m"] + WO_TRUE["platform_delay"]) / DT))
        mot[i] = 1.0 if (p["motion"] and p["Km"] > 0) else 0.0
    Ke = np.array([p["Ke"] for p in rows]); Km = np.array([p["Km"] for p in rows])
    Aw, Bw, Cw, Dw = zoh([WO_TRUE["K"], 0, 0], [1, 2 * WO_TRUE["zeta"] * WO_TRUE["w"], WO_TRUE["w"] ** 2])
    if order == 1:
        Ap = np.array([[1.0]]); Bp = np.array([Kc * DT])
    else:
        Ap = np.array([[1.0, DT], [0.0, 1.0]]); Bp = np.array([Kc * DT**2 / 2, Kc * DT])
    NB = 1024
    ebuf = np.zeros((NB, R)); rbuf = np.zeros((NB, R))
    xv = np.zeros((R, 2)); xm = np.zeros((R, 3)); xw = np.zeros((R, 2)); xp = np.zeros((R, order))
    cols = np.arange(R)
    psi_log = np.zeros((N_LOG, R)); u_log = np.zeros((N_LOG, R))
    uv_log = np.zeros((N_LOG, R)); um_log = np.zeros((N_LOG, R))
    AvT = Av; AmT = Am
    for k in range(N_FINE):
        psi = xp[:, 0]
        e = ft[k] - psi
        ebuf[k % NB] = e
        uvis = np.einsum("ij,ij->i", Cv, xv)
        uves = np.einsum("ij,ij->i", Cm, xm)
        u = mask[k] * (uvis + uves + noise[k])
        pin = u + fd[k]
        psidot = Kc * pin if order == 1 else xp[:, 1]
        r = xw @ Cw + Dw * psidot
        rbuf[k % NB] = r
        xw = xw @ Aw.T + np.outer(psidot, Bw)
        if k % LOG_DEC == 0:
            j = k // LOG_DEC
            psi_log[j] = psi; u_log[j] = u
            if record_parts:
                uv_log[j] = uvis; um_log[j] = uves
        e_d = ebuf[(k - nv) % NB, cols] * (k >= nv)
        r_d = rbuf[(k - nmp) % NB, cols] * (k >= nmp) * mot
        xv = np.einsum("rij,rj->ri", AvT, xv) + Bv * (Ke * ge_t[k] * e_d)[:, None]
        xm = np.einsum("rij,rj->ri", AmT, xm) + Bm * (-Km * gm_t[k] * r_d)[:, None]
        xp = xp @ Ap.T + np.outer(pin, Bp)
    return psi_log, u_log, uv_log, um_log


def line_share(u_log):
    """remnant share = 1 - power at the 20 forcing lines / total (DC excluded), window only."""
    x = u_log[I0_LOG:I0_LOG + N_MEAS]
    X = np.fft.rfft(x, axis=0)
    P = np.abs(X[1:N_MEAS // 2 + 1]) ** 2
    Pl = np.abs(X[LINES_ALL]) ** 2
    return 1 - Pl.sum(0) / P.sum(0)


def band_ratio(a, b, lo=1.0, hi=5.0):
    A = np.fft.rfft(a[I0_LOG:I0_LOG + N_MEAS], axis=0)
    B = np.fft.rfft(b[I0_LOG:I0_LOG + N_MEAS], axis=0)
    w = W0 * np.arange(A.shape[0])
    m = (w >= lo) & (w <= hi)
    return np.sqrt((np.abs(A[m]) ** 2).sum(0) / (np.abs(B[m]) ** 2).sum(0))


# ----------------------------------------------------------------------------
# output
# ----------------------------------------------------------------------------
def fmt(v):
    s = "%.6g" % v
    return "0" if s == "-0" else s


def write_csv(path, header_comments, t, cols, bom):
    lines = ["# " + c for c in header_comments]
    lines.append("t,ft,fd,psi,u")
    arr = np.column_stack(cols)
    for ti, row in zip(t, arr):
        lines.append(",".join([fmt(ti)] + [fmt(v) for v in row]))
    txt = "\r\n".join(lines) + "\r\n"
    with open(path, "wb") as f:
        if bom:
            f.write(b"\xef\xbb\xbf")
        f.write(txt.encode("utf-8"))


def clean(o):
    if isinstance(o, dict):
        return {k: clean(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [clean(v) for v in o]
    if isinstance(o, (np.floating, float)):
        return float(round(float(o), 6))
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, np.bool_):
        return bool(o)
    return o


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("--out", required=True, help="output folder (data/, plants/, truth.json)")
    args = ap.parse_args()
    out = args.out
    t0_wall = time.time()
    ss = np.random.SeedSequence(args.seed)
    el_seeds = dict(zip(ELEMENTS, ss.spawn(len(ELEMENTS))))
    t_fine = np.arange(N_FINE) * DT
    t_log = np.arange(N_LOG) * DT * LOG_DEC
    fd_fade = fade(t_fine)

    # plants (nominal, lab manual)
    os.makedirs(os.path.join(out, "plants"), exist_ok=True)
    nom_den = np.polymul([1, 2 * WO_NOM["zeta"] * WO_NOM["w"], WO_NOM["w"] ** 2], [WO_NOM["platform_lag"], 1])
    for el, E in ELEMENTS.items():
        hc = {"num": [E["Kc"]], "den": [1.0] + [0.0] * E["order"]}
        pj = {
            "control_to_output": hc,
            "disturbance_to_output": hc,
            "motion_path": {"num": [WO_NOM["K"], 0.0, 0.0, 0.0], "den": [float(x) for x in nom_den]},
            "units": {"output": "rad (yaw angle psi)", "control": "rad (stick deflection)",
                      "disturbance": "rad (stick-equivalent, added at plant input)",
                      "motion_path_output": "rad/s (cab yaw rate)"},
            "source": "lab7 simulator manual (NOMINAL): Hc = Kc/s^%d; motion path = s * washout "
                      "K s^2/(s^2+2 zeta w s+w^2), K=%.2f w=%.2f zeta=%.2f, * platform lag 1/(%.3f s+1)"
                      % (E["order"], WO_NOM["K"], WO_NOM["w"], WO_NOM["zeta"], WO_NOM["platform_lag"]),
        }
        with open(os.path.join(out, "plants", "yaw_%s.json" % el), "w") as f:
            json.dump(pj, f, indent=2)
            f.write("\n")

    truth = dict(
        seed=args.seed, synthetic=True,
        time=dict(dt_sim=DT, log_rate_hz=100, run_in_s=T_RUNIN, measurement_window_s=[T_RUNIN, T_RUNIN + T_MEAS - 0.01],
                  fade_in_s=T_FADE, base_frequency_rad_s=W0),
        forcing=dict(target_lines=N_T, disturbance_lines=N_D,
                     target_freqs=[W0 * n for n in N_T], disturbance_freqs=[W0 * n for n in N_D],
                     amplitude_shape="|(1+0.1s)^2/(1+0.8s)^2| scaled to RMS"),
        motion_path_true=dict(description="cab yaw rate = s * K s^2/(s^2+2 zeta w s+w^2) * exp(-tau_p s) * psi",
                              K=WO_TRUE["K"], w=WO_TRUE["w"], zeta=WO_TRUE["zeta"], tau_p=WO_TRUE["platform_delay"],
                              num_without_delay=[WO_TRUE["K"], 0, 0, 0],
                              den_without_delay=[1, 2 * WO_TRUE["zeta"] * WO_TRUE["w"], WO_TRUE["w"] ** 2]),
        motion_path_nominal=dict(num=[WO_NOM["K"], 0, 0, 0], den=[float(x) for x in nom_den]),
        human_model="u = mask*( Hnms*[ Ke(t)*(TL s+1) e^{-tau_v s} e  -  Km(t)*Hsc e^{-tau_m s} r_cab ] + n ),"
                    " Hnms = wn^2/(s^2+2 zeta wn s+wn^2), Hsc=s(0.11s+1)/(5.9s+1) on the cab yaw rate (canals on acceleration), e = ft - psi, r_cab = cab yaw rate",
        rho_definition="mean over 1..5 rad/s of |Km Hsc M_true| / |Ke (TL jw+1)| (vestibular vs visual control contribution per unit psi)",
        elements={}, lapses=[], weakened_vestibular=[],
    )
    sanity = {}

    for el, E in ELEMENTS.items():
        rng = np.random.default_rng(el_seeds[el])
        pid0 = 1 if el == "SI" else 11
        pids = ["S%02d" % (pid0 + i) for i in range(N_PERSONS)]
        users = set(rng.choice(N_PERSONS, N_USERS, replace=False).tolist())
        user_list = sorted(users)
        weaken = {user_list[i]: int(rng.integers(1, 4)) for i in rng.choice(len(user_list), 2, replace=False)}
        rho_hi = 0.2 if el == "SI" else 0.6   # rate-like feedback: an SI loop goes unstable beyond ~0.25
        rho_t = np.exp(np.linspace(np.log(0.05), np.log(rho_hi), N_USERS)) * rng.uniform(0.9, 1.1, N_USERS)
        rho_t = dict(zip(user_list, rng.permutation(rho_t)))
        persons = {}
        n_redraw = 0
        for i in range(N_PERSONS):
            while True:
                b = draw_base(el, rng)
                if i in users:
                    b["rho_target"] = float(rho_t[i])
                runs = draw_runs(el, b, i in users, weaken.get(i, -1), rng)
                if person_ok(el, runs):
                    break
                n_redraw += 1
            persons[i] = (b, runs)
        # lapses: 2 runs per element (not in weakened runs)
        lapses = []
        while len(lapses) < 2:
            i = int(rng.integers(N_PERSONS)); c = CONDS[int(rng.integers(2))]; r = int(rng.integers(N_RUNS))
            if (i, c, r) in [(l[0], l[1], l[2]) for l in lapses] or (c == "motion" and weaken.get(i, -1) == r):
                continue
            lapses.append((i, c, r, round(float(rng.uniform(20, 80)), 3), round(float(rng.uniform(1.0, 2.0)), 3)))

        # ---- build run rows + signals
        rows, meta = [], []
        R = N_PERSONS * len(CONDS) * N_RUNS
        ft = np.zeros((N_FINE, R)); fd = np.zeros((N_FINE, R)); nz = np.zeros((N_FINE, R))
        ge = np.zeros((N_FINE, R)); gm = np.zeros((N_FINE, R)); mk = np.ones((N_FINE, R))
        ft_log = np.zeros((N_LOG, R)); fd_log = np.zeros((N_LOG, R))
        j = 0
        for i in range(N_PERSONS):
            b, runs = persons[i]
            for c in CONDS:
                for r in range(N_RUNS):
                    p = dict(runs[c][r]); p["motion"] = (c == "motion")
                    rng_r = np.random.default_rng(np.random.SeedSequence([args.seed, pid0 + i, CONDS.index(c), r, 7 if el == "SI" else 9]))
                    ph_t = rng_r.uniform(0, 2 * np.pi, len(N_T)); ph_d = rng_r.uniform(0, 2 * np.pi, len(N_D))
                    x, _ = multisine(N_T, E["ft_rms"], ph_t, t_fine); ft[:, j] = x * fd_fade
                    x, _ = multisine(N_D, E["fd_rms"], ph_d, t_fine); fd[:, j] = x * fd_fade
                    ft_log[:, j] = ft[::LOG_DEC, j]; fd_log[:, j] = fd[::LOG_DEC, j]
                    nz[:, j], rinfo = remnant_unit(rng_r, t_fine)
                    ge[:, j], ae = drift(rng_r, t_fine)
                    gm[:, j], am = drift(rng_r, t_fine)
                    lap = [l for l in lapses if l[0] == i and l[1] == c and l[2] == r]
                    if lap:
                        mk[:, j] = lapse_mask(t_fine, lap[0][3], lap[0][4])
                    rows.append(p)
                    meta.append(dict(i=i, pid=pids[i], cond=c, run=r, remnant=rinfo, drift_e=ae, drift_m=am,
                                     bom=bool(rng_r.random() < 0.3), day=int(rng_r.integers(1, 28)),
                                     lapse=lap[0] if lap else None))
                    j += 1
        # ---- pass 1: forcing-only and noise-only (no lapse) to scale the remnant
        zeros = np.zeros_like(ft); ones = np.ones_like(mk)
        _, u_f, _, _ = simulate(el, rows, ft, fd, zeros, ge, gm, ones)
        _, u_n, _, _ = simulate(el, rows, zeros, zeros, nz, ge, gm, ones)
        Pf = (u_f[I0_LOG:I0_LOG + N_MEAS] ** 2).sum(0)
        xn = u_n[I0_LOG:I0_LOG + N_MEAS]
        Pn = ((xn - xn.mean(0)) ** 2).sum(0)
        s_t = np.array([p["share_target"] for p in rows])
        kscale = np.sqrt(s_t * Pf / ((1 - s_t) * Pn))
        del u_f, u_n, zeros
        nz *= kscale[None, :]
        # ---- pass 2: final
        psi_log, u_log, uv_log, um_log = simulate(el, rows, ft, fd, nz, ge, gm, mk, record_parts=True)
        share = line_share(u_log)
        vr = band_ratio(um_log, uv_log)
        assert np.all(np.isfinite(psi_log)) and np.all(np.isfinite(u_log))
        # ---- write files + truth
        el_truth = dict(Kc=E["Kc"], plant="Kc/s^%d" % E["order"], ft_rms=E["ft_rms"], fd_rms=E["fd_rms"],
                        n_redraws=n_redraw, persons={})
        wc_list, pm_list, rho_list = [], [], []
        bounded = []
        for j, (p, m) in enumerate(zip(rows, meta)):
            i, c, r = m["i"], m["cond"], m["run"]
            pid = m["pid"]
            b, runs = persons[i]
            d = os.path.join(out, "data", el, c); os.makedirs(d, exist_ok=True)
            fn = "%s_R%d_%s.csv" % (pid, r + 1, c)
            com = ["Yaw tracking experiment, controlled element %s (Hc = %.1f/s%s), condition: %s" % (el, E["Kc"], "" if E["order"] == 1 else "^2", c),
                   "lab: Motion Lab 7 (fictitious) | date: 2026-03-%02d | subject %s run %d | SYNTHETIC DATA (gen.py seed %d)" % (m["day"], pid, r + 1, args.seed),
                   "units: t s; ft psi rad; fd u rad (stick); logged 100 Hz incl. 8 s run-in (measurement window t = 8.00..89.91 s)"]
            write_csv(os.path.join(d, fn), com, t_log, [ft_log[:, j], fd_log[:, j], psi_log[:, j], u_log[:, j]], m["bom"])
            mot = c == "motion" and p["Km"] > 0
            mtr = loop_metrics(loop_fr(WGRID, el, p, motion=mot), E["order"])
            e_rms = float(np.std(ft_log[I0_LOG:, j] - psi_log[I0_LOG:, j]))
            bounded.append(float(np.max(np.abs(psi_log[:, j]))))
            rec = dict(file="data/%s/%s/%s" % (el, c, fn), Ke=p["Ke"], T_L=p["TL"], tau_v=p["tau_v"], Km=p["Km"],
                       tau_m=p["tau_m"] if p["Km"] > 0 else None, wn=p["wn"], zeta=p["zeta"],
                       remnant_share_target=p["share_target"], remnant_share_achieved=float(share[j]),
                       remnant_scale=float(kscale[j]), remnant=m["remnant"],
                       gain_drift_amplitude_Ke=m["drift_e"], gain_drift_amplitude_Km=(m["drift_m"] if p["Km"] > 0 else None),
                       lapse=(dict(t0=m["lapse"][3], dur=m["lapse"][4]) if m["lapse"] else None),
                       weakened_vestibular=bool(c == "motion" and weaken.get(i, -1) == r),
                       loop_wc=mtr["wc"], loop_pm_deg=mtr["pm"], loop_gm=mtr["gm"],
                       rho_vestibular=(rho_of(el, p) if p["Km"] > 0 else 0.0),
                       sim_vest_over_vis_rms_1to5=(float(vr[j]) if p["Km"] > 0 else 0.0),
                       error_rms_window=e_rms, bom=m["bom"])
            wc_list.append(mtr["wc"]); pm_list.append(mtr["pm"])
            pe = el_truth["persons"].setdefault(pid, dict(uses_motion=bool(i in users), rho_target=(b["rho_target"] if i in users else 0.0),
                                                       base=dict(Ke=b["Ke"], T_L=b["TL"], tau_v=b["tau_v"], wn=b["wn"], zeta=b["zeta"],
                                                                 tau_m=(b["tau_m"] if i in users else None), remnant_share=b["share"]),
                                                       runs={"motion": {}, "static": {}}))
            pe["runs"][c]["R%d" % (r + 1)] = rec
            if m["lapse"]:
                truth["lapses"].append(dict(element=el, person=pid, cond=c, run="R%d" % (r + 1), t0=m["lapse"][3], dur=m["lapse"][4]))
            if rec["weakened_vestibular"]:
                truth["weakened_vestibular"].append(dict(element=el, person=pid, cond=c, run="R%d" % (r + 1), Km=p["Km"]))
            if mot:
                rho_list.append((rho_of(el, p), float(vr[j])))
        truth["elements"][el] = el_truth
        rl = np.array(rho_list)
        sanity[el] = dict(median_wc=float(np.median(wc_list)), wc_range=[min(wc_list), max(wc_list)],
                          median_pm=float(np.median(pm_list)), pm_range=[min(pm_list), max(pm_list)],
                          share_range=[float(share.min()), float(share.max())], share_median=float(np.median(share)),
                          max_abs_psi=max(bounded), max_abs_u=float(np.abs(u_log).max()),
                          rho_model_range=[float(rl[:, 0].min()), float(np.median(rl[:, 0])), float(rl[:, 0].max())],
                          rho_sim_range=[float(rl[:, 1].min()), float(np.median(rl[:, 1])), float(rl[:, 1].max())],
                          n_redraws=n_redraw)
        print(el, json.dumps(clean(sanity[el])), "t=%.1fs" % (time.time() - t0_wall), flush=True)
    truth["sanity"] = sanity
    with open(os.path.join(out, "truth.json"), "w") as f:
        json.dump(clean(truth), f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
