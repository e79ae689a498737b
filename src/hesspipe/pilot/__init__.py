"""The pilot model: Hess's structural model (original and with motion feedback), its
blocks and effects, the closed-loop simulation, crossover, McRuer's precision model.

Implementation modules are private in spirit (as in :mod:`scipy.signal`); the names a
researcher scripts with are re-exported here, loaded on first use.
"""

from ..core.lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "Loop": "blocks", "Term": "blocks", "Crossover": "crossover", "CrossoverLimits": "crossover",
    "loop_crossover": "crossover", "Effect": "effects", "get_effect": "effects",
    "PilotModel": "hess", "Simulator": "simulation", "gain_scale": "crossover", "model_from_name": "hess",
    "simulate": "simulation", "synthetic_run": "simulation", "table1": "hess", "PrecisionFit": "mcruer", "fit_precision": "mcruer",
    "precision_loop": "mcruer", "motion_block": "motion", "paper_motion_path": "motion",
    "with_motion_path": "motion", "remnant_gain": "remnant",
})
