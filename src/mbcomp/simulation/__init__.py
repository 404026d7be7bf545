"""Simulation: the driver (``simulate``), run monitors, post-processing and the ``Result``.

:mod:`.setup` checks a request and resolves the system, :mod:`.driver` steps it
(:mod:`.stepping`: the run and its per-step hooks; :mod:`.monitors`: singular positions;
:mod:`.endings`: how a run that ends early says why), :mod:`.postprocess` computes the
result columns of :class:`~.result.Result`.
"""
from .driver import ALL_METHODS, FORMULATIONS, simulate
from .result import Result

__all__ = ["simulate", "Result", "METHODS", "ALL_METHODS", "FORMULATIONS"]


def __getattr__(name):
    """``METHODS`` (see :mod:`.driver`): built on first use, as it imports ``scipy.integrate``."""
    if name == "METHODS":
        from . import driver
        return driver.METHODS
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
