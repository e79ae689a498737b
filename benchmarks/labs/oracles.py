"""Oracles of the motion test on lab7's, lab8's, lab10's, lab11's and lab12's files: how many motion runs any test could name (SYNTHETIC).

Uses the laboratory's truth.json and its own model (numpy and scipy only, no hesspipe), on the
describing-function lines (equation error U - Hv E + Km G Y, G the canals x neuromuscular x
vestibular delay x the true motion path acting on Y), each line weighted by the TRUE remnant's
power at its six nearest unforced bins (the oracle knows it; a real test estimates it):

- "known": every parameter at its true value but Km; one-sided chi-square test of Km >= 0;
- "structural": the lab's own pilot structure with Kv, TL, tv, wn, zn free (the visual and
  neuromuscular nuisance a real test must fit), Km and tm added under the alternative;
  chi-square test with 2 degrees of freedom.
- "measured": the structural test with weights a real test can have instead of the true
  remnant's: at each line, U - H E at its six nearest unforced bins with H = U/E measured
  at the line (no model and no truth enters; the residual under any right model is the
  remnant there, up to how far H moves between the line and its neighbours).
- "measured-F": the measured test with the chi-square's known scale replaced by the scale of
  the alternative's own residual, an F test of 2 and 2n - 7 degrees of freedom, as
  hesspipe's test makes it: weights of six bins each have a noisy scale, and a chi-square
  on them is liberal (lab10's double-integrator static runs: 2 of 24 at 0.01).
- "true-F": the structural test (true remnant weights) with the F test's scale: the lab's
  own model with ideal weights and an honest scale. On a pursuit display the measured
  weights weigh the target lines down (H at a target line holds the feedforward, which the
  neighbours' E lacks), which there raises "measured-F" above this.

lab11's display is pursuit: its persons add a feedforward on the target, ``Hn Kf Hc^-1
(Tf s + 1)^-n e^(-tau_f s) R`` (Drop et al.), which every test above subtracts too, its three
parameters free in the structural tests; its single-integrator persons have no visual lead,
so there the lab's own structure fixes TL at 0 (with it free, a lead on E = R - Y and a
smaller feedforward mimic a canal path on Y almost exactly).

Prints per element, condition and motion use how many runs have p < 0.01; then, per element
and condition, the cohort verdict the structural oracle would give by hesspipe's rule (each
person's runs combined by Fisher's method, then the median-person order-statistic test,
Wilkinson 1951: "yes" below 0.01): what any test of the lab's own model could say about the
cohort (`hesspipe pilots`' verdict is measured against it).

Usage::

    python benchmarks/labs/oracles.py lab8 /tmp/lab8
    python benchmarks/labs/oracles.py lab7 /tmp/lab7
    python benchmarks/labs/oracles.py lab10 /tmp/lab10
    python benchmarks/labs/oracles.py lab11 /tmp/lab11
    python benchmarks/labs/oracles.py lab12 /tmp/lab12
"""
import csv
import json
import sys

import numpy as np
from scipy import io as sio
from scipy import stats
from scipy.optimize import least_squares

LABS = {
    # window (start s, samples, rate Hz), lines (target + disturbance), columns (control, output, target),
    # separator, decimal comma, canal on the cab's rate, true motion path from the output to the cab's rate
    "lab8": dict(start=10.0, n=4500, fs=50, lines=[3, 8, 15, 27, 45, 74, 122, 5, 11, 20, 35, 58, 95, 157],
                 cols=("Stick [deg]", "Yaw [deg]", "Target [deg]"), sep=";",
                 canal=lambda s: 5.9 * s * (0.11 * s + 1) / ((5.9 * s + 1) * (0.005 * s + 1)),
                 path=lambda s: s * 0.7 * s**2 / (s**2 + 0.7 * s + 0.25) * 900 / (s**2 + 42 * s + 900)
                 * np.exp(-0.03 * s)),
    "lab7": dict(start=8.0, n=8192, fs=100, lines=[2, 5, 11, 17, 27, 41, 59, 83, 119, 179,
                                                  3, 7, 13, 19, 29, 43, 61, 89, 127, 187],
                 cols=("u", "psi", "ft"), sep=",",
                 canal=lambda s: s * (0.11 * s + 1) / (5.9 * s + 1),
                 path=lambda s: s * 0.7 * s**2 / (s**2 + 0.7 * s + 0.25) * np.exp(-0.05 * s)),
    # lab10's files carry a units row under the header (skipped); its canal has no 5 ms pole
    "lab10": dict(start=8.08, n=8192, fs=100, lines=[3, 7, 13, 23, 37, 53, 79, 109, 149, 211,
                                                    5, 11, 17, 29, 43, 61, 89, 127, 173, 233],
                  cols=("StickDefl", "YawAngle", "TargetYaw"), sep=";", units_row=True,
                  canal=lambda s: 5.9 * s * (0.11 * s + 1) / (5.9 * s + 1),
                  path=lambda s: s * 0.8 * s**2 / (s**2 + 0.56 * s + 0.16) * 1600 / (s**2 + 56 * s + 1600)
                  * np.exp(-0.03 * s)),
    # lab11: tab-separated with '%' metadata lines; pursuit (feedforward on the target)
    "lab11": dict(start=15.0, n=9600, fs=120, lines=[3, 7, 13, 23, 37, 59, 89, 131, 181, 223,
                                                    5, 11, 17, 29, 47, 71, 109, 157, 199, 241],
                  cols=("stick_deg", "yaw_deg", "target_deg"), sep="\t", pursuit=True,
                  canal=lambda s: 5.9 * s * (0.11 * s + 1) / ((5.9 * s + 1) * (0.005 * s + 1)),
                  path=lambda s: s * 0.7 * s**2 / (s**2 + 0.7 * s + 0.25) * 1225 / (s**2 + 49 * s + 1225)
                  * np.exp(-0.03 * s)),
    # lab12: MATLAB v5 files, one struct `run` of column vectors; the stick in volts
    "lab12": dict(start=8.08, n=8192, fs=100, lines=[6, 13, 27, 41, 53, 73, 103, 139, 174, 229,
                                                    5, 11, 23, 37, 51, 71, 101, 137, 171, 226],
                  cols=("stick", "psi", "psi_tgt"), struct="run",
                  canal=lambda s: 5.97 * s * (0.11 * s + 1) / ((5.97 * s + 1) * (0.005 * s + 1)),
                  path=lambda s: s * 0.6 * s**2 / (s**2 + 0.7 * s + 0.25) * 625 / (s**2 + 35 * s + 625)
                  * np.exp(-0.03 * s)),
}


def lines(lab):
    """The lab's forcing lines (FFT bins of its window), sorted, and the same as a set."""
    out = np.array(sorted(lab["lines"]))
    return out, set(out.tolist())


def read(path, lab):
    i0 = int(round(lab["start"] * lab["fs"]))
    if lab.get("struct"):
        st = sio.loadmat(path, squeeze_me=True, struct_as_record=False)[lab["struct"]]
        return {k: np.asarray(getattr(st, k), float)[i0:i0 + lab["n"]] for k in lab["cols"]}
    rows = [r for r in csv.reader(open(path, encoding="utf-8-sig"), delimiter=lab["sep"])
            if r and not r[0].startswith(("#", "%"))]
    body = rows[2:] if lab.get("units_row") else rows[1:]
    d = np.array([[float(x.replace(",", ".")) if lab["sep"] == ";" else float(x) for x in r if x.strip()]
                  for r in body])
    return {k: d[i0:i0 + lab["n"], i] for i, k in enumerate(rows[0])}


def spectra(x, lab):
    """U, Y, E and R (the target's) of the window."""
    u, y, r = lab["cols"]
    return np.fft.rfft(x[u]), np.fft.rfft(x[y]), np.fft.rfft(x[r] - x[y]), np.fft.rfft(x[r])


def visual(s, Kv, TL, tv, wn, zn):
    Hn = wn**2 / (s**2 + 2 * zn * wn * s + wn**2)
    return Kv * (TL * s + 1) * np.exp(-s * tv) * Hn, Hn


def vestibular(s, Hn, tm, lab):
    return lab["canal"](s) * Hn * np.exp(-s * tm) * lab["path"](s)


def feedforward(s, Hn, Kf, tf, Tf, p):
    """A pursuit person's path from the target: ``Hn Kf Hc^-1 (Tf s + 1)^-n e^(-tf s)``."""
    n = p["order"]
    return Hn * Kf / p["Kc"] * s**n / (Tf * s + 1) ** n * np.exp(-s * tf)


def weights(U, Y, E, R, s, p, Km, lab):
    Hv, Hn = visual(s, p["Kv"], p["TL"], p["tv"], p["wnm"], p["znm"])
    noise = U - Hv * E + Km * vestibular(s, Hn, p["tm"], lab) * Y
    if lab.get("pursuit"):
        noise = noise - feedforward(s, Hn, p["Kf"], p["tf"], p["Tf"], p) * R
    return np.array([np.mean(np.abs(noise[nb]) ** 2) for _, nb in neighbours(lab)])


def measured_weights(U, E, lab):
    """Each line's remnant power as a real test measures it: ``mean |U_j - H E_j|^2`` over the
    six nearest unforced bins j, H = U/E at the line."""
    return np.array([np.mean(np.abs(U[nb] - U[L] / E[L] * E[nb]) ** 2) for L, nb in neighbours(lab)])


def neighbours(lab):
    """(line, its six nearest unforced bins) for each of the lab's forcing lines."""
    bins, forced = lines(lab)
    return [(L, sorted((j for j in range(L - 6, L + 7) if j not in forced and j > 0), key=lambda j: abs(j - L))[:6])
            for L in bins]


def known(U, Y, E, R, s, p, sig, lab):
    Hv, Hn = visual(s, p["Kv"], p["TL"], p["tv"], p["wnm"], p["znm"])
    bins = lines(lab)[0]
    a = U - Hv * E - (feedforward(s, Hn, p["Kf"], p["tf"], p["Tf"], p) * R if lab.get("pursuit") else 0)
    a, g = a[bins], (vestibular(s, Hn, p["tm"], lab) * Y)[bins]
    k = max(0.0, -np.sum((np.conj(g) * a).real / sig) / np.sum(np.abs(g) ** 2 / sig))
    d = 2 * (np.sum(np.abs(a) ** 2 / sig) - np.sum(np.abs(a + k * g) ** 2 / sig))
    return 0.5 * stats.chi2.sf(d, 1) if d > 0 else 1.0


def structural(U, Y, E, R, s, p, sig, lab, f_test=False):
    bins = lines(lab)[0]
    sl, Ul, Yl, El, Rl, w = s[bins], U[bins], Y[bins], E[bins], R[bins], 1 / np.sqrt(sig)
    lead, nf = p.get("lead", True), 3 if lab.get("pursuit") else 0
    nv = 5 if lead else 4

    def resid(q, h1):
        Hv, Hn = visual(sl, *(q[:5] if lead else (q[0], 0.0, *q[1:4])))
        r = Ul - Hv * El
        if nf:
            r = r - feedforward(sl, Hn, *q[nv:nv + 3], p) * Rl
        if h1:
            r = r + q[nv + nf] * vestibular(sl, Hn, q[nv + nf + 1], lab) * Yl
        r = r * w
        return np.concatenate([r.real, r.imag])

    keep = slice(None) if lead else [0, 2, 3, 4]
    lo = list(np.array([1e-3, 0, 0.05, 3, 0.05])[keep]) + [0, 0, 0.01][:nf]
    hi = list(np.array([50, 5, 0.5, 30, 1.5])[keep]) + [3, 0.5, 1.0][:nf]
    ff = ([p["Kf"], p["tf"], p["Tf"]], [0.5, 0.15, 0.2], [0.8, 0.1, 0.1]) if nf else ([],) * 3
    fits0 = [least_squares(resid, np.clip(list(np.array(st)[keep]) + f, np.add(lo, 1e-6), np.subtract(hi, 1e-6)),
                           bounds=(lo, hi), args=(False,))
             for st, f in zip(([p["Kv"], p["TL"], 0.25, 10, 0.3], [p["Kv"] * 0.7, max(p["TL"], 0.5) * 0.5, 0.2, 8, 0.5],
                               [p["Kv"] * 1.3, p["TL"] * 1.5 + 0.1, 0.3, 14, 0.2]), ff)]
    f0 = min(fits0, key=lambda f: f.cost)
    f1 = min((least_squares(resid, np.concatenate([f0.x, [km * abs(f0.x[0]), tm]]),
                            bounds=(lo + [0, 0], hi + [50, 0.3]), args=(True,))
              for km in (0.1, 0.5) for tm in (0.05, 0.15)), key=lambda f: f.cost)
    if f_test:   # the scale from the alternative's residual, as a real test has it
        dof = 2 * bins.size - f1.x.size
        return stats.f.sf(max((f0.cost - f1.cost) / 2 / (f1.cost / dof), 0.0), 2, dof)
    return stats.chi2.sf(max(4 * (f0.cost - f1.cost), 0.0), 2)   # cost = sum(r^2)/2; chi2 = 2 sum(r^2)


def runs(name, truth):
    """(element, condition, uses motion, file, parameters in lab8's names, person) of every run."""
    if name == "lab11":
        for person, v in truth["persons"].items():
            ce = truth["design"]["controlled_elements"][v["element"]]
            for r in v["runs"]:
                yield v["element"], r["condition"], v["uses_motion"], r["file"], dict(
                    Kv=r["Kv_mean_window"], TL=r["TL_s"], tv=r["tau_v_s"], wnm=r["wn_nms_rad_s"],
                    znm=r["zeta_nms"], tm=r["tau_m_s"], Km=r["Km"], Kf=r["Kf"], tf=r["tau_f_s"],
                    Tf=r["Tf_s"], Kc=ce["Kc"], order=ce["order"], lead=r["TL_s"] > 0), person
        return
    if name == "lab12":
        for r in truth["runs"]:
            q = r["params"]
            yield r["element"], r["condition"], r["person_is_motion_user"], r["file"], dict(
                Kv=q["Kv_V_per_deg"], TL=q["TL_s"], tv=q["tau_v_s"], wnm=q["w_nm_rad_s"], znm=q["zeta_nm"],
                tm=q["tau_m_s"], Km=q["Km_V_per_degps"]), r["person"]
        return
    if name == "lab10":
        for person, v in truth["persons"].items():
            for r in v["runs"]:
                c = v[r["condition"]]   # the neuromuscular mode is the person's, per condition
                yield v["element"], r["condition"], v["uses_motion"], r["file"], dict(
                    Kv=r["Kv"], TL=r["TL"], tv=r["tau_v"], wnm=c["omega_nms"], znm=c["zeta_nms"],
                    tm=r["tau_m"] or 0.1, Km=r["Km"]), person
        return
    if name == "lab8":
        for person, v in truth["persons"].items():
            for key, r in v["runs"].items():
                yield v["element"], key.split("_")[0], v["uses_motion"], r["file"], r["params"], person
        return
    for el, e in truth["elements"].items():
        for person, v in e["persons"].items():
            for cond, rr in v["runs"].items():
                for r in rr.values():
                    # a static run's tau_m is null (never used: Km is 0 there)
                    yield el, cond, v["uses_motion"], r["file"], dict(
                        Kv=r["Ke"], TL=r["T_L"], tv=r["tau_v"], wnm=r["wn"], znm=r["zeta"],
                        tm=r["tau_m"] or 0.1, Km=r["Km"] or 0.0), person


def median_person_p(ps):
    """P(Binomial(n, p_(r)) >= r), r = ceil(n / 2): at least half of the persons show it."""
    ps = np.sort(np.asarray(ps, dtype=float))
    r = int(np.ceil(ps.size / 2))
    return float(stats.binom.sf(r - 1, ps.size, ps[r - 1]))


def main(name, root):
    lab = LABS[name]
    truth = json.load(open(f"{root}/truth.json"))
    w0 = 2 * np.pi * lab["fs"] / lab["n"]
    tally, persons = {}, {}
    for el, cond, user, file, p, person in runs(name, truth):
        cond = "motion" if cond.startswith("motion") else "static"
        U, Y, E, R = spectra(read(f"{root}/{file}", lab), lab)
        s = 1j * np.arange(U.size) * w0
        sig = weights(U, Y, E, R, s, p, p["Km"] if cond == "motion" else 0.0, lab)
        mw = measured_weights(U, E, lab)
        for test_name, test, w, kw in (("known", known, sig, {}), ("structural", structural, sig, {}),
                                       ("measured", structural, mw, {}),
                                       ("measured-F", structural, mw, {"f_test": True}),
                                       ("true-F", structural, sig, {"f_test": True})):
            t = tally.setdefault((test_name, el, cond, user), [0, 0])
            p_run = test(U, Y, E, R, s, p, w, lab, **kw)
            t[0] += p_run < 0.01
            t[1] += 1
            if test_name == "structural":
                persons.setdefault((el, cond), {}).setdefault(person, []).append(p_run)
    print(f"SYNTHETIC DATA: {name}'s files; oracle motion tests (p < 0.01)")
    for (test_name, el, cond, user), (k, n) in sorted(tally.items()):
        print(f"{test_name:<10} {el} {cond:<6} {'user' if user else 'non-user':<8} {k}/{n}")
    for (el, cond), by in sorted(persons.items()):
        ps = [stats.combine_pvalues(v, method="fisher").pvalue for v in by.values()]
        mp = median_person_p(ps)
        print(f"structural cohort {el} {cond:<6} median-person p = {mp:.2g} ({'yes' if mp < 0.01 else 'no'}); "
              f"persons with p < 0.01: {sum(q < 0.01 for q in ps)}/{len(ps)}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
