#!/usr/bin/env python
"""SYNTHETIC yaw-tracking laboratory data set ("lab8").

Independent generator (numpy + scipy only).  Usage:
    python lab8_simona_yaw.py SEED OUTDIR      (the files scored in docs/status.md: seed 8080)
Same seed -> byte-identical output files.

Loop (per run), all signals in degrees:
    e   = ft - psi                                   (displayed, compensatory)
    u   = Hnm * [ g(t) Kv (TL s + 1) e(t - tv)  -  Km Hscc w_c(t - tm) ] + n
    psi = Hc (u + fd)
    w_c = cab yaw rate = s * Hwo * Hplat * e^{-s tp} psi   (motion condition only)
Simulated at 1 kHz in blocks of 50 samples (< every loop delay) with exact
integer-sample delays; logged at 50 Hz by plain sampling.
"""
import json
import os
import sys

import numpy as np
from scipy import signal

if len(sys.argv) != 3:
    sys.exit("usage: python lab8_simona_yaw.py SEED OUTDIR")
SEED = int(sys.argv[1])
OUT = sys.argv[2]

# ---------------------------------------------------------------- design ----
DT = 0.001                # simulation step [s]
FS_LOG = 50.0             # logged rate [Hz]
DEC = int(round(1.0 / (FS_LOG * DT)))
T_MEAS = 90.0             # measurement window = one period of the multisines [s]
T_RUNIN = 10.0            # logged run-in before the window [s]
T_FADE = 5.0              # raised-cosine fade-in of the forcing functions [s]
T_TOTAL = T_RUNIN + T_MEAS
N = int(round(T_TOTAL / DT))
BLOCK = 50                # samples per simulation block (50 ms)
W0 = 2 * np.pi / T_MEAS
K_T = np.array([3, 8, 15, 27, 45, 74, 122])     # target lines
K_D = np.array([5, 11, 20, 35, 58, 95, 157])    # disturbance lines
N_PHASE_SETS = 4
RUNS = 4
N_PERS = 10
N_NONUSERS = 2

ELEMENTS = {
    "SI": dict(Kc=1.5, order=1, ft_rms=1.2, fdout_rms=1.8),
    "DI": dict(Kc=4.0, order=2, ft_rms=1.0, fdout_rms=1.5),
}
# motion system (identical for both elements)
WO = dict(K=0.7, w=0.5, z=0.7)          # 2nd-order high-pass yaw washout
PLAT = dict(w=30.0, z=0.7, tau=0.030)   # platform 2nd-order + pure latency
SCC = dict(tL=0.11, t1=5.9, t2=0.005)   # semicircular canals (Hosman), on yaw rate


def hc_tf(el):
    p = ELEMENTS[el]
    return [p["Kc"]], [1.0] + [0.0] * p["order"]


def washout_plat_rate_tf():
    """psi [deg] -> cab yaw rate [deg/s] without the latency."""
    num = np.polymul([WO["K"], 0, 0, 0], [PLAT["w"] ** 2])
    den = np.polymul([1, 2 * WO["z"] * WO["w"], WO["w"] ** 2],
                     [1, 2 * PLAT["z"] * PLAT["w"], PLAT["w"] ** 2])
    return num, den


def motion_path_pade():
    num, den = washout_plat_rate_tf()
    h = PLAT["tau"] / 2
    return np.polymul(num, [-h, 1.0]), np.polymul(den, [h, 1.0])


def scc_tf():
    num = np.polymul([SCC["t1"], 0.0], [SCC["tL"], 1.0])
    den = np.polymul([SCC["t1"], 1.0], [SCC["t2"], 1.0])
    return num, den


def nm_tf(w, z):
    return [w * w], [1.0, 2 * z * w, w * w]


def fr(num, den, w):
    s = 1j * w
    return np.polyval(num, s) / np.polyval(den, s)


# ------------------------------------------------------------- forcing ----
def shape(w):
    return 1.0 / (1.0 + (w / 1.0) ** 2) ** 0.75 + 0.08


def crest_opt_phases(rng, amps, ks, nsets):
    t = np.arange(0, T_MEAS, 1 / FS_LOG)
    sets = []
    for _ in range(nsets):
        best, bcf = None, np.inf
        for _ in range(150):
            ph = rng.uniform(0, 2 * np.pi, len(ks))
            x = (amps[:, None] * np.sin(np.outer(ks * W0, t) + ph[:, None])).sum(0)
            cf = np.abs(x).max() / x.std()
            if cf < bcf:
                best, bcf = ph, cf
        sets.append(best)
    return sets


def forcing_design(rng, el):
    p = ELEMENTS[el]
    wt, wd = K_T * W0, K_D * W0
    at = shape(wt)
    at *= p["ft_rms"] / np.sqrt(0.5 * (at ** 2).sum())
    ad_out = shape(wd)
    ad_out *= p["fdout_rms"] / np.sqrt(0.5 * (ad_out ** 2).sum())
    num, den = hc_tf(el)
    ad = ad_out / np.abs(fr(num, den, wd))      # amplitudes at the plant input
    return dict(target=dict(k=K_T.tolist(), w=wt.tolist(), A=at.tolist(),
                            phases=[ph.tolist() for ph in crest_opt_phases(rng, at, K_T, N_PHASE_SETS)]),
                dist=dict(k=K_D.tolist(), w=wd.tolist(), A=ad.tolist(),
                          phases=[ph.tolist() for ph in crest_opt_phases(rng, ad, K_D, N_PHASE_SETS)]))


def multisine(A, w, ph, t):
    x = np.zeros_like(t)
    for a, ww, p in zip(A, w, ph):
        x += a * np.sin(ww * t + p)
    fade = np.where(t < T_FADE, 0.5 * (1 - np.cos(np.pi * t / T_FADE)), 1.0)
    return x * fade


# ------------------------------------------------------------- persons ----
def loop_metrics(el, P, motion):
    """crossover [rad/s], phase margin [deg], gain-margin OK flag for the
    disturbance open loop L = Hc Hnm (Hpv + Km Hscc e^-tm Hmot e^-tp)."""
    w = np.logspace(-1.5, 2, 2500)
    s = 1j * w
    hc = fr(*hc_tf(el), w)
    hnm = fr(*nm_tf(P["wnm"], P["znm"]), w)
    hpv = P["Kv"] * (P["TL"] * s + 1) * np.exp(-s * P["tv"])
    L = hc * hnm * hpv
    if motion and P["Km"] > 0:
        hm = P["Km"] * fr(*scc_tf(), w) * np.exp(-s * P["tm"]) \
            * fr(*washout_plat_rate_tf(), w) * np.exp(-s * PLAT["tau"])
        L = hc * hnm * (hpv + hm)
    mag = np.abs(L)
    ph = np.unwrap(np.angle(L))
    # reference the unwrapped phase to the integrator low-frequency asymptote
    n0 = ELEMENTS[el]["order"]
    ph = ph - 2 * np.pi * np.round((ph[0] + n0 * np.pi / 2) / (2 * np.pi) - 0.0)
    cross = np.where(np.diff(np.sign(mag - 1.0)) != 0)[0]
    if len(cross) != 1:
        return None
    i = cross[0]
    f = (1 - mag[i]) / (mag[i + 1] - mag[i])
    wc = w[i] + f * (w[i + 1] - w[i])
    pm = 180 + np.degrees(ph[i] + f * (ph[i + 1] - ph[i]))
    beyond = w > wc
    gm_ok = np.all(mag[beyond][ph[beyond] <= -np.pi] < 0.8) if np.any(ph[beyond] <= -np.pi) else True
    return dict(wc=float(wc), pm=float(pm), gm_ok=bool(gm_ok))


def draw_person(rng, el, km_frac, user):
    for tries in range(100000):
        if el == "SI":
            P = dict(Kv=rng.uniform(1.3, 2.4), TL=0.0, tv=rng.uniform(0.17, 0.27))
            km_lo, km_hi = 0.04, 0.25
        else:
            P = dict(Kv=rng.uniform(0.28, 0.50), TL=rng.uniform(0.9, 1.6), tv=rng.uniform(0.24, 0.34))
            km_lo, km_hi = 0.06, 0.40
        P.update(wnm=rng.uniform(8.0, 14.0), znm=rng.uniform(0.12, 0.45),
                 tm=rng.uniform(0.08, 0.16), Tn=rng.uniform(0.08, 0.22),
                 rem_share=rng.uniform(0.13, 0.36), drift_amp=rng.uniform(0.02, 0.08),
                 learn=rng.uniform(0.0, 0.03))
        P["Km"] = 0.0
        # motion-condition parameters: users add a vestibular channel, raise the
        # visual gain a little, lean less on visual lead, react a bit faster
        M = dict(P)
        if user:
            M["Km"] = km_lo * (km_hi / km_lo) ** km_frac * rng.uniform(0.9, 1.1)
            M["Kv"] = P["Kv"] * rng.uniform(1.0, 1.1) * (1 + (0.25 if el == "SI" else 0.1) * km_frac)
            M["TL"] = P["TL"] * rng.uniform(0.7, 0.9)
            M["tv"] = P["tv"] - rng.uniform(0.0, 0.02)
        ok = True
        for Q, mot in ((P, False), (M, True)):
            for kf in (0.85, 1.0, 1.2):          # robust to run/drift gain spread
                Qk = dict(Q, Kv=Q["Kv"] * kf, Km=Q["Km"] * kf)
                m = loop_metrics(el, Qk, mot)
                if m is None or not m["gm_ok"] or not (1.0 <= m["wc"] <= 5.0) \
                        or not (20.0 <= m["pm"] <= 60.0):
                    ok = False
        if ok:
            P["draws"] = M["draws"] = tries + 1
            return P, M


def run_params(rng, base, run):
    R = dict(base)
    g = (1 + base["learn"] * run) * np.exp(rng.normal(0, 0.04))
    R["Kv"] = base["Kv"] * g
    R["Km"] = base["Km"] * np.exp(rng.normal(0, 0.06))
    R["TL"] = base["TL"] * np.exp(rng.normal(0, 0.04))
    R["tv"] = round(base["tv"] + rng.normal(0, 0.006), 3)
    R["tm"] = round(base["tm"] + rng.normal(0, 0.005), 3)
    R["wnm"] = base["wnm"] * np.exp(rng.normal(0, 0.03))
    R["znm"] = base["znm"] * np.exp(rng.normal(0, 0.05))
    R["rem_share"] = float(np.clip(base["rem_share"] + rng.normal(0, 0.025), 0.10, 0.40))
    R["drift_f"] = rng.uniform(0.003, 0.02, 3).tolist()
    R["drift_ph"] = rng.uniform(0, 2 * np.pi, 3).tolist()
    R["noise_seed"] = int(rng.integers(0, 2 ** 31 - 1))
    return R


# ----------------------------------------------------------- simulation ----
class DFilt:
    """Bilinear-discretised SISO filter applied block-wise to 2 channels."""

    def __init__(self, num, den):
        b, a, _ = signal.cont2discrete((np.atleast_1d(num), np.atleast_1d(den)), DT, method="bilinear")
        self.b, self.a = np.ravel(b), np.ravel(a)
        n = max(len(self.a), len(self.b)) - 1
        self.zi = np.zeros((2, n))

    def __call__(self, x):
        if self.zi.shape[1] == 0:
            return self.b[0] / self.a[0] * x
        y, self.zi = signal.lfilter(self.b, self.a, x, axis=1, zi=self.zi)
        return y


def simulate(el, R, motion, ft, fd):
    """Two superposed channels: 0 = forcing only, 1 = unit remnant only."""
    t = np.arange(N) * DT
    nrng = np.random.default_rng(R["noise_seed"])
    white = nrng.standard_normal(N) / np.sqrt(DT)
    nf = signal.lfilter(*[np.ravel(v) for v in signal.cont2discrete(
        ([1.0], np.polymul([R["Tn"], 1], [R["Tn"], 1])), DT, method="bilinear")[:2]], white)
    d = sum(np.sin(2 * np.pi * f * t + p) for f, p in zip(R["drift_f"], R["drift_ph"]))
    g = R["Kv"] * (1.0 + R["drift_amp"] * d / np.abs(d).max())   # visual gain incl. slow drift

    Fv = DFilt(np.polymul([R["TL"], 1.0], [R["wnm"] ** 2]), nm_tf(R["wnm"], R["znm"])[1])
    use_m = motion and R["Km"] > 0
    if use_m:
        sn, sd = scc_tf()
        Fm = DFilt(-R["Km"] * np.polymul(sn, [R["wnm"] ** 2]), np.polymul(sd, nm_tf(R["wnm"], R["znm"])[1]))
    Hc = DFilt(*hc_tf(el))
    Gm = DFilt(*washout_plat_rate_tf()) if motion else None

    Dv = int(round(R["tv"] / DT))
    Dmt = int(round((R["tm"] + PLAT["tau"]) / DT))
    Dp = int(round(PLAT["tau"] / DT))
    assert Dv >= BLOCK and Dmt >= BLOCK

    F = np.vstack([ft, np.zeros(N)])
    Dd = np.vstack([fd, np.zeros(N)])
    Nn = np.vstack([np.zeros(N), nf])
    e = np.zeros((2, N)); psi = np.zeros((2, N)); u = np.zeros((2, N))
    um = np.zeros((2, N)); wr = np.zeros((2, N))
    for k0 in range(0, N, BLOCK):
        k1 = min(k0 + BLOCK, N)
        a0, a1 = k0 - Dv, k1 - Dv
        ed = np.zeros((2, k1 - k0))
        if a1 > 0:
            ed[:, max(0, a0) - a0:] = e[:, max(0, a0):a1]
        uv = Fv(ed * g[k0:k1])
        if use_m:
            b0, b1 = k0 - Dmt, k1 - Dmt
            wd = np.zeros((2, k1 - k0))
            if b1 > 0:
                wd[:, max(0, b0) - b0:] = wr[:, max(0, b0):b1]
            um[:, k0:k1] = Fm(wd)
        u[:, k0:k1] = uv + um[:, k0:k1] + Nn[:, k0:k1]
        psi[:, k0:k1] = Hc(u[:, k0:k1] + Dd[:, k0:k1])
        e[:, k0:k1] = F[:, k0:k1] - psi[:, k0:k1]
        if Gm is not None:
            wr[:, k0:k1] = Gm(psi[:, k0:k1])
    wcab = np.zeros((2, N))
    if motion:
        wcab[:, Dp:] = wr[:, :N - Dp]
    return dict(u=u, psi=psi, e=e, um=um, wcab=wcab)


def combine(S, share):
    i0 = int(round(T_RUNIN / DT))
    uf, un = S["u"][0, i0:], S["u"][1, i0:]
    uf, un = uf - uf.mean(), un - un.mean()
    a, b, x = uf @ uf, un @ un, uf @ un
    s = share
    c = (2 * x * s + np.sqrt(4 * x * x * s * s + 4 * b * (1 - s) * a * s)) / (2 * b * (1 - s))
    out = {k: v[0] + c * v[1] for k, v in S.items()}
    out["u_rem"] = c * S["u"][1]
    return out, float(c)


# --------------------------------------------------------------- output ----
HEADER = ["Time [s]", "Target [deg]", "Dist [deg]", "Yaw [deg]", "Error [deg]", "Stick [deg]"]


def fmt_col(x):
    x = np.round(x, 4)
    x[x == 0] = 0.0   # no "-0,0000"
    return np.char.replace(np.char.mod("%.4f", x), ".", ",")


def write_csv(path, comments, cols):
    S = [fmt_col(np.asarray(c, float)) for c in cols]
    lines = ["# " + c for c in comments] + [";".join(HEADER)]
    body = S[0]
    for c in S[1:]:
        body = np.char.add(np.char.add(body, ";"), c)
    lines += body.tolist()
    with open(path, "wb") as f:
        f.write(("\r\n".join(lines) + "\r\n").encode("ascii"))


def r6(v):
    if isinstance(v, float):
        return round(v, 6)
    if isinstance(v, dict):
        return {k: r6(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [r6(x) for x in v]
    if isinstance(v, np.floating):
        return round(float(v), 6)
    return v


def main():
    os.makedirs(OUT, exist_ok=True)
    rng = np.random.default_rng(SEED)
    t = np.arange(N) * DT
    idx_log = np.arange(0, N, DEC)
    mp_num, mp_den = motion_path_pade()
    wo_num, wo_den = washout_plat_rate_tf()
    truth = dict(seed=SEED, note="SYNTHETIC lab8 yaw-tracking data; all angles in degrees",
                 design=dict(dt_sim=DT, fs_log=FS_LOG, T_meas=T_MEAS, T_runin_logged=T_RUNIN,
                             T_fade=T_FADE, block=BLOCK, w0=W0),
                 motion_system=dict(
                     washout=dict(WO, tf="K s^2/(s^2+2 z w s+w^2)"),
                     platform=dict(PLAT, tf="w^2/(s^2+2 z w s+w^2) * exp(-tau s)"),
                     true_motion_path="s * washout * platform * exp(-0.030 s) (psi [deg] -> cab yaw rate [deg/s])",
                     true_motion_path_rational_part=dict(num=wo_num.tolist(), den=wo_den.tolist(), delay=PLAT["tau"]),
                     motion_path_pade1=dict(num=mp_num.tolist(), den=mp_den.tolist())),
                 pilot_model=("u = Hnm*[g(t)*Kv*(TL s+1)*e(t-tv) - Km*Hscc*wcab(t-tm)] + n ; "
                              "Hnm = wnm^2/(s^2+2 znm wnm s+wnm^2); Hscc = t1 s (tL s+1)/((t1 s+1)(t2 s+1)) "
                              "on yaw rate; g(t) = 1+drift_amp*normalised sum of 3 slow sines; "
                              "n = white noise through 1/(Tn s+1)^2 scaled to rem_share of stick variance "
                              "(measurement window, superposition)"),
                 scc=SCC, elements={}, persons={})
    pid = 0
    for el in ("SI", "DI"):
        frc = forcing_design(rng, el)
        num, den = hc_tf(el)
        pn = dict(control_to_output=dict(num=num, den=den), disturbance_to_output=dict(num=num, den=den),
                  motion_path=dict(num=mp_num.tolist(), den=mp_den.tolist()),
                  units=dict(input="deg (stick)", output="deg (yaw)", motion_path_output="deg/s (cab yaw rate)"),
                  source="SYNTHETIC lab8; motion_path = s*washout*platform*Pade1(30 ms latency)")
        with open(os.path.join(OUT, f"plants_{el}.json"), "w") as f:
            json.dump(r6(pn), f, indent=1)
        truth["elements"][el] = dict(Hc=dict(num=num, den=den), Kc=ELEMENTS[el]["Kc"], forcing=r6(frc))
        users = np.ones(N_PERS, bool)
        users[rng.choice(N_PERS, N_NONUSERS, replace=False)] = False
        km_fracs = rng.permutation(np.linspace(0, 1, N_PERS - N_NONUSERS))
        ki = 0
        for p in range(N_PERS):
            pid += 1
            name = f"P{pid:02d}"
            frac = km_fracs[ki] if users[p] else 0.0
            ki += int(users[p])
            Ps, Pm = draw_person(rng, el, frac, bool(users[p]))
            truth["persons"][name] = dict(element=el, uses_motion=bool(users[p]),
                                          nominal=dict(static=r6(Ps), motion=r6(Pm)),
                                          nominal_loop=dict(static=r6(loop_metrics(el, Ps, False)),
                                                            motion=r6(loop_metrics(el, Pm, True))),
                                          runs={})
            for cond, base in (("static", Ps), ("motion", Pm)):
                tperm = rng.permutation(N_PHASE_SETS)
                dperm = rng.permutation(N_PHASE_SETS)
                for r in range(RUNS):
                    R = run_params(rng, base, r)
                    ft = multisine(frc["target"]["A"], frc["target"]["w"], frc["target"]["phases"][tperm[r]], t)
                    fd = multisine(frc["dist"]["A"], frc["dist"]["w"], frc["dist"]["phases"][dperm[r]], t)
                    S = simulate(el, R, cond == "motion", ft, fd)
                    O, c = combine(S, R["rem_share"])
                    fn = f"{name}_{el}_{'MOT' if cond == 'motion' else 'STAT'}_R{r + 1}.csv"
                    d = os.path.join(OUT, "data", el, cond)
                    os.makedirs(d, exist_ok=True)
                    com = ["SYNTHETIC DATA - lab8 yaw tracking simulator (generated, not measured)",
                           f"Subject {name}; element {el} (Hc = {ELEMENTS[el]['Kc']}/s^{ELEMENTS[el]['order']}); "
                           f"condition {cond}; run {r + 1} of {RUNS}",
                           f"Logger 50 Hz; first {T_RUNIN:.0f} s = run-in (forcing fade-in), "
                           f"measurement window {T_RUNIN:.0f}-{T_TOTAL:.0f} s ({T_MEAS:.0f} s)",
                           "Separator ';' decimal ',' ; angles in deg; Dist is added to Stick at the plant input"]
                    write_csv(os.path.join(d, fn), com,
                              [idx_log * DT, ft[idx_log], fd[idx_log], O["psi"][idx_log],
                               O["e"][idx_log], O["u"][idx_log]])
                    m = loop_metrics(el, R, cond == "motion")
                    i0 = int(round(T_RUNIN / DT))
                    uw = O["u"][i0:]
                    rec = dict(file=f"data/{el}/{cond}/{fn}", uses_motion=bool(users[p] and cond == "motion"),
                               target_phase_set=int(tperm[r]), dist_phase_set=int(dperm[r]),
                               params=r6(R), remnant_scale=c, loop=r6(m),
                               achieved=dict(rem_share=float(np.var(O["u_rem"][i0:]) / np.var(uw)),
                                             motion_channel_var_share=float(np.var(O["um"][i0:]) / np.var(uw)),
                                             max_abs_yaw=float(np.abs(O["psi"]).max()),
                                             max_abs_stick=float(np.abs(O["u"]).max()),
                                             rms_error=float(np.std(O["e"][i0:]))))
                    truth["persons"][name]["runs"][f"{cond}_R{r + 1}"] = r6(rec)
                    print(name, el, cond, r + 1, "wc=%.2f pm=%.1f rem=%.2f" %
                          (m["wc"], m["pm"], rec["achieved"]["rem_share"]), flush=True)
    with open(os.path.join(OUT, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1)


if __name__ == "__main__":
    main()
