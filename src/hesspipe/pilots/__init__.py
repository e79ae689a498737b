"""Stage ``pilots`` (command ``hesspipe pilots``): a cohort of pilot runs, each identified
with the original and expanded models, compared, and the cohort's motion verdict.
"""

from ..core.lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "CohortSpec": "cohort", "synth_cohort": "cohort", "synth_pilot": "cohort", "Comparison": "results",
    "PilotsConfig": "settings", "CompareSettings": "settings", "compare_pilots": "compare",
    "compare_run": "compare", "fly_cohort": "flown",
    "cohort_verdict": "verdict", "motion_test": "verdict", "pilot_groups": "verdict",
    "compare_conditions": "conditions", "ConditionComparison": "conditions",
})
