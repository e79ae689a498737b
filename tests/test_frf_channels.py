"""The error and output channels apart (hesspipe.identification.frf_channels): built records
whose channels are known exactly, and the independent generator's precision pilots with and
without the cab's motion (hesspipe.humanlike; SYNTHETIC)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import Run, write_run
from hesspipe.identification.frf import estimate_frf
from hesspipe.identification.frf_channels import BAND_RAD_S, separate_channels
from test_frf import FS, _apply, _multisine

T = 80.0
N = int(FS * T)
D_BINS = np.array([4, 9, 15, 23, 33, 45, 60, 80, 105, 140])
R_BINS = D_BINS + 2


def HPE(s):
    return 2.0 * np.exp(-0.25 * s) * 100 / (s * s + 6 * s + 100)


def HPY(s):
    return 0.6 * s * np.exp(-0.15 * s) / (1 + 0.05 * s) * 100 / (s * s + 6 * s + 100)


def _record(hpy, noise=0.0, target=True):
    # u = Hpe e - Hpy y with y any signal carrying both sets (here: the two forcings through
    # different filters) and e = r - y, so the disturbance lines carry no target power.
    d = _multisine(D_BINS, 1, N)
    r = _multisine(R_BINS, 2, N) if target else np.zeros(N)
    y = _apply(d, lambda s: 1 / (s + 0.5)) + _apply(r, lambda s: 0.8 / (0.3 * s + 1))
    e = r - y
    u = _apply(e, HPE) - _apply(y, hpy) + noise * np.random.default_rng(3).standard_normal(N)
    return Run(time=np.arange(N) / FS, disturbance=d, output=y, control=u, reference=r, id="built",
               synthetic=True)


def test_built_channels_are_recovered_up_to_the_interpolation():
    ch = separate_channels(estimate_frf(_record(HPY)))
    s = 1j * ch.freq_rad_s
    # The last target line lies above the highest disturbance line: not estimated.
    assert ch.freq_rad_s.size == R_BINS.size - 1
    # The interpolation's error grows where Hpe + Hpy bends between lines far apart (the
    # neuromuscular mode at 10 rad/s: 5 % of |Hpe| at 8.4 rad/s); in the band it is small.
    band = (ch.freq_rad_s >= BAND_RAD_S[0]) & (ch.freq_rad_s <= BAND_RAD_S[1])
    for est, true in ((ch.Hpy, HPY(s)), (ch.Hpe, HPE(s))):
        err = np.abs(est - true) / np.abs(HPE(s))
        assert np.max(err[band]) < 0.02 and np.max(err) < 0.1
    assert ch.lines_in_band == band.sum() >= 2
    assert ch.ratio_median == pytest.approx(np.median(np.abs(HPY(s[band]) / HPE(s[band]))), rel=0.05)
    none = separate_channels(estimate_frf(_record(lambda s: 0 * s)))
    assert none.ratio_median < 0.02 and np.max(np.abs(none.Hpy) / np.abs(HPE(1j * none.freq_rad_s))) < 0.05


def test_the_remnant_sigma_is_the_scatter_about_the_noise_free_estimate():
    # The stated sigma is the remnant's part of the error; the interpolation's bias is not in
    # it, so the scatter is measured about the same record's noise-free estimate.
    import dataclasses

    clean = separate_channels(estimate_frf(_record(HPY))).Hpy
    z2 = []
    for seed in range(12):
        rec = _record(HPY)
        noise = 0.4 * np.random.default_rng(seed).standard_normal(N)
        ch = separate_channels(estimate_frf(dataclasses.replace(rec, control=rec.control + noise)))
        z2.append(np.abs(ch.Hpy - clean) ** 2 / ch.sigma_Hpy ** 2)
    assert 0.7 < np.mean(z2) < 1.4     # E|dHpy|^2 = sigma^2 (108 values)


def test_one_forcing_has_no_channels_and_says_why():
    frf = estimate_frf(_record(HPY, target=False))
    assert frf.reference is None and frf.channels is None and frf.to_dict()["channels"] is None
    with pytest.raises(HesspipeError, match="built: the channels need target and disturbance"):
        separate_channels(frf)


def test_command_line_prints_and_writes_the_channels(tmp_path, capsys):
    from hesspipe.cli import main

    write_run(tmp_path / "r.csv", _record(HPY, noise=0.05), ("synthetic test data",))
    (tmp_path / "p.json").write_text('{"control_to_output": {"num": [1], "den": [1, 0]}, '
                                     '"disturbance_to_output": {"num": [1], "den": [1, 0]}}')
    assert main(["frf", str(tmp_path / "r.csv"), "--plants", str(tmp_path / "p.json"),
                 "--json", str(tmp_path / "o.json"), "--figure", str(tmp_path / "o.png")]) == 0
    assert "channels at the reference lines, U = Hpe E - Hpy Y" in capsys.readouterr().out
    assert (tmp_path / "o.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    ch = json.loads((tmp_path / "o.json").read_text())["channels"]
    assert len(ch["Hpy_magnitude"]) == R_BINS.size - 1 and ch["lines_in_band"] >= 2


# --- the independent generator (SYNTHETIC): its truth is the drawn pilot's own two paths ---

@pytest.mark.parametrize("effects", [("motion_feedback",), ()])
def test_generator_precision_pilot_channels_against_the_truth(effects):
    # A yaw-angle person on a single integrator, the cab turning with the displayed angle, at
    # a low remnant (1 % of control power) and no gain wander: what is left is the method's.
    from hesspipe.core.seeds import derive_seed
    from hesspipe.humanlike import draw_trial, pilots, simulate_trial
    from hesspipe.humanlike.forcing import SPARSE_LAYOUT

    spec = None
    for attempt in range(10):
        try:
            spec = draw_trial("1/s", derive_seed(5, "channels", str(attempt)), task="both", pilot="precision",
                              output="angle", tau_m=0.15, effects=effects, remnant_share=0.01,
                              line_bins=SPARSE_LAYOUT["line_bins"], fs=SPARSE_LAYOUT["fs"],
                              T_m=SPARSE_LAYOUT["T_m"])
            break
        except HesspipeError:
            continue
    tr = simulate_trial(spec, fine_ratio=10)
    run = Run(time=tr.time, disturbance=tr.disturbance, output=tr.output, control=tr.control,
              reference=tr.reference, id=spec.name, synthetic=True)
    ch = estimate_frf(run).channels
    A, B = pilots.parts(spec.pilot, ch.freq_rad_s, spec.motion_tf)
    band = (ch.freq_rad_s >= BAND_RAD_S[0]) & (ch.freq_rad_s <= BAND_RAD_S[1])
    assert np.median(np.abs(ch.Hpy[band] - B[band]) / np.abs(A[band])) < 0.1
    truth = np.median(np.abs(B[band]) / np.abs(A[band]))
    if effects:
        assert truth > 0.2 and ch.ratio_median == pytest.approx(truth, rel=0.25)
    else:
        assert ch.ratio_median < 0.1
