"""Stage two, ``plants`` (and ``analytic``): ARX wind -> roll rate and aileron -> roll rate
as continuous transfer functions, validated; the paper's analytic aircraft beside them.
"""

from ..core.lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "AnalyticPlants": "analytic", "analytic_transfer_functions": "analytic", "load_analytic": "analytic",
    "ArxModel": "arx", "arx_fit": "arx", "select_order": "order", "residual_tests": "validation", "fit_percent": "validation", "tustin_d2c": "d2c", "AnalyticConfig": "settings",
    "PlantsConfig": "settings", "PlantsResult": "fit", "analytic_plants": "fit", "fit_plants": "fit",
})
