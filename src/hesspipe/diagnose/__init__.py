"""Stage ``diagnose``: where model and measurement disagree, which effect is missing
(pilot side or aircraft side), the re-fit with it, and the gap it closes.

Modules: ``settings`` (DiagnoseConfig), ``checks`` (the plant check), ``spectra`` (Welch
statistics, expected-PSD kernel, bands), ``likelihood`` (the model's expected spectrum,
residuals, fits), ``motion`` (the describing-function verdicts), ``aircraft`` (aircraft-side
candidates), ``results``, ``report`` (text), ``workflow`` (the rounds), ``examples``
(SYNTHETIC test data made by hesspipe's own simulator).
"""

from ..core.lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "DiagnoseConfig": "settings", "Diagnosis": "results", "Step": "results", "diagnose": "workflow",
    "format_report": "report", "plant_check": "checks", "PlantCheck": "checks",
})
