#!/usr/bin/env python
"""SYNTHETIC data generator - lab 10: multimodal yaw tracking with and without cab motion.

Imitates a SIMONA-style (hexapod research simulator) experiment: compensatory yaw
tracking with a target and a disturbance on interleaved multisines, disturbance added
to the stick, single (Kc/s) and double (Kc/s^2) integrator controlled elements, the
cab yaws with the controlled yaw angle through a high-pass motion filter, platform
dynamics and a transport latency.

Usage:  python lab10_yaw_cab.py SEED OUTDIR

Everything written goes into OUTDIR. Same seed -> byte-identical files.
Pilot model (per person, per condition, per run):
    u = Hnms * [ g(t) Kv (TL s + 1) e(t - tau_v)  -  g(t) Km Hscc r_cab(t - tau_m) ] + n + u_off
    Hscc(s) = 5.9 s (0.11 s + 1) / (5.9 s + 1)   (unity mid-band gain, input cab yaw rate)
    Hnms(s) = wn^2 / (s^2 + 2 zn wn s + wn^2)
    n = Kn * wr/(s + wr) * Hnms * white noise  (coloured remnant)
"""
import argparse
import json
import os
import time

import numpy as np
from scipy import signal

# --------------------------------------------------------------------------------------
# fixed lab design
# --------------------------------------------------------------------------------------
FS_SIM = 1000.0
DT = 1.0 / FS_SIM
FS_LOG = 100.0
DEC = int(FS_SIM / FS_LOG)
T_RUNIN = 8.08
T_MEAS = 81.92
T_TOTAL = T_RUNIN + T_MEAS            # 90.00 s
N = int(round(T_TOTAL * FS_SIM))       # 90000
N0 = int(round(T_RUNIN * FS_SIM))      # 8080
NLOG = N // DEC                        # 9000
NLOG0 = N0 // DEC                      # 808
T_FADE = 3.0
BLOCK = 100                            # samples per simulation block (0.1 s)

W0 = 2.0 * np.pi / T_MEAS
K_TARGET = [3, 7, 13, 23, 37, 53, 79, 109, 149, 211]
K_DIST = [5, 11, 17, 29, 43, 61, 89, 127, 173, 233]
SIGMA_FT = 1.5      # deg, target std
SIGMA_FD_PSI = 1.2  # deg, open-loop yaw-equivalent std of disturbance

ELEMENTS = {
    "SI": {"Kc": 1.5, "order": 1, "ids": ["Y0%d" % i for i in range(1, 9)],
           "units": "(deg/s)/deg"},
    "DI": {"Kc": 4.0, "order": 2, "ids": ["Y1%d" % i for i in range(1, 9)],
           "units": "(deg/s^2)/deg"},
}

# motion system: 2nd-order high-pass yaw motion filter, platform 2nd-order, latency
MF_K, MF_W, MF_Z = 0.8, 0.4, 0.7
PL_W, PL_Z = 40.0, 0.7
PL_DELAY = 0.030
DP = int(round(PL_DELAY * FS_SIM))

# semicircular canals (Hosman / Zaal time constants, unity mid-band gain on rate)
SCC_TA, SCC_TL = 5.9, 0.11
SCC_NUM = [SCC_TA * SCC_TL, SCC_TA, 0.0]
SCC_DEN = [SCC_TA, 1.0]

W_GRID = np.logspace(-1, np.log10(40.0), 6000)
W_REM = np.logspace(-3, np.log10(np.pi * FS_SIM), 30000)

PM_LIM = (22.0, 58.0)
WC_LIM = (1.1, 4.8)


def pade2(T):
    return [T * T / 12.0, -T / 2.0, 1.0], [T * T / 12.0, T / 2.0, 1.0]


def motion_tf():
    """yaw angle psi [deg] -> cab yaw rate [deg/s] (without latency), and -> cab angle."""
    den = np.polymul([1.0, 2 * MF_Z * MF_W, MF_W ** 2], [1.0, 2 * PL_Z * PL_W, PL_W ** 2])
    num_rate = [MF_K * PL_W ** 2, 0.0, 0.0, 0.0]
    num_ang = [MF_K * PL_W ** 2, 0.0, 0.0]
    return num_rate, num_ang, list(den)


MP_NUM_RATE, MP_NUM_ANG, MP_DEN = motion_tf()


def tfval(num, den, s):
    return np.polyval(num, s) / np.polyval(den, s)


def hmp_exact(s):
    return tfval(MP_NUM_RATE, MP_DEN, s) * np.exp(-s * PL_DELAY)


def hscc(s):
    return tfval(SCC_NUM, SCC_DEN, s)


def hc(elem, s):
    e = ELEMENTS[elem]
    return e["Kc"] / s ** e["order"]


def pilot_fr(p, s):
    Hn = p["wn"] ** 2 / (s ** 2 + 2 * p["zn"] * p["wn"] * s + p["wn"] ** 2)
    Hpv = p["Kv"] * (p["TL"] * s + 1.0) * np.exp(-s * p["tv"]) * Hn
    if p["Km"] > 0:
        Hpm = p["Km"] * hscc(s) * np.exp(-s * p["tm"]) * Hn
    else:
        Hpm = np.zeros_like(s)
    return Hpv, Hpm, Hn


def _margins(H, w):
    lm = np.log(np.abs(H))
    ph = np.unwrap(np.angle(H))
    if ph[0] > np.pi / 2:
        ph -= 2 * np.pi
    sc = np.nonzero(np.sign(lm[:-1]) != np.sign(lm[1:]))[0]
    if len(sc) != 1:
        return None
    i = sc[0]
    f = lm[i] / (lm[i] - lm[i + 1])
    lw = np.log(w[i]) + f * (np.log(w[i + 1]) - np.log(w[i]))
    wc = float(np.exp(lw))
    phc = ph[i] + f * (ph[i + 1] - ph[i])
    pm = float(np.degrees(phc) + 180.0)
    # gain margin above crossover
    gm_ok = True
    x = ph + np.pi
    pc = np.nonzero((np.sign(x[:-1]) != np.sign(x[1:])) & (w[:-1] > wc))[0]
    gms = []
    for j in pc:
        gms.append(float(1.0 / np.abs(H[j])))
        if np.abs(H[j]) > 0.8:
            gm_ok = False
    return {"wc": wc, "pm": pm, "gm": (min(gms) if gms else None), "gm_ok": gm_ok}


def loop_metrics(elem, p, motion):
    s = 1j * W_GRID
    Hc = hc(elem, s)
    Hpv, Hpm, _ = pilot_fr(p, s)
    Hmp = hmp_exact(s) if motion else np.zeros_like(s)
    Hol = Hc * (Hpv + Hpm * Hmp)
    Holt = Hpv * Hc / (1.0 + Hpm * Hmp * Hc)
    return _margins(Hol, W_GRID), _margins(Holt, W_GRID)


def metrics_ok(m):
    d, t = m
    for x in (d, t):
        if x is None or not x["gm_ok"]:
            return False
        if not (WC_LIM[0] <= x["wc"] <= WC_LIM[1] and PM_LIM[0] <= x["pm"] <= PM_LIM[1]):
            return False
    return True


# --------------------------------------------------------------------------------------
# forcing functions
# --------------------------------------------------------------------------------------
def shaping(w):
    jw = 1j * np.asarray(w)
    return np.abs((1 + 0.1 * jw) ** 2 / (1 + 0.8 * jw) ** 2)


def best_phases(rng, amps, w, ntry=300):
    t = np.arange(int(T_MEAS * FS_LOG)) / FS_LOG
    S = np.sin(np.outer(w, t))
    C = np.cos(np.outer(w, t))
    best, bcf = None, np.inf
    for _ in range(ntry):
        ph = rng.uniform(0, 2 * np.pi, len(w))
        x = (amps * np.cos(ph)) @ S + (amps * np.sin(ph)) @ C
        cf = np.max(np.abs(x)) / np.sqrt(np.mean(x ** 2))
        if cf < bcf:
            best, bcf = ph, cf
    return best, float(bcf)


def build_forcing(rng):
    wt = W0 * np.array(K_TARGET, float)
    wd = W0 * np.array(K_DIST, float)
    at = shaping(wt)
    at *= SIGMA_FT / np.sqrt(np.sum(at ** 2) / 2)
    ad_psi = shaping(wd)
    ad_psi *= SIGMA_FD_PSI / np.sqrt(np.sum(ad_psi ** 2) / 2)
    pt, cft = best_phases(rng, at, wt)
    pd, cfd = best_phases(rng, ad_psi, wd)
    t = np.arange(N) * DT
    tt = t - T_RUNIN
    fade = np.ones(N)
    m = t < T_FADE
    fade[m] = 0.5 * (1 - np.cos(np.pi * t[m] / T_FADE))
    ft = fade * (at[None, :] * np.sin(np.outer(tt, wt) + pt[None, :])).sum(axis=1)
    base_d = np.sin(np.outer(tt, wd) + pd[None, :])
    F = {"wt": wt, "wd": wd, "at": at, "pt": pt, "pd": pd, "ad_psi": ad_psi,
         "crest_t": cft, "crest_d": cfd, "ft": ft, "fd": {}, "ad": {}}
    for elem, e in ELEMENTS.items():
        ad = ad_psi * wd ** e["order"] / e["Kc"]
        F["ad"][elem] = ad
        F["fd"][elem] = fade * (ad[None, :] * base_d).sum(axis=1)
    return F


# --------------------------------------------------------------------------------------
# pilots
# --------------------------------------------------------------------------------------
def remnant_gain(elem, p, motion, share, F):
    """Kn such that remnant is `share` of control variance (linear, frequency domain)."""
    def parts(w):
        s = 1j * w
        Hc = hc(elem, s)
        Hpv, Hpm, Hn = pilot_fr(p, s)
        Hmp = hmp_exact(s) if motion else np.zeros_like(s)
        Hol = Hc * (Hpv + Hpm * Hmp)
        return Hpv, Hol, Hn
    Hpv, Hol, _ = parts(F["wt"])
    vf = np.sum(F["at"] ** 2 / 2 * np.abs(Hpv / (1 + Hol)) ** 2)
    _, Hol, _ = parts(F["wd"])
    vf += np.sum(F["ad"][elem] ** 2 / 2 * np.abs(Hol / (1 + Hol)) ** 2)
    w = W_REM
    _, Hol, Hn = parts(w)
    Fn = p["wr"] / (1j * w + p["wr"]) * Hn
    integ = np.abs(Fn / (1 + Hol)) ** 2
    I = DT / np.pi * np.sum(0.5 * (integ[1:] + integ[:-1]) * np.diff(w))
    return float(np.sqrt(share / (1 - share) * vf / I))


def run_params(base, j, lam):
    """parameters of session run j (0..5) including learning."""
    x = (j - 2.5) / 2.5
    p = dict(base)
    p["Kv"] = base["Kv"] * (1 + lam["K"] * x)
    p["Km"] = base["Km"] * (1 + lam["K"] * x)
    p["tv"] = round((base["tv"] - lam["tau"] * x) * 1000) / 1000.0
    if base["Km"] > 0:
        p["tm"] = round((base["tm"] - 0.5 * lam["tau"] * x) * 1000) / 1000.0
    p["remfac"] = 1 - 1.5 * lam["K"] * x
    return p


def draw_person(rng, elem, use, order, F):
    Kc = ELEMENTS[elem]["Kc"]
    for attempt in range(1000):
        wn = rng.uniform(9.0, 14.0)
        zn = rng.uniform(0.15, 0.40)
        if elem == "SI":
            tv = float(np.clip(rng.normal(0.205, 0.025), 0.16, 0.28))
            TL = 0.0
            wct = rng.uniform(2.8, 4.0)
        else:
            tv = float(np.clip(rng.normal(0.25, 0.03), 0.18, 0.32))
            TL = rng.uniform(0.7, 1.4)
            wct = rng.uniform(1.5, 2.5)
        s = 1j * wct
        Hn = wn ** 2 / (s ** 2 + 2 * zn * wn * s + wn ** 2)
        Kv = wct ** ELEMENTS[elem]["order"] / abs(Kc * (1 + TL * s) * Hn)
        wr = rng.uniform(4.0, 10.0)
        share_s = rng.uniform(0.15, 0.32)
        static = {"Kv": Kv, "TL": TL, "tv": round(tv * 1000) / 1000.0, "Km": 0.0,
                  "tm": None, "wn": wn, "zn": zn, "wr": wr}
        # motion condition
        if use == "none":
            kvf = rng.uniform(0.96, 1.05)
            TLm = TL * rng.uniform(0.95, 1.05)
            Tm = 0.0
            tvm = tv + rng.uniform(-0.01, 0.01)
            share_m = share_s * rng.uniform(0.9, 1.1)
        else:
            kvf = rng.uniform(1.03, 1.15)
            tvm = tv + rng.uniform(-0.005, 0.02)
            if use == "strong":
                Tm = rng.uniform(0.05, 0.10) if elem == "SI" else rng.uniform(0.35, 0.7)
                TLm = TL * rng.uniform(0.6, 0.85)
                share_m = share_s * rng.uniform(0.75, 0.9)
            else:
                Tm = rng.uniform(0.015, 0.04) if elem == "SI" else rng.uniform(0.1, 0.25)
                TLm = TL * rng.uniform(0.85, 1.0)
                share_m = share_s * rng.uniform(0.85, 1.0)
        tm = rng.uniform(0.11, 0.18)
        tm = min(tm, tvm - 0.03)
        Kvm = Kv * kvf
        Km = Tm * Kvm / MF_K
        motion = {"Kv": Kvm, "TL": TLm, "tv": round(tvm * 1000) / 1000.0,
                  "Km": Km, "tm": (round(tm * 1000) / 1000.0 if Km > 0 else None),
                  "wn": wn * rng.uniform(0.97, 1.03), "zn": zn * rng.uniform(0.95, 1.05),
                  "wr": wr * rng.uniform(0.95, 1.05)}
        share = {"static": float(np.clip(share_s, 0.12, 0.36)),
                 "motion": float(np.clip(share_m, 0.12, 0.36))}
        lam = {"K": rng.uniform(0.0, 0.05), "tau": rng.uniform(0.0, 0.008)}
        base = {"motion": motion, "static": static}
        # per-run parameter sets, checks
        ok = True
        runs = {}
        cond_mean = {}
        for ci, cond in enumerate(order):
            runs[cond] = []
            for r in range(3):
                j = 3 * ci + r
                p = run_params(base[cond], j, lam)
                if not (0.15 <= p["tv"] <= 0.35):
                    ok = False
                if p["Km"] > 0 and not (0.10 <= p["tm"] <= 0.20 and p["tm"] < p["tv"]):
                    ok = False
                if ok and not metrics_ok(loop_metrics(elem, p, cond == "motion")):
                    ok = False
                runs[cond].append(p)
            if not ok:
                break
            pm = {}
            for key in ("Kv", "TL", "tv", "Km", "wn", "zn", "wr"):
                pm[key] = float(np.mean([q[key] for q in runs[cond]]))
            pm["tm"] = (float(np.mean([q["tm"] for q in runs[cond]]))
                        if base[cond]["Km"] > 0 else None)
            m = loop_metrics(elem, pm, cond == "motion")
            if not metrics_ok(m):
                ok = False
                break
            cond_mean[cond] = (pm, m)
        if not ok:
            continue
        # remnant intensities (per condition, from mean parameters)
        Kn = {}
        for cond in ("motion", "static"):
            Kn[cond] = remnant_gain(elem, cond_mean[cond][0], cond == "motion", share[cond], F)
        return {"base": base, "runs": runs, "cond_mean": cond_mean, "share": share,
                "lam": lam, "Kn": Kn, "attempts": attempt + 1}
    raise RuntimeError("could not draw a valid pilot")


# --------------------------------------------------------------------------------------
# simulation
# --------------------------------------------------------------------------------------
def disc(num, den, method="bilinear"):
    b, a, _ = signal.cont2discrete((num, den), DT, method=method)
    b = np.atleast_1d(np.squeeze(b)).astype(float)
    a = np.atleast_1d(np.squeeze(a)).astype(float)
    n = max(len(a), len(b))
    b = np.concatenate([np.zeros(n - len(b)), b])
    a = np.concatenate([a, np.zeros(n - len(a))])
    return b / a[0], a / a[0]


def gain_profile(rng, drift_sd):
    """slow OU drift of the perceptual gain (10 Hz, tau 15 s) and maybe one lapse."""
    n10 = int(T_TOTAL * 10) + 1
    a = np.exp(-0.1 / 15.0)
    x = np.zeros(n10)
    x[0] = rng.normal(0, drift_sd)
    e = rng.normal(0, drift_sd * np.sqrt(1 - a * a), n10)
    for k in range(1, n10):
        x[k] = a * x[k - 1] + e[k]
    t = np.arange(N) * DT
    g = np.exp(np.interp(t, np.arange(n10) * 0.1, x))
    lapse = None
    if rng.random() < 0.12:
        dur = rng.uniform(0.8, 2.5)
        depth = rng.uniform(0.0, 0.3)
        t0 = rng.uniform(T_RUNIN + 2, T_TOTAL - dur - 2)
        edge = 0.2
        prof = np.ones(N)
        m_in = (t >= t0 - edge) & (t < t0)
        prof[m_in] = 1 - (1 - depth) * 0.5 * (1 - np.cos(np.pi * (t[m_in] - t0 + edge) / edge))
        m_lo = (t >= t0) & (t < t0 + dur)
        prof[m_lo] = depth
        m_out = (t >= t0 + dur) & (t < t0 + dur + edge)
        prof[m_out] = depth + (1 - depth) * 0.5 * (1 - np.cos(np.pi * (t[m_out] - t0 - dur) / edge))
        g = g * prof
        lapse = {"start_s": round(float(t0), 3), "duration_s": round(float(dur), 3),
                 "gain_factor": round(float(depth), 3)}
    return g, lapse


def simulate(elem, p, motion_cond, Kn, offset, g, w_noise, ft, fd):
    e = ELEMENTS[elem]
    bp, ap = disc([e["Kc"]], [1.0] + [0.0] * e["order"], "zoh")
    hn_den = [1.0, 2 * p["zn"] * p["wn"], p["wn"] ** 2]
    bv, av = disc(list(np.polymul([p["TL"], 1.0], [p["wn"] ** 2])), hn_den)
    use_m = motion_cond and p["Km"] > 0
    if use_m:
        bm, am = disc(list(np.polymul(SCC_NUM, [p["wn"] ** 2])), list(np.polymul(SCC_DEN, hn_den)))
        dm = int(round(p["tm"] * FS_SIM))
        zm = np.zeros((2, len(am) - 1))
    bn, an = disc(list(np.polymul([p["wr"]], [p["wn"] ** 2])), list(np.polymul([1.0, p["wr"]], hn_den)))
    br, ar = disc(MP_NUM_RATE, MP_DEN)
    dv = int(round(p["tv"] * FS_SIM))
    assert BLOCK <= dv and (not use_m or BLOCK <= dm + DP)

    rem = Kn * p["remfac"] * signal.lfilter(bn, an, w_noise)
    P = 1000
    ebuf = np.zeros((2, P + N))
    rbuf = np.zeros((2, P + N))
    u = np.zeros((2, N))
    psi = np.zeros((2, N))
    ftc = np.zeros((2, N)); ftc[0] = ft
    fdc = np.zeros((2, N)); fdc[0] = fd
    offc = np.array([[offset], [0.0]])
    gv = g * p["Kv"]
    gm = g * p["Km"]
    zv = np.zeros((2, len(av) - 1))
    zp = np.zeros((2, len(ap) - 1))
    zr = np.zeros((2, len(ar) - 1))
    for k0 in range(0, N, BLOCK):
        k1 = min(k0 + BLOCK, N)
        xv = gv[k0:k1] * ebuf[:, P + k0 - dv:P + k1 - dv]
        yv, zv = signal.lfilter(bv, av, xv, axis=-1, zi=zv)
        ub = yv + rem[k0:k1] + offc
        if use_m:
            xm = gm[k0:k1] * rbuf[:, P + k0 - dm - DP:P + k1 - dm - DP]
            ym, zm = signal.lfilter(bm, am, xm, axis=-1, zi=zm)
            ub = ub - ym
        u[:, k0:k1] = ub
        pb, zp = signal.lfilter(bp, ap, ub + fdc[:, k0:k1], axis=-1, zi=zp)
        psi[:, k0:k1] = pb
        ebuf[:, P + k0:P + k1] = ftc[:, k0:k1] - pb
        if motion_cond:
            rb, zr = signal.lfilter(br, ar, pb, axis=-1, zi=zr)
            rbuf[:, P + k0:P + k1] = rb
    if motion_cond:
        ba, aa = disc(MP_NUM_ANG, MP_DEN)
        ang = signal.lfilter(ba, aa, psi[0])
        cab = np.concatenate([np.zeros(DP), ang[:N - DP]])
        rate = rbuf[0, P - DP:P + N - DP]
    else:
        cab = np.zeros(N)
        rate = np.zeros(N)
    err = ebuf[0, P:]
    return {"u": u[0], "u_rem": u[1], "psi": psi[0], "err": err, "cab": cab, "rate": rate}


# --------------------------------------------------------------------------------------
# output
# --------------------------------------------------------------------------------------
COLS = ["Time", "TargetYaw", "DistInput", "YawError", "YawAngle", "StickDefl", "CabYaw", "CabYawRate"]
UNITS = ["[s]", "[deg]", "[deg]", "[deg]", "[deg]", "[deg]", "[deg]", "[deg/s]"]
FMTS = ["%.2f", "%.4f", "%.4f", "%.4f", "%.4f", "%.4f", "%.4f", "%.3f"]


def write_run(path, meta_lines, cols):
    arr = np.column_stack(cols)
    for i, f in enumerate(FMTS):
        nd = int(f[2])
        arr[:, i] = np.round(arr[:, i], nd) + 0.0
    fmt = ";".join(FMTS)
    lines = ["# " + m for m in meta_lines]
    lines.append(";".join(COLS))
    lines.append(";".join(UNITS))
    for row in arr.tolist():
        lines.append((fmt % tuple(row)).replace(".", ","))
    with open(path, "w", newline="", encoding="ascii") as fh:
        fh.write("\r\n".join(lines) + "\r\n")


def tf_json(num, den):
    return {"num": [float(x) for x in num], "den": [float(x) for x in den]}


def rnd(x, n=5):
    return None if x is None else round(float(x), n)


def main():
    ap_ = argparse.ArgumentParser()
    ap_.add_argument("seed", type=int)
    ap_.add_argument("outdir")
    args = ap_.parse_args()
    t_start = time.time()
    rng = np.random.default_rng(args.seed)
    out = args.outdir
    for elem in ELEMENTS:
        for cond in ("motion", "static"):
            os.makedirs(os.path.join(out, "data", elem, cond), exist_ok=True)

    F = build_forcing(rng)
    tlog = np.arange(NLOG) / FS_LOG
    truth = {"SYNTHETIC": "SYNTHETIC data set - generated by lab10_yaw_cab.py, not measured",
             "seed": args.seed, "persons": {}}
    summary = []
    month_day0 = 8
    for elem, einfo in ELEMENTS.items():
        n_none = int(rng.integers(1, 3))
        n_strong = int(rng.integers(3, 5))
        labels = ["none"] * n_none + ["strong"] * n_strong + ["weak"] * (8 - n_none - n_strong)
        labels = [labels[i] for i in rng.permutation(8)]
        for ip, pid in enumerate(einfo["ids"]):
            order = ["motion", "static"] if ip % 2 == 0 else ["static", "motion"]
            use = labels[ip]
            P = draw_person(rng, elem, use, order, F)
            offset = float(rng.normal(0.0, 0.12))
            drift_sd = float(rng.uniform(0.03, 0.07))
            day = month_day0 + int(rng.integers(0, 19))
            clock = 9 * 3600 + int(rng.integers(0, 6 * 3600))
            person = {"element": elem, "uses_motion": use != "none", "motion_use": use,
                      "Kc": einfo["Kc"], "condition_order": order,
                      "stick_offset_deg": rnd(offset, 4), "gain_drift_sd": rnd(drift_sd, 4),
                      "learning": {"gain_rel_change_over_session": rnd(2 * P["lam"]["K"], 4),
                                   "tau_v_decrease_over_session_s": rnd(2 * P["lam"]["tau"], 4)},
                      "runs": []}
            real_share = {"motion": [], "static": []}
            maxstick = 0.0
            for ci, cond in enumerate(order):
                clock += 300 if ci == 1 else 0   # break between conditions
                for r in range(3):
                    j = 3 * ci + r
                    p = P["runs"][cond][r]
                    roff = offset + float(rng.normal(0, 0.03))
                    g, lapse = gain_profile(rng, drift_sd)
                    wnoise = rng.standard_normal(N)
                    res = simulate(elem, p, cond == "motion", P["Kn"][cond], roff, g, wnoise,
                                   F["ft"], F["fd"][elem])
                    sl = slice(0, N, DEC)
                    uw = res["u"][sl][NLOG0:]
                    urw = res["u_rem"][sl][NLOG0:]
                    share = float(np.var(urw) / np.var(uw))
                    real_share[cond].append(share)
                    maxstick = max(maxstick, float(np.max(np.abs(res["u"]))))
                    fname = "%s_%s_%s_r%d.csv" % (pid, elem, cond, r + 1)
                    hh, mm, ss = clock // 3600, (clock % 3600) // 60, clock % 60
                    meta = [
                        "SYNTHETIC DATA - generated by a simulation, not measured on human subjects",
                        "logger: yawtrack-daq v2.3  (research simulator, compensatory yaw tracking)",
                        "subject: %s" % pid,
                        "controlled_element: %s  Hc(s) = %.1f/s%s  [%s]" % (
                            elem, einfo["Kc"], "^2" if einfo["order"] == 2 else "", einfo["units"]),
                        "condition: %s" % cond,
                        "run_in_condition: %d/3   session_run: %d/6" % (r + 1, j + 1),
                        "recorded: 2024-04-%02d %02d:%02d:%02d" % (day, hh, mm, ss),
                        "sample_rate_Hz: 100   samples: %d" % NLOG,
                        "measurement_window: t = %.2f s to %.2f s (%d samples)  run-in before" % (
                            T_RUNIN, T_TOTAL, NLOG - NLOG0),
                        "decimal_mark: comma   separator: semicolon",
                    ]
                    cols = [tlog, F["ft"][sl], F["fd"][elem][sl], res["err"][sl], res["psi"][sl],
                            res["u"][sl], res["cab"][sl], res["rate"][sl]]
                    write_run(os.path.join(out, "data", elem, cond, fname), meta, cols)
                    clock += 150 + int(rng.integers(0, 90))
                    person["runs"].append({
                        "file": "data/%s/%s/%s" % (elem, cond, fname), "condition": cond,
                        "run_in_condition": r + 1, "session_run": j + 1,
                        "Kv": rnd(p["Kv"]), "TL": rnd(p["TL"]), "tau_v": rnd(p["tv"], 3),
                        "Km": rnd(p["Km"] if cond == "motion" else 0.0),
                        "tau_m": (rnd(p["tm"], 3) if (cond == "motion" and p["Km"] > 0) else None),
                        "remnant_Kn": rnd(P["Kn"][cond] * p["remfac"]),
                        "stick_offset_deg": rnd(roff, 4), "lapse": lapse,
                        "remnant_share_realized": rnd(share, 4)})
            for cond in ("motion", "static"):
                pm, (md, mt) = P["cond_mean"][cond]
                Km = pm["Km"] if cond == "motion" else 0.0
                person[cond] = {
                    "Kv": rnd(pm["Kv"]), "TL": rnd(pm["TL"]), "tau_v": rnd(pm["tv"], 4),
                    "Km": rnd(Km), "tau_m": rnd(pm["tm"], 4) if Km > 0 else None,
                    "Km_over_Kv_s": rnd(Km / pm["Kv"], 4),
                    "Km_times_motion_gain_over_Kv_s": rnd(Km * MF_K / pm["Kv"], 4),
                    "omega_nms": rnd(pm["wn"], 3), "zeta_nms": rnd(pm["zn"], 4),
                    "remnant_filter_break_rad_s": rnd(pm["wr"], 3),
                    "remnant_Kn": rnd(P["Kn"][cond]),
                    "remnant_share": rnd(np.mean(real_share[cond]), 4),
                    "remnant_share_design": rnd(P["share"][cond], 4),
                    "crossover_rad_s": rnd(md["wc"], 4), "phase_margin_deg": rnd(md["pm"], 3),
                    "gain_margin": rnd(md["gm"], 3),
                    "target_crossover_rad_s": rnd(mt["wc"], 4),
                    "target_phase_margin_deg": rnd(mt["pm"], 3),
                }
            person["max_abs_stick_deg"] = rnd(maxstick, 3)
            truth["persons"][pid] = person
            summary.append((pid, elem, use, person["motion"]["Km_over_Kv_s"],
                            person["static"]["crossover_rad_s"], person["static"]["phase_margin_deg"],
                            person["motion"]["crossover_rad_s"], person["motion"]["phase_margin_deg"],
                            person["static"]["remnant_share"], person["motion"]["remnant_share"],
                            maxstick))

    # ---------------- plants ----------------
    pn, pd_ = pade2(PL_DELAY)
    mp_num = np.polymul(MP_NUM_RATE, pn)
    mp_den = np.polymul(MP_DEN, pd_)
    ang_num = np.polymul(MP_NUM_ANG, pn)
    for elem, e in ELEMENTS.items():
        cden = [1.0] + [0.0] * e["order"]
        plants = {
            "SYNTHETIC": "SYNTHETIC data set - simulator description for generated data",
            "control_to_output": tf_json([e["Kc"]], cden),
            "disturbance_to_output": tf_json([e["Kc"]], cden),
            "motion_path": tf_json(mp_num, mp_den),
            "units": {"control": "deg (StickDefl)", "disturbance": "deg (DistInput, stick-equivalent)",
                      "output": "deg (YawAngle)", "motion_path_output": "deg/s (cab yaw rate)"},
            "motion_path_description": "YawAngle -> cab yaw rate: s * 0.8 s^2/(s^2+0.56 s+0.16) "
                                       "* 1600/(s^2+56 s+1600) * exp(-0.030 s), delay as 2nd-order Pade",
            "motion_filter": {"gain": MF_K, "omega_rad_s": MF_W, "zeta": MF_Z, "type": "2nd-order high-pass"},
            "platform": {"omega_rad_s": PL_W, "zeta": PL_Z, "latency_s": PL_DELAY, "pade_order": 2},
            "cab_yaw_angle_path": tf_json(ang_num, mp_den),
            "motion_path_applies_in": "motion condition only (static: cab does not move)",
        }
        with open(os.path.join(out, "plants_%s.json" % elem), "w", newline="\n") as fh:
            json.dump(plants, fh, indent=2)
            fh.write("\n")

    # ---------------- truth design ----------------
    truth["design"] = {
        "display": "compensatory; shows yaw error e = TargetYaw - YawAngle as lateral offset of a heading marker",
        "fs_sim_Hz": FS_SIM, "fs_log_Hz": FS_LOG, "run_length_s": T_TOTAL, "run_in_s": T_RUNIN,
        "window_s": T_MEAS, "window_start_s": T_RUNIN, "forcing_fade_in_s": T_FADE,
        "block_samples": BLOCK,
        "target_k": K_TARGET, "dist_k": K_DIST, "base_freq_rad_s": W0,
        "target_omega_rad_s": [round(float(x), 6) for x in F["wt"]],
        "target_amp_deg": [round(float(x), 6) for x in F["at"]],
        "target_phase_rad": [round(float(x), 6) for x in F["pt"]],
        "dist_omega_rad_s": [round(float(x), 6) for x in F["wd"]],
        "dist_amp_stick_deg": {k: [round(float(x), 6) for x in v] for k, v in F["ad"].items()},
        "dist_amp_yaw_equivalent_deg": [round(float(x), 6) for x in F["ad_psi"]],
        "dist_phase_rad": [round(float(x), 6) for x in F["pd"]],
        "forcing_phase_convention": "f(t) = sum A sin(w (t - 8.08) + phi), faded in over first 3 s",
        "crest_factor": {"target": F["crest_t"], "dist": F["crest_d"]},
        "elements": {k: {"Kc": v["Kc"], "order": v["order"]} for k, v in ELEMENTS.items()},
        "motion_filter": {"gain": MF_K, "omega": MF_W, "zeta": MF_Z},
        "platform": {"omega": PL_W, "zeta": PL_Z, "latency_s": PL_DELAY},
        "pilot_model": "u = Hnms*[g(t)*Kv*(TL s+1)*e(t-tau_v) - g(t)*Km*Hscc*r_cab(t-tau_m)] + n + offset; "
                       "Hnms = wn^2/(s^2+2 zn wn s+wn^2); n = Kn*wr/(s+wr)*Hnms*w, w unit white at 1 kHz; "
                       "g(t) = exp(OU drift, tau 15 s) * lapse profile; learning over session runs",
        "scc_tf": {"num": SCC_NUM, "den": SCC_DEN,
                   "note": "Hscc(s) = 5.9 s (0.11 s+1)/(5.9 s+1): unity mid-band gain, input cab yaw rate deg/s"},
        "visual_channel_tf": "Kv (TL s + 1) exp(-tau_v s) Hnms (TL = 0 for SI)",
        "vestibular_channel_tf": "Km Hscc(s) exp(-tau_m s) Hnms, input cab yaw rate [deg/s], subtracted",
        "crossover_definition": "crossover/phase margin of the full open loop opened at the stick "
                                "Hol = Hc (Hpv + Hpm Hmp) (exact delays); target_* = Hpv Hc / (1 + Hpm Hmp Hc)",
        "remnant_share_definition": "var(remnant-driven part of stick)/var(stick) in the window, exact linear "
                                    "decomposition, mean over the 3 runs; *_design = frequency-domain design value",
        "condition_parameters": "mean of the 3 per-run values (runs include learning)",
        "discretization": "plant ZOH, all other continuous filters Tustin at 1 kHz, delays integer samples",
    }
    with open(os.path.join(out, "truth.json"), "w", newline="\n") as fh:
        json.dump(truth, fh, indent=1)
        fh.write("\n")

    write_readme(out, F, truth)
    el = time.time() - t_start
    print("pid elem use Km/Kv  wc_s pm_s  wc_m pm_m  rs_s rs_m  max|u|")
    for row in summary:
        print("%s %s %-6s %.3f  %.2f %.1f  %.2f %.1f  %.3f %.3f  %.2f" % row)
    print("elapsed %.1f s" % el)


def write_readme(out, F, truth):
    L = []
    L.append("SYNTHETIC DATA SET - generated by simulation, NOT measured on human participants.")
    L.append("")
    L.append("Lab 10: yaw tracking with and without simulator (cab) yaw motion")
    L.append("=================================================================")
    L.append("")
    L.append("Task and display")
    L.append("  Compensatory yaw tracking. The out-the-window/head-down display shows only the")
    L.append("  yaw tracking error e = target yaw - yaw angle, as the lateral displacement of a")
    L.append("  heading marker against a fixed reference. Participants control yaw with the")
    L.append("  lateral axis of an electrical side-stick (deflection logged in deg).")
    L.append("  Target signal (TargetYaw) is a yaw-angle command; the disturbance (DistInput) is")
    L.append("  added to the stick signal before the controlled element (stick-equivalent deg):")
    L.append("      YawAngle = Hc(s) * (StickDefl + DistInput),   YawError = TargetYaw - YawAngle")
    L.append("")
    L.append("Controlled elements (one group of 8 participants each)")
    L.append("  SI: Hc(s) = 1.5/s     [(deg/s)/deg]     participants Y01..Y08")
    L.append("  DI: Hc(s) = 4.0/s^2   [(deg/s^2)/deg]   participants Y11..Y18")
    L.append("")
    L.append("Conditions")
    L.append("  motion: the cab yaws with the yaw angle through the motion filter below")
    L.append("  static: cab fixed (CabYaw and CabYawRate logged as 0)")
    L.append("  Each participant: 3 runs per condition, blocked, order counterbalanced")
    L.append("  (odd-numbered participant in group: motion first; even: static first).")
    L.append("  Training runs preceded the session and are not included.")
    L.append("")
    L.append("Motion system (hexapod research simulator, yaw only)")
    L.append("  cab yaw = 0.8 * s^2/(s^2 + 2*0.7*0.4 s + 0.4^2) * yaw angle  (2nd-order high-pass washout,")
    L.append("  gain 0.8, break 0.4 rad/s), platform dynamics 40^2/(s^2 + 2*0.7*40 s + 40^2),")
    L.append("  transport latency 30 ms. The motion_path in plants_*.json is yaw angle -> cab yaw")
    L.append("  RATE [deg/s] with the latency as a 2nd-order Pade approximant.")
    L.append("")
    L.append("Forcing functions (identical in all runs; period = measurement window)")
    L.append("  sum of 10 sines each, on interleaved integer multiples k of w0 = 2*pi/81.92 rad/s:")
    L.append("  f(t) = sum_i A_i sin(w_i (t - 8.08) + phi_i)   (t = Time column), faded in during")
    L.append("  the first 3 s of each run (raised cosine), constant amplitude afterwards.")
    L.append("  Target std 1.5 deg. Disturbance amplitudes chosen so that its open-loop effect on the")
    L.append("  yaw angle (through Hc) has std 1.2 deg; amplitude shaping |(1+0.1jw)^2/(1+0.8jw)^2|.")
    L.append("")
    L.append("   signal   k     w [rad/s]   A [deg]    phi [rad]")
    for i, k in enumerate(K_TARGET):
        L.append("   target %4d  %10.4f  %9.5f  %9.5f" % (k, F["wt"][i], F["at"][i], F["pt"][i]))
    L.append("")
    L.append("   dist     k     w [rad/s]   A_SI [deg]  A_DI [deg]  phi [rad]")
    for i, k in enumerate(K_DIST):
        L.append("   dist   %4d  %10.4f  %10.5f  %10.5f  %9.5f" % (
            k, F["wd"][i], F["ad"]["SI"][i], F["ad"]["DI"][i], F["pd"][i]))
    L.append("")
    L.append("Timing")
    L.append("  Simulation at 1000 Hz, logged at 100 Hz. Each run lasts 90.00 s (9000 samples,")
    L.append("  Time = 0.00 ... 89.99 s). First 8.08 s = run-in. Measurement window:")
    L.append("  Time >= 8.08 s, i.e. the last 8192 samples (81.92 s, exactly one forcing period).")
    L.append("")
    L.append("Files")
    L.append("  data/<SI|DI>/<motion|static>/<ID>_<SI|DI>_<condition>_r<1..3>.csv")
    L.append("  Text, ASCII, CRLF line endings, written with Dutch locale settings:")
    L.append("  field separator ';', decimal mark ','. Lines starting with '#' are metadata")
    L.append("  comments (subject, element, condition, run, time stamp, window).")
    L.append("  After the comments: one header line with column names, one line with units in")
    L.append("  brackets, then 9000 data lines.")
    L.append("")
    L.append("  Column       Unit     Meaning")
    L.append("  Time         s        time since run start")
    L.append("  TargetYaw    deg      target yaw angle ft")
    L.append("  DistInput    deg      disturbance fd, added to the stick signal (stick-equivalent)")
    L.append("  YawError     deg      displayed error e = TargetYaw - YawAngle")
    L.append("  YawAngle     deg      controlled yaw angle (output of Hc)")
    L.append("  StickDefl    deg      participant's stick deflection u (positive = yaw right)")
    L.append("  CabYaw       deg      measured cab yaw angle (0 in static)")
    L.append("  CabYawRate   deg/s    measured cab yaw rate (0 in static)")
    L.append("")
    L.append("  plants_SI.json / plants_DI.json: continuous-time transfer functions (descending")
    L.append("  powers of s, units of the data files): control_to_output (StickDefl -> YawAngle),")
    L.append("  disturbance_to_output (DistInput -> YawAngle), motion_path (YawAngle -> cab yaw rate).")
    L.append("")
    L.append("Participants and session order")
    for pid, p in truth["persons"].items():
        L.append("  %s  %s  %s" % (pid, p["element"], " -> ".join(p["condition_order"])))
    L.append("")
    with open(os.path.join(out, "README.txt"), "w", newline="\n", encoding="ascii") as fh:
        fh.write("\n".join(L))


if __name__ == "__main__":
    main()
