"""Benchmark: motion named per run on an independent laboratory's files (SYNTHETIC DATA).

The laboratories in ``benchmarks/labs/`` were written by reviewers who did not read hesspipe
(numpy and scipy only; their files, plants and ``truth.json`` are the lab's own formats).
This reads one generated laboratory as ``hesspipe diagnose FOLDER --each`` reads it (the
lab's columns and plants file), diagnoses every run on its own and counts, per controlled
element and condition, the runs named ``motion_feedback``: the motion users' motion runs,
the non-users' motion runs, and the static runs (issue 13: >= 70 % of motion runs, <= 10 %
of no-motion runs). The cohort verdicts are ``hesspipe pilots`` on each condition's folder
(docs/status.md gives the commands).

Usage::

    python benchmarks/labs/lab7_awkward_yaw.py --seed 2026 --out /tmp/lab7
    python benchmarks/bench_labs.py lab7 /tmp/lab7
    python benchmarks/labs/lab8_simona_yaw.py 8080 /tmp/lab8
    python benchmarks/bench_labs.py lab8 /tmp/lab8 [--elements SI,DI] [--conditions motion,static]
        [--display either|compensatory|pursuit]
    python benchmarks/labs/lab9_roll_hexapod.py 9090 /tmp/lab9
    python benchmarks/bench_labs.py lab9 /tmp/lab9
    python benchmarks/labs/lab10_yaw_cab.py 1010 /tmp/lab10
    python benchmarks/bench_labs.py lab10 /tmp/lab10
    python benchmarks/labs/lab11_yaw_pursuit.py 1111 /tmp/lab11
    python benchmarks/bench_labs.py lab11 /tmp/lab11
    python benchmarks/labs/lab12_yaw_mat.py 1212 /tmp/lab12
    python benchmarks/bench_labs.py lab12 /tmp/lab12

Set ``OPENBLAS_NUM_THREADS=1`` for one core's CPU time.
"""

from __future__ import annotations

import argparse
import json
import re
import statistics
import sys
from pathlib import Path

from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_plants
from hesspipe.diagnose import DiagnoseConfig

sys.path.insert(0, str(Path(__file__).parent))
from bench_diagnose_folder import read_folder, timed_diagnose  # noqa: E402  (the same reading and timing)

LABS = {
    # name: (plants file per element, --columns, person id in the file name, elements)
    "lab7": ("plants/yaw_{el}.json", "time=t,reference=ft,disturbance=fd,output=psi,control=u", r"^(S[0-9]+)_",
             "SI,DI"),
    "lab8": ("plants_{el}.json", "time=Time [s],reference=Target [deg],disturbance=Dist [deg],"
             "output=Yaw [deg],control=Stick [deg]", r"^(P[0-9]+)_", "SI,DI"),
    # Written 2026-12-02 by a reviewer who did not read hesspipe; scored once as written.
    "lab9": ("plants_{el}.json", "time=t,reference=ft,disturbance=fd,output=phi,control=u", r"^(R[0-9]+)_",
             "ROLL"),
    # Written 2026-12-02 by another reviewer from the issue's own words; scored once as written.
    "lab10": ("plants_{el}.json", "time=Time[s],reference=TargetYaw[deg],disturbance=DistInput[deg],"
              "output=YawAngle[deg],control=StickDefl[deg]", r"^(Y[0-9]+)_", "SI,DI"),
    # Written 2026-12-02 by a third reviewer from the words, read as a pursuit display; scored once.
    "lab11": ("plants_{el}.json", "time=time_ms,reference=target_deg,disturbance=disturbance_deg,output=yaw_deg,"
              "control=stick_deg", r"^(Q[0-9]+)_", "SI,DI"),
    # Written 2026-12-03 by a fourth reviewer (MATLAB structs, a stick in volts); scored once as written.
    "lab12": ("plants_{el}.json", "time=run.t,reference=run.psi_tgt,disturbance=run.fd,output=run.psi,"
              "control=run.stick", r"^(P[0-9]+)_", "SI,DI"),
}


def motion_users(lab: str, truth: dict, element: str) -> set[str]:
    """The persons the laboratory's truth says use the cab's motion in the motion condition."""
    if lab == "lab7":
        return {p for p, v in truth["elements"][element]["persons"].items() if v["uses_motion"]}
    if lab == "lab12":
        return {v["person"] for v in truth["persons"][element] if v["motion_user"]}
    return {p for p, v in truth["persons"].items() if v["element"] == element and v["uses_motion"]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("lab", choices=sorted(LABS))
    ap.add_argument("root", help="the folder the laboratory's generator wrote")
    ap.add_argument("--elements", help="comma-separated (default: the laboratory's, SI,DI or ROLL)")
    ap.add_argument("--conditions", default="motion,static")
    ap.add_argument("--display", default="either", help="DiagnoseConfig.display (the laboratories' is compensatory)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    try:
        return _score(args)
    except (HesspipeError, OSError, json.JSONDecodeError) as exc:   # a wrong folder, element or condition
        print(f"bench_labs: error: {exc}", file=sys.stderr)
        return 1


def _score(args) -> int:
    plants_name, columns, person, elements = LABS[args.lab]
    config = DiagnoseConfig(display=args.display)
    root = Path(args.root)
    truth = json.loads((root / "truth.json").read_text())
    print("SYNTHETIC DATA: an independent laboratory's generated files, diagnosed run by run")
    totals: dict[str, list[int]] = {}
    times: dict[str, list[float]] = {}
    for el in (args.elements or elements).split(","):
        plants = read_plants(root / plants_name.format(el=el))
        users = motion_users(args.lab, truth, el)
        for cond in args.conditions.split(","):
            counts = {"users": [0, 0], "others": [0, 0]}
            for run in read_folder(root / "data" / el / cond, columns):
                d, cpu = timed_diagnose(run, plants, config, args.seed)
                times.setdefault(el, []).append(cpu)
                who = "users" if cond == "motion" and re.match(person, run.id).group(1) in users else "others"
                counts[who][0] += "motion_feedback" in d.named_effects
                counts[who][1] += 1
            print(f"{el} {cond:<7} motion named: users' runs {counts['users'][0]}/{counts['users'][1]}, "
                  f"other runs {counts['others'][0]}/{counts['others'][1]}", flush=True)
            for who, (k, n) in counts.items():
                tot = totals.setdefault(f"{cond} {who}", [0, 0])
                tot[0] += k
                tot[1] += n
    for key, (k, n) in totals.items():
        if n:
            print(f"all {key}: {k}/{n} ({100 * k / n:.0f} %)")
    every = [t for ts in times.values() for t in ts]
    if every:
        # Per element as well: Hess's order 2 fits more (the precision structure too).
        per = ", ".join(f"{el} {statistics.median(ts):.2f} s" for el, ts in times.items())
        print(f"median CPU time per diagnosis {statistics.median(every):.2f} s ({len(every)} runs; {per})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
