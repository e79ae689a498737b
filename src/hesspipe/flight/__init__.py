"""Stage one, ``flight``: a JSBSim transport trimmed to the landing approach, the paper's
side wind and the identification excitation; the model pilot flying it in closed loop.
"""

from ..core.lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "AircraftConfig": "aircraft", "known_aircraft": "aircraft", "load_aircraft": "aircraft",
    "FlightConfig": "approach", "FlightResult": "approach", "fly": "approach",
    "AircraftEffects": "closed_loop", "PilotFlight": "closed_loop", "fly_pilot": "closed_loop",
    "fly_pilot_record": "closed_loop", "Excitation": "wind", "SideWind": "wind",
})
