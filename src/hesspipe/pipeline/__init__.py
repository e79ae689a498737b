"""The pipeline: declared stages (``pipeline/stages.toml``), fingerprints, re-runs of what
changed, and the report.
"""

from ..core.lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "Pipeline": "engine", "Stage": "engine", "StageContext": "engine", "StageOutcome": "engine",
    "StageStatus": "engine", "load_stages": "engine",
})
