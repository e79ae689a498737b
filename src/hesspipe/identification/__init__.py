"""Identifying the pilot model from measured data: the paper's spectral APID (Eq. 10),
phase-aware criteria on the nonparametric describing function, and the describing
function itself.
"""

from ..core.lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "bit_climb": "apid", "choose_k": "criteria", "identify_phase_aware": "criteria", "Frf": "frf",
    "estimate_frf": "frf", "nonparametric_crossover": "frf", "average_frf": "frf_average",
    "separate_channels": "frf_channels", "Identification": "problem",
    "identifiability": "fit", "identify": "fit", "PaperWelch": "spectra", "fitness": "spectra",
    "psd": "spectra",
})
