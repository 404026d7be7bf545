"""Analysis on top of the assembled system: steady states, linearization and stability
classification, parameter sweeps (:mod:`mbcomp.analysis.stability` is their facade, also
importable as ``mbcomp.stability``), work-precision studies
(:mod:`mbcomp.analysis.workprecision`), and studies of many runs on any executor
(:mod:`mbcomp.analysis.study`, :mod:`mbcomp.analysis.executors`)."""
from .stability import (Linearization, SteadyState, Sweep, classify, linearize, parse_steady, steady_states, sweep,
                        system_for, to_json)
from .study import Normal, StudyResult, Uniform, study

__all__ = ["SteadyState", "Linearization", "Sweep", "steady_states", "linearize", "classify", "sweep",
           "parse_steady", "system_for", "to_json", "study", "StudyResult", "Uniform", "Normal"]
