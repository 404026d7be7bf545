"""Simulation: the driver (``simulate``), run monitors, post-processing and the ``Result``."""
from .driver import ALL_METHODS, FORMULATIONS, METHODS, simulate
from .result import Result

__all__ = ["simulate", "Result", "METHODS", "ALL_METHODS", "FORMULATIONS"]
