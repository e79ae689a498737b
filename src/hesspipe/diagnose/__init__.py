"""Stage ``diagnose``: where model and measurement disagree, which effect is missing
(pilot side or aircraft side), the re-fit with it, and the gap it closes.

The package is also the stage's entry point: ``hesspipe.diagnose(run, plants)`` is
:func:`hesspipe.diagnose.workflow.diagnose` (so the stage, its package, its command and
its function share one name).

Parameters
----------
run : hesspipe.core.formats.Run
    Measured run: disturbance, output, control (and reference).
plants : hesspipe.core.formats.Plants
    Yc (control -> output) and Yd (disturbance -> output), optional motion path.
**options
    ``model``, ``candidates``, ``seed``, ``config`` (a :class:`DiagnoseConfig`), as in
    :func:`hesspipe.diagnose.workflow.diagnose`.

Returns
-------
Diagnosis

Modules: ``settings`` (DiagnoseConfig), ``checks`` (the plant check), ``spectra`` (Welch
statistics, expected-PSD kernel, bands), ``expected`` (a model's expected control
spectrum), ``likelihood`` (log-spectral residuals and their likelihood), ``fitting`` (the
fits), ``motion`` (the describing-function verdicts), ``aircraft`` (aircraft-side
candidates), ``results``, ``report`` (text), ``workflow`` (the rounds), ``each`` (every run
on its own, the names tallied), ``examples``
(SYNTHETIC test data made by hesspipe's own simulator).
"""

import sys
import types

from ..core.lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "DiagnoseConfig": "settings", "Diagnosis": "results", "Step": "results", "diagnose": "workflow",
    "format_report": "report", "plant_check": "checks", "PlantCheck": "checks",
    "diagnose_each": "each", "RunDiagnoses": "each",
})


class _StagePackage(types.ModuleType):
    """The package, callable as the stage's function (see the package docstring)."""

    def __call__(self, run, plants, **options):
        from .workflow import diagnose  # the package itself stays light until called

        return diagnose(run, plants, **options)


sys.modules[__name__].__class__ = _StagePackage
