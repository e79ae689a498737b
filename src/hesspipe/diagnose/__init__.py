"""Stage ``diagnose``: where model and measurement disagree, which effect is missing
(pilot side or aircraft side), the re-fit with it, and the gap it closes.
"""

from ..core.lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "DiagnoseConfig": "workflow", "Diagnosis": "workflow", "diagnose": "workflow",
    "format_report": "workflow",
})
