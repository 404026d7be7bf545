"""Analysis on top of the assembled system: steady states, linearization and stability
classification, parameter sweeps (:mod:`mbcomp.analysis.stability` is their facade, also
importable as ``mbcomp.stability``), and work-precision studies
(:mod:`mbcomp.analysis.workprecision`)."""
from .stability import (Linearization, SteadyState, Sweep, classify, linearize, parse_steady, steady_states, sweep,
                        system_for, to_json)

__all__ = ["SteadyState", "Linearization", "Sweep", "steady_states", "linearize", "classify", "sweep",
           "parse_steady", "system_for", "to_json"]
