"""The benchmarks that reach into private fitting code still run (SYNTHETIC DATA).

``bench_motion_limit`` and ``bench_flown_motion_limit`` call ``motion_test``'s private
``_fit`` and ``_predict`` to build their oracle; a change of those signatures broke both
once without any test noticing. ``bench_drift_sidebands`` reads the generator's realised gain
wander. One seed each, the cheapest case.
"""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

BENCH = Path(__file__).resolve().parent.parent / "benchmarks"


def _load(name):
    spec = importlib.util.spec_from_file_location(name, BENCH / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_motion_limit_oracle_runs(capsys):
    assert _load("bench_motion_limit").main(["--seeds", "1", "--cases", "roll:rate"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("SYNTHETIC DATA")
    summary = re.search(r"oracle nc median ([\d.]+).*expected named ([\d.]+) of 1", out)
    assert summary, out
    assert float(summary.group(1)) > 0.0


def test_flown_motion_limit_oracle_runs(capsys):
    assert _load("bench_flown_motion_limit").main(["--seeds", "1"]) == 0
    out = capsys.readouterr().out
    summary = re.search(r"SUMMARY \(1 pilots, SYNTHETIC\): measured named \d of 1; "
                        r"oracle expected ([\d.]+) \(median nc ([\d.]+)\)", out)
    assert summary, out
    assert float(summary.group(2)) > 0.0


def test_drift_sidebands_runs():
    # The DFT of the product is the full circular convolution, so the truncated sums must
    # approach it: a wrong index or normalisation would not.
    d, share = _load("bench_drift_sidebands").spread("roll", "angle", "both", 108, 0.15)
    assert d.shape == (6,) and d[0] > 0.0
    assert share[20] > 0.95 and share[20] >= share[1]
