#!/usr/bin/env python3
"""SYNTHETIC lab 9: compensatory roll-attitude tracking on a hexapod motion base.

Generates a synthetic data set that imitates a human-in-the-loop simulator
experiment (10 persons, motion / static condition, 3 runs each), as a roll
tracking study in the style of Zaal et al. (2009) / Pool et al.

Usage:  python lab9_roll_hexapod.py SEED OUTDIR

Only numpy and scipy are used. Every random draw comes from one
numpy.random.default_rng(SEED); the same seed gives byte-identical files.
Nothing is written outside OUTDIR.
"""
import io
import json
import os
import sys
import time

import numpy as np
from scipy import io as sio
from scipy import signal
from scipy.optimize import brentq

SYNTH = "SYNTHETIC data set (lab9_roll_hexapod generator) - not measured on humans"

# ---------------------------------------------------------------- design ----
DT = 0.001                 # simulation step [s] (1 kHz)
FS_LOG = 100.0             # logging rate [Hz]
DEC = int(round(1.0 / (DT * FS_LOG)))
T_M = 81.92                # measurement window [s]
T_IN = 8.08                # run-in [s]
T_TOT = T_IN + T_M         # 90 s per run
N_SIM = int(round(T_TOT / DT))
N_LOG = int(round(T_TOT * FS_LOG))
I0_LOG = int(round(T_IN * FS_LOG))          # first logged sample of window (0-based)
N_WIN = int(round(T_M * FS_LOG))            # 8192
T_FADE = 2.0               # cosine fade-in of the forcing functions [s]
W0 = 2.0 * np.pi / T_M

# forcing lines (integer multiples of W0), interleaved, non-overlapping
K_T = np.array([3, 7, 13, 23, 37, 53, 79, 109, 149, 193])
K_D = np.array([2, 5, 11, 19, 31, 47, 67, 97, 131, 181])
RMS_T = 1.0                # target RMS [deg roll]
RMS_D = 1.6                # disturbance RMS [deg stick]
SHAPE_TAU_Z, SHAPE_TAU_P = 0.1, 0.5   # amplitude shaping (1+0.1s)^2/(1+0.5s)^2
N_PHASE_SETS = 5
N_PHASE_CAND = 200

# controlled element  Hc = Kc / (s (T_r s + 1))   [deg roll / deg stick]
KC = 2.5
T_R = 0.4

# motion system
K_MF = 0.6                 # motion gain
W_W, Z_W = 0.5, 0.7        # 2nd-order high-pass washout
W_P, Z_P = 30.0, 0.7       # platform 2nd-order lag
T_LAT = 0.030              # platform latency [s]

# sensory models (pilot side)
SCC = dict(tau_1=5.9, tau_2=0.005, tau_a=0.11)        # Hosman canal model
OTO = dict(tau_a=10.0, tau_1=5.0, tau_2=0.016)        # Hosman otolith model
G = 9.81

N_PERSONS = 10
RUNS_PER_COND = 3

# literature ranges enforced on every (person, condition, run)
WC_RANGE = (1.5, 4.0)
PM_RANGE = (20.0, 60.0)
GM_MIN_DB = 4.0


# -------------------------------------------------------------- helpers ----
def shape_amp(w):
    s = 1j * w
    return np.abs((1 + SHAPE_TAU_Z * s) ** 2 / (1 + SHAPE_TAU_P * s) ** 2)


def fr_hc(s):
    return KC / (s * (T_R * s + 1))


def fr_nm(s, w, z):
    return w ** 2 / (s ** 2 + 2 * z * w * s + w ** 2)


def fr_scc(s):
    return SCC["tau_1"] * s * (SCC["tau_a"] * s + 1) / (
        (SCC["tau_1"] * s + 1) * (SCC["tau_2"] * s + 1))


def fr_oto(s):
    return (OTO["tau_a"] * s + 1) / ((OTO["tau_1"] * s + 1) * (OTO["tau_2"] * s + 1))


def fr_motion(s, delay_exact=True):
    """roll angle of the aircraft [deg] -> cab roll rate [deg/s]"""
    wash = s ** 2 / (s ** 2 + 2 * Z_W * W_W * s + W_W ** 2)
    plat = W_P ** 2 / (s ** 2 + 2 * Z_P * W_P * s + W_P ** 2)
    return s * K_MF * wash * plat * np.exp(-T_LAT * s)


def fr_channels(s, p):
    """pilot responses (without Hnm) to e (visual) and to cab roll rate"""
    hpe = p["Kv"] * (p["T_L"] * s + 1) * np.exp(-p["tau_v"] * s)
    c = G * np.pi / 180.0
    hpm = (p["Km"] * fr_scc(s) + p["K_oto"] * c * fr_oto(s) / s) * np.exp(-p["tau_m"] * s)
    return hpe, hpm


def open_loops(w, p, motion):
    s = 1j * w
    hpe, hpm = fr_channels(s, p)
    hnm = fr_nm(s, p["w_nm"], p["z_nm"])
    hc = fr_hc(s)
    m = fr_motion(s) if motion else 0.0 * s
    L = hc * hnm * (hpe + hpm * m)                      # loop broken at the stick
    Lt = hc * hnm * hpe / (1 + hc * hnm * hpm * m)      # target open loop
    return L, Lt, hpe, hnm


_WGRID = np.logspace(-2, 2.6, 12000)


def loop_metrics(fun):
    """crossover, phase margin and gain margin of a loop given as f(w)->complex."""
    Lg = fun(_WGRID)
    mag = np.abs(Lg)
    ph = np.unwrap(np.angle(Lg))
    # low-frequency phase reference: a type-1 loop starts near -90 deg
    ph = ph - 2 * np.pi * np.round((ph[0] + np.pi / 2) / (2 * np.pi))
    lm = np.log(mag)
    idx = np.where(np.sign(lm[:-1]) != np.sign(lm[1:]))[0]
    out = dict(n_cross=int(len(idx)))
    if len(idx) == 0:
        out.update(wc=np.nan, pm=np.nan, gm_db=np.nan, ok_shape=False)
        return out
    i = idx[-1]
    wc = brentq(lambda x: np.log(np.abs(fun(np.array([x]))[0])), _WGRID[i], _WGRID[i + 1],
                xtol=1e-10)
    a = np.angle(fun(np.array([wc]))[0])
    ref = ph[i]
    a = a + 2 * np.pi * np.round((ref - a) / (2 * np.pi))
    pm = 180.0 + np.degrees(a)
    # gain margin: |L| at every -180 (mod 360) phase crossing
    k180 = np.floor((ph + np.pi) / (2 * np.pi))
    jdx = np.where(k180[:-1] != k180[1:])[0]
    gms = [-20 * np.log10(mag[j]) for j in jdx]
    gm = min(gms) if gms else np.inf
    below = ph[: i + 1] <= -np.pi          # phase below -180 while |L| > 1 ?
    out.update(wc=float(wc), pm=float(pm), gm_db=float(gm),
               ok_shape=bool(len(idx) == 1 and not below.any()))
    return out


def disc_section(num, den, dt, method):
    """one continuous section (order <= 2) -> discrete biquad row [b0 b1 b2 1 a1 a2]"""
    A, B, C, D = signal.tf2ss(num, den)
    Ad, Bd, Cd, Dd, _ = signal.cont2discrete((A, B, C, D), dt, method=method)
    b, a = signal.ss2tf(Ad, Bd, Cd, Dd)
    b = np.ravel(b) / a[0]
    a = np.ravel(a) / a[0]
    b = np.concatenate([b, np.zeros(3 - len(b))])
    a = np.concatenate([a, np.zeros(3 - len(a))])
    return np.concatenate([b, a])


class Chain:
    """cascade of continuous sections, each discretized exactly for a
    piecewise-linear input (first-order hold), run block by block."""

    def __init__(self, sections, dt=DT, method="foh"):
        self.sos = np.array([disc_section(n, d, dt, method) for n, d in sections])
        self.zi = np.zeros((len(sections), 2))

    def run(self, x):
        y, self.zi = signal.sosfilt(self.sos, x, zi=self.zi)
        return y


def delayed(arr, idx, n):
    src = idx - n
    out = np.zeros(len(idx))
    ok = src >= 0
    out[ok] = arr[src[ok]]
    return out


# ----------------------------------------------------------- simulation ----
def simulate(p, motion, ft, fd, noise, drift):
    """Fine-step (1 kHz) block-wise closed-loop simulation.

    u = Hnm[ Kv d(t) (T_L s+1) e^{-tau_v s} e
             - Km d(t) Hscc e^{-tau_m s} p_cab
             - K_oto Hoto e^{-tau_m s} g sin(phi_cab) ] + n
    phi = Hc (u + fd),  e = ft - phi
    phi_cab = delay_lat{ platform{ K_mf washout{ phi } } },  p_cab = d/dt phi_cab
    """
    nv = int(round(p["tau_v"] / DT))
    nm = int(round(p["tau_m"] / DT))
    nl = int(round(T_LAT / DT))
    nm_sec = [([p["w_nm"] ** 2], [1, 2 * p["z_nm"] * p["w_nm"], p["w_nm"] ** 2])]
    vis = Chain([([p["T_L"] * p["w_nm"] ** 2, p["w_nm"] ** 2],
                  [1, 2 * p["z_nm"] * p["w_nm"], p["w_nm"] ** 2])])
    use_m = motion and p["Km"] > 0
    use_o = motion and p["K_oto"] > 0
    if use_m:
        canal = Chain([([SCC["tau_1"], 0], [SCC["tau_1"], 1]),
                       ([SCC["tau_a"], 1], [SCC["tau_2"], 1])] + nm_sec)
    if use_o:
        oto = Chain([([OTO["tau_a"], 1], [OTO["tau_1"], 1]),
                     ([1], [OTO["tau_2"], 1])] + nm_sec)
    plant = Chain([([KC], [T_R, 1, 0])])
    if motion:
        wash = Chain([([K_MF, 0, 0], [1, 2 * Z_W * W_W, W_W ** 2])])
        ppos = Chain([([W_P ** 2], [1, 2 * Z_P * W_P, W_P ** 2])])
        prate = Chain([([W_P ** 2, 0], [1, 2 * Z_P * W_P, W_P ** 2])])

    u = np.zeros(N_SIM)
    phi = np.zeros(N_SIM)
    e = np.zeros(N_SIM)
    cab_nd = np.zeros(N_SIM)     # platform roll before the latency
    rate_nd = np.zeros(N_SIM)    # platform roll rate before the latency
    B = nv
    if motion:
        B = min(nv, nm + nl)
    assert B >= 1
    for k0 in range(0, N_SIM, B):
        k1 = min(N_SIM, k0 + B)
        idx = np.arange(k0, k1)
        d = drift[idx]
        ub = vis.run(p["Kv"] * d * delayed(e, idx, nv)) + noise[idx]
        if use_m:
            ub -= canal.run(p["Km"] * d * delayed(rate_nd, idx, nm + nl))
        if use_o:
            fy = G * np.sin(np.radians(delayed(cab_nd, idx, nm + nl)))
            ub -= oto.run(p["K_oto"] * fy)
        u[idx] = ub
        phi[idx] = plant.run(ub + fd[idx])
        e[idx] = ft[idx] - phi[idx]
        if motion:
            cmd = wash.run(phi[idx])
            cab_nd[idx] = ppos.run(cmd)
            rate_nd[idx] = prate.run(cmd)
    allidx = np.arange(N_SIM)
    cab = delayed(cab_nd, allidx, nl) if motion else np.zeros(N_SIM)
    rate = delayed(rate_nd, allidx, nl) if motion else np.zeros(N_SIM)
    return dict(u=u, phi=phi, e=e, phim=cab, pm=rate)


# --------------------------------------------------------------- output ----
def savemat_det(path, mdict):
    """scipy.io.savemat (MATLAB 5) with a fixed header text (byte-identical)."""
    bio = io.BytesIO()
    sio.savemat(bio, mdict, format="5", oned_as="column", do_compression=False)
    raw = bytearray(bio.getvalue())
    txt = ("MATLAB 5.0 MAT-file, SYNTHETIC data, Platform: posix, "
           "Created by: lab9_roll_hexapod generator").encode("ascii")
    raw[0:116] = txt.ljust(116, b" ")
    with open(path, "wb") as f:
        f.write(bytes(raw))


def tolist(x):
    return [float(v) for v in np.ravel(x)]


def rnd(x, n=6):
    return float(np.round(float(x), n))


# ----------------------------------------------------------------- main ----
def main():
    t_start = time.time()
    seed = int(sys.argv[1])
    outdir = sys.argv[2]
    rng = np.random.default_rng(seed)

    # ---- forcing functions
    w_t = K_T * W0
    w_d = K_D * W0
    a_t = shape_amp(w_t)
    a_t *= RMS_T / np.sqrt(np.sum(a_t ** 2) / 2)
    a_d = shape_amp(w_d)
    a_d *= RMS_D / np.sqrt(np.sum(a_d ** 2) / 2)
    tw = np.arange(N_WIN) / FS_LOG

    def best_phases(w, a):
        best, bcf = None, np.inf
        for _ in range(N_PHASE_CAND):
            ph = rng.uniform(0, 2 * np.pi, len(w))
            x = np.sin(np.outer(tw, w) + ph) @ a
            cf = np.max(np.abs(x)) / np.sqrt(np.mean(x ** 2))
            if cf < bcf:
                best, bcf = ph, cf
        return best, bcf

    phase_sets = []
    for _ in range(N_PHASE_SETS):
        pt, cft = best_phases(w_t, a_t)
        pd, cfd = best_phases(w_d, a_d)
        phase_sets.append(dict(target=pt, disturbance=pd, crest_t=cft, crest_d=cfd))

    t_sim = np.arange(N_SIM) * DT
    ramp = np.where(t_sim < T_FADE, 0.5 * (1 - np.cos(np.pi * t_sim / T_FADE)), 1.0)

    def forcing(ps):
        ft = ramp * (np.sin(np.outer(t_sim - T_IN, w_t) + ps["target"]) @ a_t)
        fd = ramp * (np.sin(np.outer(t_sim - T_IN, w_d) + ps["disturbance"]) @ a_d)
        return ft, fd

    # ---- persons
    pids = ["R%02d" % (i + 1) for i in range(N_PERSONS)]
    n_users = int(rng.integers(7, 10))
    users = set(int(i) for i in rng.choice(N_PERSONS, n_users, replace=False))
    oto_users = set(int(i) for i in rng.choice(sorted(users), 2, replace=False))

    wint = np.logspace(-3, np.log10(np.pi / DT), 20000)

    def remnant_calib(p, motion, share, T_n):
        L, Lt, hpe, hnm = open_loops(w_t, p, motion)
        pf = np.sum(0.5 * (a_t * np.abs(hnm * hpe / (1 + L))) ** 2)
        L, _, _, _ = open_loops(w_d, p, motion)
        pf += np.sum(0.5 * (a_d * np.abs(L / (1 + L))) ** 2)
        Li, _, _, _ = open_loops(wint, p, motion)
        hn = 1.0 / (1j * wint * T_n + 1)
        pn1 = DT / np.pi * np.trapezoid(np.abs(hn / (1 + Li)) ** 2, wint)
        return float(np.sqrt(share / (1 - share) * pf / pn1)), float(pf)

    persons = {}
    for i, pid in enumerate(pids):
        um = i in users
        uo = i in oto_users
        motion_first = (i % 2 == 0)
        order = (["motion"] * 3 + ["static"] * 3) if motion_first else \
                (["static"] * 3 + ["motion"] * 3)
        for attempt in range(10000):
            tau_v = round(float(np.clip(rng.normal(0.25, 0.03), 0.18, 0.32)), 3)
            tau_m = round(float(rng.uniform(0.11, 0.17)), 3)
            if tau_m > tau_v - 0.04:
                continue
            T_L = float(rng.uniform(0.30, 0.60))
            w_nm = float(rng.uniform(8.0, 13.0))
            z_nm = float(rng.uniform(0.15, 0.45))
            wc_target = float(rng.uniform(2.0, 3.2))
            s = 1j * wc_target
            Kv = float(1.0 / abs(fr_hc(s) * fr_nm(s, w_nm, z_nm) * (T_L * s + 1)))
            st = dict(Kv=Kv, T_L=T_L, tau_v=tau_v, Km=0.0, tau_m=tau_m, K_oto=0.0,
                      w_nm=w_nm, z_nm=z_nm)
            mo = dict(st)
            mo["tau_v"] = round(tau_v + float(rng.uniform(-0.01, 0.015)), 3)
            mo["w_nm"] = w_nm * float(rng.uniform(0.97, 1.08))
            mo["z_nm"] = z_nm * float(rng.uniform(0.9, 1.1))
            if um:
                mo["Kv"] = Kv * float(rng.uniform(1.03, 1.18))
                mo["T_L"] = T_L * float(rng.uniform(0.5, 0.8))
                mo["Km"] = mo["Kv"] * float(rng.uniform(0.2, 0.45))
                if uo:
                    mo["K_oto"] = float(rng.uniform(0.05, 0.15))
            else:
                mo["Kv"] = Kv * float(rng.uniform(0.97, 1.05))
                mo["T_L"] = T_L * float(rng.uniform(0.95, 1.05))
            if mo["tau_m"] > mo["tau_v"] - 0.04:
                continue
            T_n = float(rng.uniform(0.10, 0.25))
            share_s = float(rng.uniform(0.18, 0.30))
            share_m = share_s * float(rng.uniform(0.75, 0.95) if um else rng.uniform(0.9, 1.1))
            learn_K = float(rng.uniform(0.0, 0.08))
            learn_R = float(rng.uniform(0.0, 0.15))
            drift_a = float(rng.uniform(0.02, 0.05))
            drift_P = float(rng.uniform(30.0, 90.0))
            runs = []
            ok = True
            for k, cond in enumerate(order):
                fk = 1 - np.exp(-k / 1.5)
                base = mo if cond == "motion" else st
                pr = dict(base)
                pr["Kv"] = base["Kv"] * (1 + learn_K * fk)
                pr["Km"] = base["Km"] * (1 + learn_K * fk)
                met = loop_metrics(lambda w, pr=pr, c=cond: open_loops(w, pr, c == "motion")[0])
                if not (met["ok_shape"] and WC_RANGE[0] <= met["wc"] <= WC_RANGE[1]
                        and PM_RANGE[0] <= met["pm"] <= PM_RANGE[1]
                        and met["gm_db"] >= GM_MIN_DB):
                    ok = False
                    break
                runs.append(dict(order=k + 1, condition=cond, params=pr, metrics=met,
                                 remnant_factor=float(1 - learn_R * fk)))
            if not ok:
                continue
            cond_mean = {}
            for cond, base in (("static", st), ("motion", mo)):
                rr = [r for r in runs if r["condition"] == cond]
                pm_ = dict(base)
                pm_["Kv"] = float(np.mean([r["params"]["Kv"] for r in rr]))
                pm_["Km"] = float(np.mean([r["params"]["Km"] for r in rr]))
                met = loop_metrics(lambda w, pr=pm_, c=cond: open_loops(w, pr, c == "motion")[0])
                mt = loop_metrics(lambda w, pr=pm_, c=cond: open_loops(w, pr, c == "motion")[1])
                if not (met["ok_shape"] and WC_RANGE[0] <= met["wc"] <= WC_RANGE[1]
                        and PM_RANGE[0] <= met["pm"] <= PM_RANGE[1]):
                    ok = False
                cond_mean[cond] = dict(params=pm_, metrics=met, metrics_target=mt)
            if not ok:
                continue
            break
        else:
            raise RuntimeError("could not draw person %s" % pid)
        # remnant: condition-level share, modulated by learning (mean over the
        # condition's three runs equals the condition-level share); the noise
        # gain is calibrated per run for that run's pilot parameters
        Kn = {}
        share_c = dict(static=share_s, motion=share_m)
        for cond in ("static", "motion"):
            rr = [r for r in runs if r["condition"] == cond]
            rf_mean = np.mean([r["remnant_factor"] for r in rr])
            for r in rr:
                r["share_target"] = share_c[cond] * r["remnant_factor"] / rf_mean
                r["Kn"], _ = remnant_calib(r["params"], cond == "motion",
                                           r["share_target"], T_n)
            Kn[cond] = float(np.mean([r["Kn"] for r in rr]))
        persons[pid] = dict(uses_motion=um, uses_otolith=uo, order=order, st=st, mo=mo,
                            T_n=T_n, share=dict(static=share_s, motion=share_m), Kn=Kn,
                            learn_K=learn_K, learn_R=learn_R, drift_a=drift_a,
                            drift_P=drift_P, runs=runs, cond_mean=cond_mean,
                            attempts=attempt + 1)

    # ---- runs
    for cond in ("motion", "static"):
        os.makedirs(os.path.join(outdir, "data", "ROLL", cond), exist_ok=True)
    stats = []
    for pid in pids:
        P = persons[pid]
        a_zn = np.exp(-DT / P["T_n"])
        cnt = {"motion": 0, "static": 0}
        for r in P["runs"]:
            cond = r["condition"]
            motion = cond == "motion"
            cnt[cond] += 1
            r["run"] = cnt[cond]
            r["phase_set"] = int(rng.integers(0, N_PHASE_SETS))
            r["drift_phase"] = float(rng.uniform(0, 2 * np.pi))
            wn = rng.standard_normal(N_SIM)
            noise = r["Kn"] * signal.lfilter([0.0, 1 - a_zn], [1.0, -a_zn], wn)
            drift = 1 + P["drift_a"] * np.sin(2 * np.pi * t_sim / P["drift_P"] + r["drift_phase"])
            ft, fd = forcing(phase_sets[r["phase_set"]])
            sim = simulate(r["params"], motion, ft, fd, noise, drift)
            sim0 = simulate(r["params"], motion, ft, fd, np.zeros(N_SIM), drift)
            win = slice(I0_LOG * DEC, N_SIM)
            uu = sim["u"][win]
            un = (sim["u"] - sim0["u"])[win]
            r["share_realized"] = float(np.var(un) / np.var(uu))
            # spectral share on the logged window (non-forcing bins / all bins)
            ul = sim["u"][::DEC][I0_LOG:]
            U = np.fft.rfft(ul - ul.mean())
            pw = np.abs(U[1:]) ** 2
            fb = np.concatenate([K_T, K_D]) - 1
            r["share_spectral"] = float(1 - pw[fb].sum() / pw.sum())
            stats.append(dict(pid=pid, cond=cond, u=np.std(uu), e=np.std(sim["e"][win]),
                              phi=np.std(sim["phi"][win]),
                              phim=np.max(np.abs(sim["phim"])),
                              pm=np.max(np.abs(sim["pm"]))))
            lg = slice(0, N_SIM, DEC)
            t = np.arange(N_LOG) / FS_LOG
            info = ("SYNTHETIC data. Roll-attitude compensatory tracking, hexapod motion base. "
                    "Subject %s, condition %s, run %d (session position %d of 6). "
                    "t [s]; ft target roll [deg]; fd disturbance at stick/plant input "
                    "[deg stick]; e displayed error ft-phi [deg]; u stick [deg]; "
                    "phi aircraft roll [deg]; phim cab roll [deg]; pm cab roll rate [deg/s]. "
                    "100 Hz; run-in Tin s, then measurement window Tm s (samples 809..9000, "
                    "MATLAB indexing)." % (pid, cond, r["run"], r["order"]))
            md = {
                "SYNTHETIC": SYNTH,
                "info": info,
                "subject": pid,
                "condition": cond,
                "run": float(r["run"]),
                "order": float(r["order"]),
                "phaseset": float(r["phase_set"] + 1),
                "fs": FS_LOG,
                "Tin": T_IN,
                "Tm": T_M,
                "t": t,
                "ft": ft[lg],
                "fd": fd[lg],
                "e": sim["e"][lg],
                "u": sim["u"][lg],
                "phi": sim["phi"][lg],
                "phim": sim["phim"][lg],
                "pm": sim["pm"][lg],
            }
            fn = os.path.join(outdir, "data", "ROLL", cond,
                              "%s_%s_run%d.mat" % (pid, cond, r["run"]))
            savemat_det(fn, md)

    # ---- plants file
    hp = T_LAT / 2
    num = np.polymul([K_MF * W_P ** 2, 0, 0, 0], [-hp, 1])
    den = np.polymul(np.polymul([1, 2 * Z_W * W_W, W_W ** 2], [1, 2 * Z_P * W_P, W_P ** 2]),
                     [hp, 1])
    plants = {
        "SYNTHETIC": SYNTH,
        "element": "ROLL",
        "control_to_output": {"num": [KC], "den": [T_R, 1.0, 0.0]},
        "disturbance_to_output": {"num": [KC], "den": [T_R, 1.0, 0.0]},
        "motion_path": {"num": tolist(num), "den": tolist(den)},
        "units": {"control": "deg stick", "output": "deg roll",
                  "disturbance": "deg stick (added to the stick at the plant input)",
                  "motion_path_output": "deg/s cab roll rate"},
        "motion_path_description": ("aircraft roll angle [deg] -> cab roll rate [deg/s]: "
                                    "s * K_mf * s^2/(s^2+2 zeta_w w_w s+w_w^2) * "
                                    "w_p^2/(s^2+2 zeta_p w_p s+w_p^2) * Pade1(latency)"),
        "motion_parameters": {"K_mf": K_MF, "omega_w": W_W, "zeta_w": Z_W,
                              "omega_p": W_P, "zeta_p": Z_P, "latency_s": T_LAT},
        "motion_conditions": ["motion"],
        "note": "In the static condition the cab does not move (motion path inactive).",
    }
    with open(os.path.join(outdir, "plants_ROLL.json"), "w") as f:
        json.dump(plants, f, indent=2)

    # ---- truth
    def pdict(p):
        return {"Kv": rnd(p["Kv"]), "T_L": rnd(p["T_L"]), "tau_v": rnd(p["tau_v"], 3),
                "Km": rnd(p["Km"]), "tau_m": rnd(p["tau_m"], 3), "K_oto": rnd(p["K_oto"]),
                "omega_nm": rnd(p["w_nm"]), "zeta_nm": rnd(p["z_nm"])}

    tpersons = {}
    for pid in pids:
        P = persons[pid]
        entry = {"element": "ROLL", "uses_motion": P["uses_motion"],
                 "uses_otolith": P["uses_otolith"],
                 "session_order": P["order"],
                 "remnant_filter": {"form": "K_n/(T_n s + 1) driven by unit-variance white "
                                            "noise at 1 kHz (ZOH), added to the stick",
                                    "T_n": rnd(P["T_n"])},
                 "learning": {"gain_increase_max": rnd(P["learn_K"]),
                              "remnant_decrease_max": rnd(P["learn_R"]),
                              "form": "factor 1+gmax(1-exp(-k/1.5)) on Kv,Km and "
                                      "1-rmax(1-exp(-k/1.5)) on the remnant share "
                                      "(normalized to the condition mean), "
                                      "k=session position-1"},
                 "gain_drift": {"amplitude": rnd(P["drift_a"]), "period_s": rnd(P["drift_P"]),
                                "form": "Kv,Km multiplied by 1+a sin(2 pi t/P + phase_run)"},
                 "draw_attempts": P["attempts"]}
        for cond in ("static", "motion"):
            cm = P["cond_mean"][cond]
            rr = [r for r in P["runs"] if r["condition"] == cond]
            d = pdict(cm["params"])
            d["Km_over_Kv"] = rnd(cm["params"]["Km"] / cm["params"]["Kv"])
            d["remnant_share_target"] = rnd(P["share"][cond])
            d["remnant_share"] = rnd(np.mean([r["share_realized"] for r in rr]))
            d["remnant_share_spectral"] = rnd(np.mean([r["share_spectral"] for r in rr]))
            d["K_n"] = rnd(np.mean([r["Kn"] for r in rr]))
            d["T_n"] = rnd(P["T_n"])
            d["crossover_rad_s"] = rnd(cm["metrics"]["wc"], 4)
            d["phase_margin_deg"] = rnd(cm["metrics"]["pm"], 3)
            d["gain_margin_dB"] = rnd(cm["metrics"]["gm_db"], 3)
            d["target_crossover_rad_s"] = rnd(cm["metrics_target"]["wc"], 4)
            d["target_phase_margin_deg"] = rnd(cm["metrics_target"]["pm"], 3)
            d["runs"] = []
            for r in rr:
                d["runs"].append({"run": r["run"], "session_position": r["order"],
                                  "file": "data/ROLL/%s/%s_%s_run%d.mat" % (cond, pid, cond,
                                                                            r["run"]),
                                  "phase_set": r["phase_set"] + 1,
                                  "Kv": rnd(r["params"]["Kv"]), "Km": rnd(r["params"]["Km"]),
                                  "K_n": rnd(r["Kn"]),
                                  "remnant_share_target": rnd(r["share_target"]),
                                  "drift_phase": rnd(r["drift_phase"]),
                                  "remnant_share": rnd(r["share_realized"]),
                                  "remnant_share_spectral": rnd(r["share_spectral"]),
                                  "crossover_rad_s": rnd(r["metrics"]["wc"], 4),
                                  "phase_margin_deg": rnd(r["metrics"]["pm"], 3),
                                  "gain_margin_dB": rnd(r["metrics"]["gm_db"], 3)})
            entry[cond] = d
        tpersons[pid] = entry

    design = {
        "SYNTHETIC": True,
        "sim_step_s": DT, "log_rate_hz": FS_LOG, "T_m_s": T_M, "run_in_s": T_IN,
        "fade_in_s": T_FADE, "base_frequency_rad_s": W0,
        "target_k": K_T.tolist(), "disturbance_k": K_D.tolist(),
        "target_omega_rad_s": tolist(w_t), "disturbance_omega_rad_s": tolist(w_d),
        "target_amplitude_deg": tolist(a_t), "disturbance_amplitude_deg_stick": tolist(a_d),
        "target_rms_deg": RMS_T, "disturbance_rms_deg_stick": RMS_D,
        "amplitude_shaping": "|(1+0.1 jw)^2/(1+0.5 jw)^2|",
        "forcing_form": "f(t) = fade(t) * sum A_k sin(w_k (t - run_in) + phase_k)",
        "phase_sets": [{"target": tolist(ps["target"]), "disturbance": tolist(ps["disturbance"]),
                        "crest_target": rnd(ps["crest_t"], 4),
                        "crest_disturbance": rnd(ps["crest_d"], 4)} for ps in phase_sets],
        "Hc": {"Kc": KC, "T_r": T_R, "form": "Kc/(s (T_r s + 1))"},
        "motion": {"K_mf": K_MF, "omega_w": W_W, "zeta_w": Z_W, "omega_p": W_P,
                   "zeta_p": Z_P, "latency_s": T_LAT},
        "pilot_model": ("u = Hnm(s) [ Kv (T_L s+1) e^{-tau_v s} e - Km Hscc(s) e^{-tau_m s} "
                        "p_cab - K_oto Hoto(s) e^{-tau_m s} g sin(phi_cab) ] + n ; "
                        "Hnm = omega_nm^2/(s^2+2 zeta_nm omega_nm s+omega_nm^2); "
                        "p_cab = cab roll rate [deg/s], phi_cab cab roll [deg], g=9.81 m/s^2; "
                        "Kv, Km multiplied by the slow drift factor d(t)"),
        "Hscc": {"form": "tau_1 s (tau_a s+1)/((tau_1 s+1)(tau_2 s+1))", **SCC},
        "Hoto": {"form": "(tau_a s+1)/((tau_1 s+1)(tau_2 s+1)), input m/s^2", **OTO},
        "open_loop_definition": ("crossover / phase margin of the loop broken at the stick: "
                                 "L = Hc Hnm (Hpe + Hpm_eff M), M = motion path (exact delay), "
                                 "Hpm_eff includes the linearized otolith; static: M = 0. "
                                 "target_* : Hc Hnm Hpe/(1+Hc Hnm Hpm_eff M)"),
        "condition_values": "per-condition Kv, Km = mean of the three runs' values",
        "discretization": "first-order-hold exact per section, 1 kHz, block-wise, "
                          "integer-sample delays",
        "users_of_motion": [pids[i] for i in sorted(users)],
        "otolith_users": [pids[i] for i in sorted(oto_users)],
        "run_order": "blocked and counterbalanced: odd persons MMMSSS, even persons SSSMMM",
        "mat_variables": ["SYNTHETIC", "info", "subject", "condition", "run", "order",
                          "phaseset", "fs", "Tin", "Tm", "t", "ft", "fd", "e", "u", "phi",
                          "phim", "pm"],
    }
    truth = {"SYNTHETIC": SYNTH, "seed": seed, "persons": tpersons, "design": design}
    with open(os.path.join(outdir, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1)

    # ---- README
    lines = [
        "SYNTHETIC DATA SET - generated by a simulation, not measured on humans.",
        "",
        "Roll-attitude compensatory tracking experiment, hexapod motion simulator",
        "=========================================================================",
        "",
        "Task: compensatory roll tracking. The display shows only the error",
        "e = ft - phi (deg). The pilot controls the aircraft roll with a side stick.",
        "Controlled element: phi = Hc(s) (u + fd),  Hc(s) = %.3g / (s (%.3g s + 1))" % (KC, T_R),
        "(u stick deflection in deg, phi roll angle in deg). The disturbance fd is",
        "added to the stick signal at the plant input.",
        "",
        "Conditions",
        "  motion : the cab rolls with the simulated aircraft through the motion filter",
        "           K_mf = %.2f, washout s^2/(s^2 + 2*%.2f*%.2f s + %.2f^2)," % (K_MF, Z_W, W_W, W_W),
        "           platform response %.0f^2/(s^2 + 2*%.2f*%.0f s + %.0f^2), latency %.0f ms."
        % (W_P, Z_P, W_P, W_P, T_LAT * 1000),
        "  static : the cab does not move (phim = pm = 0).",
        "  See plants_ROLL.json (motion_path = roll angle [deg] -> cab roll rate [deg/s],",
        "  latency as a first-order Pade approximant).",
        "",
        "Persons R01..R10, 3 runs per condition. Blocked, counterbalanced order:",
        "  R01,R03,R05,R07,R09: motion x3 then static x3;",
        "  R02,R04,R06,R08,R10: static x3 then motion x3.",
        "  The variable 'order' in each file gives the position in the session (1..6).",
        "",
        "Files",
        "  data/ROLL/motion/Rxx_motion_runN.mat, data/ROLL/static/Rxx_static_runN.mat",
        "  MATLAB 5 files, column vectors, %d samples each, sampled at %.0f Hz:" % (N_LOG, FS_LOG),
        "    t     time [s], 0 ... %.2f" % ((N_LOG - 1) / FS_LOG),
        "    ft    target forcing function (desired roll) [deg]",
        "    fd    disturbance forcing function, added to the stick [deg stick]",
        "    e     displayed tracking error ft - phi [deg]",
        "    u     stick deflection (pilot output) [deg]",
        "    phi   aircraft roll angle [deg]",
        "    phim  cab (motion platform) roll angle [deg] (zero in static)",
        "    pm    cab roll rate [deg/s] (zero in static)",
        "    fs (100), Tin (run-in, s), Tm (window, s), subject, condition, run, order,",
        "    phaseset (forcing phase set 1..%d), info (text), SYNTHETIC (text label)." % N_PHASE_SETS,
        "  Each run lasts %.2f s: run-in of %.2f s followed by the measurement window" % (T_TOT, T_IN),
        "  of %.2f s = %d samples (t >= %.2f s, samples %d..%d in MATLAB indexing)."
        % (T_M, N_WIN, T_IN, I0_LOG + 1, N_LOG),
        "  The forcing functions fade in over the first %.0f s of the run-in." % T_FADE,
        "",
        "Forcing functions (sums of sines, periodic in the measurement window)",
        "  f(t) = sum_k A_k sin(w_k (t - Tin) + phase_k),  w_k = n_k * 2 pi / %.2f s" % T_M,
        "  Phases: %d phase sets (chosen for low crest factor); the set used is in 'phaseset'."
        % N_PHASE_SETS,
        "  Target ft (RMS %.2f deg):" % RMS_T,
    ]
    for k, w, a in zip(K_T, w_t, a_t):
        lines.append("    n = %3d  w = %7.4f rad/s  A = %.4f deg" % (k, w, a))
    lines.append("  Disturbance fd (RMS %.2f deg stick):" % RMS_D)
    for k, w, a in zip(K_D, w_d, a_d):
        lines.append("    n = %3d  w = %7.4f rad/s  A = %.4f deg" % (k, w, a))
    lines += [
        "  Amplitudes follow |(1 + 0.1 jw)^2 / (1 + 0.5 jw)^2| (scaled to the RMS above).",
        "",
        "Units: all angles in degrees, rates in deg/s, time in seconds.",
        "Sign convention: positive stick gives positive roll rate; e = ft - phi.",
        "",
        "SYNTHETIC: generated by lab9_roll_hexapod.py (seed %d)." % seed,
    ]
    with open(os.path.join(outdir, "README.txt"), "w") as f:
        f.write("\n".join(lines) + "\n")

    # ---- console summary (not written to disk)
    el = time.time() - t_start
    print("users of motion:", [pids[i] for i in sorted(users)],
          " otolith:", [pids[i] for i in sorted(oto_users)])
    for pid in pids:
        tp = tpersons[pid]
        s_, m_ = tp["static"], tp["motion"]
        print("%s use=%d oto=%d | S Kv=%.3f TL=%.3f tv=%.3f wc=%.2f pm=%.1f gm=%.1f rem=%.2f/%.2f"
              " | M Kv=%.3f TL=%.3f Km/Kv=%.3f tm=%.3f wc=%.2f pm=%.1f gm=%.1f rem=%.2f/%.2f"
              " | wnm=%.1f znm=%.2f att=%d"
              % (pid, tp["uses_motion"], tp["uses_otolith"], s_["Kv"], s_["T_L"], s_["tau_v"],
                 s_["crossover_rad_s"], s_["phase_margin_deg"], s_["gain_margin_dB"],
                 s_["remnant_share"], s_["remnant_share_spectral"],
                 m_["Kv"], m_["T_L"], m_["Km_over_Kv"], m_["tau_m"], m_["crossover_rad_s"],
                 m_["phase_margin_deg"], m_["gain_margin_dB"], m_["remnant_share"],
                 m_["remnant_share_spectral"], s_["omega_nm"], s_["zeta_nm"],
                 tp["draw_attempts"]))
    for cond in ("static", "motion"):
        ss = [x for x in stats if x["cond"] == cond]
        print(cond, "RMS u %.2f-%.2f  e %.2f-%.2f  phi %.2f-%.2f  max|phim| %.2f  max|pm| %.2f"
              % (min(x["u"] for x in ss), max(x["u"] for x in ss),
                 min(x["e"] for x in ss), max(x["e"] for x in ss),
                 min(x["phi"] for x in ss), max(x["phi"] for x in ss),
                 max(x["phim"] for x in ss), max(x["pm"] for x in ss)))
    print("crest factors:", [(round(p["crest_t"], 2), round(p["crest_d"], 2)) for p in phase_sets])
    print("amp ratio target %.1f, disturbance %.1f" % (a_t[0] / a_t[-1], a_d[0] / a_d[-1]))
    allr = [r for pid in pids for r in persons[pid]["runs"]]
    for cond in ("static", "motion"):
        rr = [r for r in allr if r["condition"] == cond]
        print(cond, "per-run remnant share %.3f-%.3f (spectral %.3f-%.3f), "
              "wc %.2f-%.2f rad/s, PM %.1f-%.1f deg, GM %.1f-%.1f dB"
              % (min(r["share_realized"] for r in rr), max(r["share_realized"] for r in rr),
                 min(r["share_spectral"] for r in rr), max(r["share_spectral"] for r in rr),
                 min(r["metrics"]["wc"] for r in rr), max(r["metrics"]["wc"] for r in rr),
                 min(r["metrics"]["pm"] for r in rr), max(r["metrics"]["pm"] for r in rr),
                 min(r["metrics"]["gm_db"] for r in rr), max(r["metrics"]["gm_db"] for r in rr)))
    print("run time %.1f s" % el)


if __name__ == "__main__":
    main()
